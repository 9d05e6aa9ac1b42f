#include "narrowphase/batched_pairs.h"

#include <algorithm>
#include <tuple>

#include "narrowphase/box_box.h"
#include "narrowphase/convex_pairs.h"
#include "narrowphase/speculative_margin.h"
#include "simd/simd.h"
#include "simd/transpose.h"
#include "simd/vec.h"

namespace rubble::detail {
namespace {

using simd::FloatW;
using simd::Vec3W;

static_assert(kBatchBlock % simd::kLanes == 0, "blocks hold whole batches");

/// Per side: the shape's pose (origin and orientation; a sphere's centre) and size (half extents; a sphere's radius
/// in x).
enum InputLane : std::size_t { kPx, kPy, kPz, kQx, kQy, kQz, kQw, kSx, kSy, kSz, kSideLanes };
constexpr std::size_t kSideB = kSideLanes;
constexpr std::size_t kMarginLane = 2 * kSideLanes;
static_assert(kMarginLane + 1 == kBatchInputLanes, "the header sizes the lanes");

using InputLanes = float[kBatchInputLanes][kBatchBlock];

/// How each side of a batched kernel's pairs is laid out in the input lanes. Sphere: centre in the position lanes,
/// radius in size x. Box: origin, orientation, half extents. Capsule: centre, half axis (in the orientation lanes
/// x, y, z), radius in size x.
enum class SideForm : std::uint8_t { Sphere, Box, Capsule };

/// One side of SIMD-width pairs, as the batched kernels take it.
struct SideLanes {
    Vec3W<FloatW> position;  ///< shape origin (a sphere's or capsule's centre)
    simd::QuatW<FloatW> q;
    Vec3W<FloatW> size;  ///< as ShapeTables
    Motion<FloatW> motion;
};

/// How the pairs of a batch reach one side's data: all whole moving bodies and all whole static bodies are
/// gathered lane-wide; anything else (compound children, a mix) goes lane by lane.
enum class SideSource { Moving, Static, Mixed };

/// Side `sideB` of the pairs jobs[0 .. kLanes) (jobs of `chunk`), gathered into lanes. Whole moving bodies: the shape
/// origin from the centre of mass (com - R lc, as posed() computes it), except that a sphere is at its centre of
/// mass (as sphereCenter() has it).
RUBBLE_FLATTEN SideLanes gatherSide(const NarrowChunk& chunk, const std::uint32_t* jobs, bool sideB, SideForm form,
                                    const BatchSources& from) {
    using simd::IntW;
    alignas(64) std::int32_t body[simd::kLanes], shape[simd::kLanes];
    bool allMoving = true, allStatic = true, oneShape = true;
    const MovingBodies& m = from.storage.moving;
    const StaticBodies& st = from.storage.statics;
    const ShapeTables& tables = from.tables;
    for (std::size_t k = 0; k < simd::kLanes; ++k) {
        const ContactPair& p = chunk.jobs[jobs[k]].pair;
        const std::uint32_t i = sideB ? p.b : p.a;
        const bool isStatic = sideB ? p.bStatic : p.aStatic;
        const bool whole = (sideB ? p.childB : p.childA) == kNoChild;
        allMoving = allMoving && whole && !isStatic;
        allStatic = allStatic && whole && isStatic;
        body[k] = static_cast<std::int32_t>(i);
        shape[k] = static_cast<std::int32_t>(isStatic ? st.shape[i] : m.shape[i]);
        oneShape = oneShape && shape[k] == shape[0];
    }
    const SideSource source = allMoving ? SideSource::Moving : (allStatic ? SideSource::Static : SideSource::Mixed);
    SideLanes side;
    if (source != SideSource::Mixed) {
        const IntW index = simd::loadInt<IntW>(body), shapeIndex = simd::loadInt<IntW>(shape);
        // Per-shape values: one load when every lane has the same shape (a pile of one kind of box), else gathered.
        auto perShape = [&](const std::vector<float>& table) {
            return oneShape ? FloatW(table[static_cast<std::size_t>(shape[0])])
                            : simd::gather(table.data(), shapeIndex);
        };
        auto vec = [&](const AlignedVector<float>& x, const AlignedVector<float>& y, const AlignedVector<float>& z) {
            return Vec3W<FloatW>{simd::gather(x.data(), index), simd::gather(y.data(), index),
                                 simd::gather(z.data(), index)};
        };
        if (source == SideSource::Moving) {
            FloatW pose[simd::kRowFloats], motion[simd::kRowFloats];
            simd::loadRowsTransposed(from.rows.pose.data(), body, pose);
            simd::loadRowsTransposed(from.rows.motion.data(), body, motion);
            side.position = {pose[kComX], pose[kComY], pose[kComZ]};
            side.q = {pose[kRotX], pose[kRotY], pose[kRotZ], pose[kRotW]};
            if (form != SideForm::Sphere)
                side.position = side.position - simd::rotate(side.q, Vec3W<FloatW>{pose[kLocalComX], motion[kLocalComY],
                                                                                   motion[kLocalComZ]});
            side.motion = {{motion[kVelX], motion[kVelY], motion[kVelZ]},
                           {motion[kSpinX], motion[kSpinY], motion[kSpinZ]},
                           perShape(tables.reach)};
        } else {
            side.position = vec(st.px, st.py, st.pz);
            side.q = {simd::gather(st.qx.data(), index), simd::gather(st.qy.data(), index),
                      simd::gather(st.qz.data(), index), simd::gather(st.qw.data(), index)};
        }
        side.size = {perShape(tables.sizeX), perShape(tables.sizeY), perShape(tables.sizeZ)};
        return side;
    }
    // Lane by lane, through the same helpers as the one-pair kernels.
    alignas(64) float lanes[17][simd::kLanes];
    for (std::size_t k = 0; k < simd::kLanes; ++k) {
        const ContactPair& p = chunk.jobs[jobs[k]].pair;
        const Posed posed = posedSide(from.storage, from.rows, from.shapes, p, sideB);
        const Vec3 position = form == SideForm::Sphere ? sphereCenter(from.storage, from.rows, from.shapes, p, sideB)
                                                       : posed.pose.position;
        const Quat q = posed.pose.rotation;
        const Vec3 size = sizeOf(*posed.shape);
        const Motion<float> motion = motionOf(from.storage, from.rows, tables, p, sideB);
        const float values[17] = {position.x, position.y, position.z, q.x,        q.y,         q.z,
                                  q.w,        size.x,     size.y,     size.z,     motion.v.x,  motion.v.y,
                                  motion.v.z, motion.w.x, motion.w.y, motion.w.z, motion.reach};
        for (std::size_t f = 0; f < 17; ++f) lanes[f][k] = values[f];
    }
    auto load = [&](std::size_t f) { return simd::load<FloatW>(lanes[f]); };
    auto load3 = [&](std::size_t f) { return Vec3W<FloatW>{load(f), load(f + 1), load(f + 2)}; };
    side.position = load3(0);
    side.q = {load(3), load(4), load(5), load(6)};
    side.size = load3(7);
    side.motion = {load3(10), load3(13), load(16)};
    return side;
}

/// Pairs [k0, k0 + kLanes) of a block into its input lanes; `jobs` holds the block's jobs, `count` of them valid
/// (lanes past the end repeat the last job, so every gather reads a real body; their results are not used).
void gatherBatch(const NarrowChunk& chunk, const std::uint32_t* jobs, std::size_t count, std::size_t k0, SideForm formA,
                 SideForm formB, const BatchSources& from, InputLanes& in) {
    std::uint32_t batch[simd::kLanes];
    for (std::size_t k = 0; k < simd::kLanes; ++k) batch[k] = jobs[std::min(k0 + k, count - 1)];
    const SideLanes a = gatherSide(chunk, batch, false, formA, from);
    const SideLanes b = gatherSide(chunk, batch, true, formB, from);
    for (const auto& [side, form, base] : {std::tuple{&a, formA, std::size_t{0}}, std::tuple{&b, formB, kSideB}}) {
        side->position.store(in[base + kPx], in[base + kPy], in[base + kPz], k0);
        side->size.store(in[base + kSx], in[base + kSy], in[base + kSz], k0);
        if (form == SideForm::Capsule) {
            // The capsule's segment: centre -/+ this half axis (capsuleSegmentOf).
            const Vec3W<FloatW> axis = simd::rotate(side->q, Vec3W<FloatW>{FloatW(0.0f), side->size.y, FloatW(0.0f)});
            axis.store(in[base + kQx], in[base + kQy], in[base + kQz], k0);
        } else {
            side->q.store(in[base + kQx], in[base + kQy], in[base + kQz], in[base + kQw], k0);
        }
    }
    simd::store(in[kMarginLane] + k0, speculativeMargin<FloatW>(from.margin, from.dt, a.motion, b.motion));
}

// Each kernel over a block of n pairs in `in`: the closed-form kernels leave SoA results in `result`; box-box writes
// each job's manifold in place.
constexpr std::size_t b = kSideB;

void spheresBlock(const InputLanes& in, std::size_t n, float margin, const PairContacts& result, const std::uint32_t*,
                  Manifold*) {
    collideSpheresBatch(
        {in[kPx], in[kPy], in[kPz], in[kSx], in[b + kPx], in[b + kPy], in[b + kPz], in[b + kSx], in[kMarginLane]}, n,
        margin, result);
}

void sphereBoxesBlock(const InputLanes& in, std::size_t n, float margin, const PairContacts& result,
                      const std::uint32_t*, Manifold*) {
    collideSphereBoxesBatch(
        {in[kPx], in[kPy], in[kPz], in[kSx], in[b + kPx], in[b + kPy], in[b + kPz], in[b + kQx], in[b + kQy],
         in[b + kQz], in[b + kQw], in[b + kSx], in[b + kSy], in[b + kSz], in[kMarginLane]},
        n, margin, result);
}

void sphereCapsulesBlock(const InputLanes& in, std::size_t n, float margin, const PairContacts& result,
                         const std::uint32_t*, Manifold*) {
    collideSphereCapsulesBatch({in[kPx], in[kPy], in[kPz], in[kSx], in[b + kPx], in[b + kPy], in[b + kPz], in[b + kQx],
                                in[b + kQy], in[b + kQz], in[b + kSx], in[kMarginLane]},
                               n, margin, result);
}

void capsulesBlock(const InputLanes& in, std::size_t n, float margin, const PairContacts& result, const std::uint32_t*,
                   Manifold*) {
    collideCapsulesBatch({in[kPx], in[kPy], in[kPz], in[kQx], in[kQy], in[kQz], in[kSx], in[b + kPx], in[b + kPy],
                          in[b + kPz], in[b + kQx], in[b + kQy], in[b + kQz], in[b + kSx], in[kMarginLane]},
                         n, margin, result);
}

void boxesBlock(const InputLanes& in, std::size_t n, float, const PairContacts&, const std::uint32_t* jobs,
                Manifold* manifolds) {
    collideBoxesBatch({in[kPx],     in[kPy],     in[kPz],     in[kQx],     in[kQy],     in[kQz],     in[kQw],
                       in[kSx],     in[kSy],     in[kSz],     in[b + kPx], in[b + kPy], in[b + kPz], in[b + kQx],
                       in[b + kQy], in[b + kQz], in[b + kQw], in[b + kSx], in[b + kSy], in[b + kSz], in[kMarginLane]},
                      n, manifolds, jobs, /*padded=*/true);
}

/// A batched kernel: how its two sides are laid out, the kernel over a block, and whether it writes the jobs'
/// manifolds itself.
struct BatchedRow {
    BatchedKernel kernel;
    SideForm a, b;
    void (*block)(const InputLanes& in, std::size_t n, float margin, const PairContacts& result,
                  const std::uint32_t* jobs, Manifold* manifolds);
    bool writesManifolds;
};

/// One row per BatchedKernel, in its order.
constexpr BatchedRow kBatchedRows[static_cast<int>(BatchedKernel::Count)] = {
    {BatchedKernel::SphereSphere, SideForm::Sphere, SideForm::Sphere, spheresBlock, false},
    {BatchedKernel::SphereBox, SideForm::Sphere, SideForm::Box, sphereBoxesBlock, false},
    {BatchedKernel::SphereCapsule, SideForm::Sphere, SideForm::Capsule, sphereCapsulesBlock, false},
    {BatchedKernel::CapsuleCapsule, SideForm::Capsule, SideForm::Capsule, capsulesBlock, false},
    {BatchedKernel::BoxBox, SideForm::Box, SideForm::Box, boxesBlock, true},
};
constexpr bool rowsInOrder() {
    for (int k = 0; k < static_cast<int>(BatchedKernel::Count); ++k)
        if (static_cast<int>(kBatchedRows[k].kernel) != k) return false;
    return true;
}
static_assert(rowsInOrder(), "kBatchedRows[k] is kernel k's row");

}  // namespace

void collideBatched(BatchedKernel kernel, NarrowChunk& chunk, BatchScratch& s, const BatchSources& sources) {
    const BatchedRow& row = kBatchedRows[static_cast<int>(kernel)];
    const std::vector<std::uint32_t>& list = s.jobs[static_cast<int>(kernel)];
    const PairContacts result{s.out[0],     s.out[1], s.out[2], s.out[3], s.out[4], s.out[5],  s.out[6],
                              s.feature[0], s.count,  s.out[7], s.out[8], s.out[9], s.out[10], s.feature[1]};
    for (std::size_t first = 0; first < list.size(); first += kBatchBlock) {
        const std::uint32_t* jobs = list.data() + first;
        const std::size_t n = std::min(kBatchBlock, list.size() - first);
        for (std::size_t k0 = 0; k0 < n; k0 += simd::kLanes)
            gatherBatch(chunk, jobs, n, k0, row.a, row.b, sources, s.in);
        row.block(s.in, n, sources.margin, result, jobs, chunk.manifolds.data());
        if (row.writesManifolds) continue;
        for (std::size_t k = 0; k < n; ++k) {
            Manifold& m = chunk.manifolds[jobs[k]];
            m.pointCount = s.count[k];
            m.normal = {s.out[0][k], s.out[1][k], s.out[2][k]};
            m.points[0] = {{s.out[3][k], s.out[4][k], s.out[5][k]}, s.out[6][k], s.feature[0][k]};
            if (m.pointCount > 1)
                m.points[1] = {{s.out[7][k], s.out[8][k], s.out[9][k]}, s.out[10][k], s.feature[1][k]};
        }
    }
}

}  // namespace rubble::detail
