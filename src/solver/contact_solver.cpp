#include "solver/contact_solver.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>

#include "core/parallel.h"
#include "islands/islands.h"

namespace rubble::detail {
namespace {

constexpr std::size_t kBodyChunk = 1024;
constexpr std::size_t kManifoldChunk = 1024;
/// Batches per task inside a colour: small enough that two threads share a colour of a few thousand manifolds,
/// large enough that a task outweighs its dispatch.
constexpr std::size_t kBatchChunk = 8;
/// Below this many batches a solve runs on the calling thread alone: it costs less than waking a second worker and
/// meeting it at every phase, and a worker that the machine deschedules while it holds a unit would hold up the
/// step for milliseconds (seen on these shared two-core machines: a 0.08 ms step of 100 spheres took 2.5-4.6 ms).
constexpr std::size_t kBatchesForTwoWorkers = 16;
/// Shock propagation: passes over each level's contacts.
constexpr int kShockPasses = 4;

using Softness = ContactSoftness;

/// A spring-damper contact solved implicitly over the substep h (the soft step's contact): the bias rate,
/// and how much of the rigid response and of the accumulated impulse each iteration uses.
simd::Vec3W<float> toWide(Vec3 v) { return {v.x, v.y, v.z}; }

Softness soft(float hertz, float dampingRatio, float h) {
    const float omega = 2.0f * 3.14159265358979f * hertz;
    const float a1 = 2.0f * dampingRatio + h * omega;
    const float a2 = h * omega * a1;
    const float a3 = 1.0f / (1.0f + a2);
    return {omega / a1, a2 * a3, a3};
}

/// The largest change of a body's world inverse inertia over a step that the solver accepts from freezing it at the
/// step's start, relative to its largest principal value: a 14 degree turn of a very uneven body (a rod at 15 rad/s at
/// 60 Hz), 24 degrees of a box twice as long as it is wide. At 0.785 a rod that a first hit had slowed to 36 rad/s
/// still tumbled out of its plane at the second.
constexpr float kMostInertiaDrift = 0.25f;

/// A dynamic body's masses for the step's solve. The world inverse inertia is the one at the step's start, and it
/// stays right while the body turns little; a body whose principal axes turn far within the step (a rod spinning end
/// over end) would meet its contacts with the inertia of an orientation it has left, and an impulse that was cheap to
/// turn it by then (about the rod's long axis, say) spins it up about what is now a heavy axis: a rod hitting a wall
/// at 75 rad/s gained 70% of its energy and tumbled out of its plane. For such a body the solve uses the smallest
/// principal inverse moment about every axis, which is no more than its world inverse inertia in any orientation it can
/// take, so no impulse turns it faster than it would turn. The drift rate is that of R diag(d) R^T as the body turns
/// at w: in the body's frame the commutator of w's cross-product matrix with diag(d), with entries w_k (d_i - d_j).
MassRow massRow(const MovingBodies& m, std::uint32_t d, bool rotation, float stepTime) {
    MassRow row{};
    if (!isDynamicBody(m, d)) return row;
    row.inverseMass = m.invMass[d];
    if (!rotation) return row;
    row.inverseInertia[0] = m.iwXX[d], row.inverseInertia[1] = m.iwYY[d], row.inverseInertia[2] = m.iwZZ[d];
    row.inverseInertia[3] = m.iwXY[d], row.inverseInertia[4] = m.iwXZ[d], row.inverseInertia[5] = m.iwYZ[d];
    const float dx = m.invIx[d], dy = m.invIy[d], dz = m.invIz[d];
    const float least = std::min({dx, dy, dz}), most = std::max({dx, dy, dz});
    if (!(least > 0) || least == most) return row;  // a locked axis, or an inertia no turn changes
    const Quat q{m.qx[d], m.qy[d], m.qz[d], m.qw[d]};
    const Vec3 w = rotate(conjugate(q), Vec3{m.wx[d], m.wy[d], m.wz[d]});
    const float rate = std::sqrt(w.x * w.x * (dy - dz) * (dy - dz) + w.y * w.y * (dx - dz) * (dx - dz) +
                                 w.z * w.z * (dx - dy) * (dx - dy));
    if (rate * stepTime > kMostInertiaDrift * most)
        for (int k = 0; k < 6; ++k) row.inverseInertia[k] = k < 3 ? least : 0.0f;
    return row;
}

/// Sizes `v` for n rows whose old content is not kept: every row is built again each step. Growing past its
/// capacity drops the old rows before allocating, instead of copying them into storage twice their size (a pile of
/// 2 million contacts held 1.7 GB of batches for 0.6 GB of rows).
template <class T>
void resizeDiscarding(std::vector<T>& v, std::size_t n) {
    if (n > v.capacity()) {
        v = std::vector<T>();
        v.reserve(n + n / 8);  // room for a step or two of growth
    }
    v.resize(n);
}

/// Fetches a manifold, its pair and its carried impulses into the cache ahead of use. Always inlined: GCC judges a
/// function that only prefetches free of effects and deletes calls to it.
[[gnu::always_inline]] inline void prefetchManifold(const Contacts& contacts, const std::vector<PointImpulse>& warm,
                                                    bool warmStarting, std::uint32_t k) {
    const char* manifold = reinterpret_cast<const char*>(&contacts.manifolds[k]);
    __builtin_prefetch(manifold);
    __builtin_prefetch(manifold + sizeof(Manifold) - 1);
    __builtin_prefetch(&contacts.pairs[k]);
    if (warmStarting) {
        __builtin_prefetch(&warm[k * kMaxManifoldPoints]);
        __builtin_prefetch(&warm[k * kMaxManifoldPoints + kMaxManifoldPoints - 1]);
    }
}

/// What building a batch's lanes gathers besides the batch itself: which lanes and points are used, and the bodies'
/// velocities and gravity along the normal (for the approach speeds restitution needs).
struct BatchInputs {
    using Lanes = ContactBatch::Lanes;
    alignas(64) Lanes used = {};
    alignas(64) Lanes point[kMaxManifoldPoints] = {};
    alignas(64) Lanes vAx = {}, vAy = {}, vAz = {}, wAx = {}, wAy = {}, wAz = {};
    alignas(64) Lanes vBx = {}, vBy = {}, vBz = {}, wBx = {}, wBy = {}, wBz = {};
    alignas(64) Lanes normalGravity = {};  ///< B's gravity less A's along the normal, m/s^2
};

/// The lane-parallel part of building a batch, in SIMD over its manifolds: friction directions, effective masses
/// and approach speeds.
void finishBatch(ContactBatch& b, ContactBatchExtras* extras, const BatchInputs& in, const MassRow* mass,
                 bool friction) {
    using F = simd::FloatW;
    using contact_kernels::at;
    using contact_kernels::at3;
    using contact_kernels::put;
    const auto used = at<F>(in.used, 0) > F(0.0f);
    const F zero(0.0f), one(1.0f);
    // Empty lanes have no normal: give them one so that nothing divides by zero, and zero what it yields.
    const simd::Vec3W<F> n = simd::select<F>(used, at3<F>(b.nx, b.ny, b.nz, 0), {zero, one, zero});
    // Friction directions from the normal: the helper axis follows the normal's largest component, so the basis is
    // continuous for every normal near a coordinate axis (ground, walls, stacked boxes) and the carried friction
    // impulses keep their meaning from step to step.
    const F ax = simd::abs(n.x), ay = simd::abs(n.y), az = simd::abs(n.z);
    const auto yLargest = simd::andMask(ay >= ax, ay >= az), xLargest = ax >= az;
    const simd::Vec3W<F> helper{simd::select(yLargest, one, zero),
                                simd::select(yLargest, zero, simd::select(xLargest, zero, one)),
                                simd::select(yLargest, zero, simd::select(xLargest, one, zero))};
    simd::Vec3W<F> t1 = simd::cross(helper, n);
    t1 = t1 * (F(1.0f) / simd::length(t1));
    const simd::Vec3W<F> t2 = simd::cross(n, t1);
    const simd::Vec3W<F> none{zero, zero, zero};
    const simd::Vec3W<F> t1Used = simd::select<F>(used, t1, none), t2Used = simd::select<F>(used, t2, none);
    put(b.t1x, 0, t1Used.x), put(b.t1y, 0, t1Used.y), put(b.t1z, 0, t1Used.z);
    put(b.t2x, 0, t2Used.x), put(b.t2y, 0, t2Used.y), put(b.t2z, 0, t2Used.z);

    const contact_kernels::MassW<F> massA = contact_kernels::loadMasses<F>(mass, b.bodyA);
    const contact_kernels::MassW<F> massB = contact_kernels::loadMasses<F>(mass, b.bodyB);
    const F mA = massA.inverseMass, mB = massB.inverseMass;
    const simd::SymMat3W<F>&iA = massA.inverseInertia, &iB = massB.inverseInertia;
    const simd::Vec3W<F> vA = at3<F>(in.vAx, in.vAy, in.vAz, 0), wA = at3<F>(in.wAx, in.wAy, in.wAz, 0);
    const simd::Vec3W<F> vB = at3<F>(in.vBx, in.vBy, in.vBz, 0), wB = at3<F>(in.wBx, in.wBy, in.wBz, 0);
    if (extras) put(extras->normalGravity, 0, simd::select(used, at<F>(in.normalGravity, 0), zero));
    for (int i = 0; i < b.pointCount; ++i) {
        const auto present = at<F>(in.point[i], 0) > zero;
        if (!simd::any(present)) continue;
        ContactBatch::Point& pt = b.points[i];
        const simd::Vec3W<F> rA = at3<F>(pt.rAx, pt.rAy, pt.rAz, 0), rB = at3<F>(pt.rBx, pt.rBy, pt.rBz, 0);
        const auto effective = [&](const simd::Vec3W<F>& dir) {
            const simd::Vec3W<F> ra = simd::cross(rA, dir), rb = simd::cross(rB, dir);
            const F sum = mA + mB + simd::dot(ra, iA * ra) + simd::dot(rb, iB * rb);
            return simd::select(simd::andMask(present, sum > zero), F(1.0f) / sum, zero);
        };
        put(pt.normalMass, 0, effective(n));
        if (friction) {
            put(pt.tangentMass1, 0, effective(t1));
            put(pt.tangentMass2, 0, effective(t2));
        }
        if (extras) {
            const simd::Vec3W<F> dv = (vB + simd::cross(wB, rB)) - (vA + simd::cross(wA, rA));
            ContactBatchExtras::Point& extra = extras->points[i];
            put(extra.relativeVelocity, 0, simd::select(present, simd::dot(dv, n), zero));
            put(extra.maxNormalImpulse, 0, zero);
            put(extra.pseudoImpulse, 0, zero);
        }
    }
}

}  // namespace

void ContactSolver::prepare(const Contacts& contacts, const std::vector<PointImpulse>& warm, const BodyStorage& storage,
                            const WorldSettings& settings, EffectSet effects, float h, TaskPool& pool,
                            const JointCoupling* joints, const Islands* islands) {
    settings_ = settings.solver;
    h_ = h;
    friction_ = effects.has(Effect::Friction);
    frictionInRelaxOnly_ =
        settings_.positionCorrection == PositionCorrection::SoftStep && settings.positionIterations > 0;
    rotation_ = effects.has(Effect::Rotation);
    const bool bounce = effects.has(Effect::Restitution);
    scratchRows_ = std::max(1, pool.threadCount());
    const MovingBodies& m = storage.moving;
    const StaticBodies& s = storage.statics;
    const std::size_t manifoldCount = contacts.manifolds.size();

    // What partitioning and colouring read of each manifold, one byte each (see traits_).
    traits_.resize(manifoldCount);
    const std::size_t traitChunks = TaskPool::chunkCount(manifoldCount, kManifoldChunk);
    chunkHeld_.assign(traitChunks, 0);
    const bool jointFilter = joints && !joints->noContactPairs.empty();
    const auto jointed = [&](const ContactPair& p) {
        const std::uint32_t slotA = p.aStatic ? s.slot[p.a] : m.slot[p.a];
        const std::uint32_t slotB = p.bStatic ? s.slot[p.b] : m.slot[p.b];
        return std::binary_search(joints->noContactPairs.begin(), joints->noContactPairs.end(),
                                  jointedPairKey(slotA, slotB));
    };
    pool.forChunks(manifoldCount, kManifoldChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        bool held = false;
        for (std::size_t k = begin; k < end; ++k) {
            const ContactPair& p = contacts.pairs[k];
            const bool movingA = !p.aStatic, movingB = !p.bStatic;
            const bool dynamicA = movingA && isDynamicBody(m, p.a), dynamicB = movingB && isDynamicBody(m, p.b);
            const bool leftOut = (!dynamicA && !dynamicB) || (jointFilter && jointed(p));
            const bool heldA = movingA && !dynamicA, heldB = movingB && !dynamicB;
            traits_[k] = static_cast<std::uint8_t>(contacts.manifolds[k].pointCount | (dynamicA ? kTraitDynamicA : 0) |
                                                   (dynamicB ? kTraitDynamicB : 0) | (heldA ? kTraitHeldA : 0) |
                                                   (heldB ? kTraitHeldB : 0) | (leftOut ? kTraitLeftOut : 0));
            held = held || (!leftOut && (heldA || heldB));
        }
        chunkHeld_[c] = held;
    });
    const bool anyHeld = std::find(chunkHeld_.begin(), chunkHeld_.end(), 1) != chunkHeld_.end();

    // Segments, body rows, then greedy colouring in each segment's manifold order (the segments in parallel) and the
    // colours' lanes: dependent only on the manifolds' canonical order, the islands and the bodies' places.
    partition(contacts, islands, m);
    assignRows(contacts, islands, m, anyHeld);
    colourSegments(contacts, m, pool);
    const std::uint32_t batchCount = layOutColours();
    laneOfManifold_.assign(manifoldCount, ~0u);
    fillLanes(pool);
    // Islands in a block that kept no constraint are solved with the large islands (their joints, say).
    for (std::uint32_t& segment : segmentOfIsland_)
        segment = segment == kLargeSegment || blockOfSegment_[segment] == kLargeSegment
                      ? static_cast<std::uint32_t>(blocks_.size())
                      : blockOfSegment_[segment];
    // Jointed bodies after the contacts' own, in the joints' order.
    if (joints)
        for (std::uint32_t dense : joints->bodies)
            if (dense != kNoCoupledBody) touchRow(dense);
    const std::uint32_t bodyCount = static_cast<std::uint32_t>(bodies_.moving.size());
    bodies_.count = bodyCount;
    stats_.batches = batchCount;
    stats_.blocks = static_cast<std::uint32_t>(blocks_.size());
    stats_.laneOccupancy =
        batchCount ? static_cast<float>(stats_.constraints) / static_cast<float>(batchCount * kBatchLanes) : 0;
    // For the next step's choice of slabs: the large islands' batches over their colours, as if uncut (the slabs'
    // batches together over the most colours either needed).
    std::uint32_t largeBatches = 0, largeColors = 0;
    const auto countLarge = [&](const ColorSpan& span) {
        largeColors = std::max(largeColors, span.colorCount);
        for (std::uint32_t c = span.firstColor; c < span.firstColor + span.colorCount; ++c)
            largeBatches += colors_[c].batchCount;
    };
    if (slabs_.empty()) countLarge(large_);
    for (const ColorSpan& span : slabs_) countLarge(span);
    largeBatchesPerColor_ =
        largeColors > 0 ? static_cast<float>(largeBatches) / static_cast<float>(largeColors) : INFINITY;
    // Body rows: the touched bodies, the still row, one scratch row per worker.
    const std::size_t rows = bodyCount + 1 + static_cast<std::size_t>(scratchRows_);
    // Every row starts at rest, and a body that is not dynamic keeps a zero mass row (it cannot be moved); the
    // touched bodies' rows are cleared in the parallel loop, the still and scratch rows here.
    for (auto* a : {&bodies_.velocity, &bodies_.motion, &bodies_.pseudo}) {
        a->resize(rows);
        std::fill(a->begin() + bodyCount, a->end(), BodyRow{});
    }
    bodies_.mass.resize(rows);
    std::fill(bodies_.mass.begin() + bodyCount, bodies_.mass.end(), MassRow{});
    for (auto* a : {&p0x_, &p0y_, &p0z_, &q0x_, &q0y_, &q0z_, &q0w_}) a->resize(bodyCount);
    const float stepTime = h * static_cast<float>(settings.substeps);
    pool.forChunks(bodyCount, kBodyChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) {
            const std::uint32_t d = bodies_.moving[i];
            p0x_[i] = m.px[d], p0y_[i] = m.py[d], p0z_[i] = m.pz[d];
            q0x_[i] = m.qx[d], q0y_[i] = m.qy[d], q0z_[i] = m.qz[d], q0w_[i] = m.qw[d];
            bodies_.velocity[i] = bodies_.motion[i] = bodies_.pseudo[i] = BodyRow{};
            bodies_.mass[i] = massRow(m, d, rotation_, stepTime);
        }
    });

    // Constraint rows. A block's rows are built in the block's own task, just before its warm start reads them while
    // they are still in the core's cache (see forEachColor); the large islands' rows are built here, in parallel.
    // Nothing the rows read changes between here and the first solve. Shock propagation reads every row here.
    resizeDiscarding(batches_, batchCount);
    resizeDiscarding(extras_,
                     bounce || settings_.positionCorrection == PositionCorrection::SplitImpulse ? batchCount : 0);
    const float invH = 1.0f / h;
    const float hertz = std::min(settings_.contactHertz, 0.25f * invH);
    const bool softStep = settings_.positionCorrection == PositionCorrection::SoftStep;
    build_ = {&contacts, &warm, &storage, soft(hertz, settings_.contactDampingRatio, h),
              soft(2.0f * hertz, settings_.contactDampingRatio, h), Softness{settings_.baumgarte * invH, 1.0f, 0.0f},
              softStep,
              // Soft contacts are damped springs from the first millimetre: a dead zone would only add to the sag
              // of stacks.
              softStep ? 0.0f : settings_.linearSlop, settings_.warmStarting, bounce,
              effects.has(Effect::Gravity) ? settings.gravity : Vec3{}};
    pool_ = &pool;
    blocksPending_ = !blocks_.empty();
    const ColorSpan whole =
        slabs_.empty()
            ? large_
            : ColorSpan{slabs_.front().firstColor, large_.firstColor + large_.colorCount - slabs_.front().firstColor};
    if (whole.colorCount > 0) {
        const std::uint32_t first = colors_[whole.firstColor].firstBatch;
        const ColorRange& lastRange = colors_[whole.firstColor + whole.colorCount - 1];
        pool.forChunks(lastRange.firstBatch + lastRange.batchCount - first, kManifoldChunk / kBatchLanes,
                       [&](std::size_t, std::size_t begin, std::size_t end, int) {
                           buildBatches(first + static_cast<std::uint32_t>(begin),
                                        first + static_cast<std::uint32_t>(end));
                       });
    }
    shockOrder_.clear();
    if (settings_.shockPropagation) {
        buildPendingBlocks();
        orderForShock();
    }
}

void ContactSolver::buildBlock(std::size_t block) {
    const ColorSpan span = blocks_[block];
    const ColorRange& lastRange = colors_[span.firstColor + span.colorCount - 1];
    buildBatches(colors_[span.firstColor].firstBatch, lastRange.firstBatch + lastRange.batchCount);
}

void ContactSolver::buildPendingBlocks() {
    if (!blocksPending_) return;
    pool_->forChunks(blocks_.size(), 1, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t block = begin; block < end; ++block) buildBlock(block);
    });
    blocksPending_ = false;
}

void ContactSolver::buildBatches(std::uint32_t begin, std::uint32_t end) {
    const Contacts& contacts = *build_.contacts;
    const std::vector<PointImpulse>& warm = *build_.warm;
    const MovingBodies& m = build_.storage->moving;
    const StaticBodies& s = build_.storage->statics;
    const std::int32_t stillRow = static_cast<std::int32_t>(bodies_.count);
    const bool warmStarting = build_.warmStarting, bounce = build_.bounce, softStep = build_.softStep;
    const Softness &dynamicSoft = build_.dynamicSoft, &staticSoft = build_.staticSoft, &stiff = build_.stiff;
    const float slop = build_.slop;
    const auto isDynamic = [&](std::uint32_t dense) { return isDynamicBody(m, dense); };
    // A colour's manifolds lie far apart in manifold order, so no hardware prefetcher follows the lanes: the
    // manifold, pair and carried impulses of the lane kPrefetchLanes ahead are fetched while this one is built
    // (a few lanes at a time: a whole batch's worth of prefetches would overrun the core's miss buffers).
    constexpr std::size_t kPrefetchLanes = 4;
    const auto prefetchLane = [&](std::size_t at) __attribute__((always_inline)) {
        if (at >= manifoldOfLane_.size()) return;
        const std::uint32_t k = manifoldOfLane_[at];
        if (k != ~0u) prefetchManifold(contacts, warm, warmStarting, k);
    };
    for (std::size_t lane = 0; lane < kPrefetchLanes; ++lane) prefetchLane(begin * kBatchLanes + lane);
    for (std::size_t bi = begin; bi < end; ++bi) {
        ContactBatch& b = batches_[bi];
        ContactBatchExtras* extras = extrasOf(b);
        if (extras) std::memset(static_cast<void*>(extras->restitution), 0, sizeof extras->restitution);
        b.pointCount = batchPoints_[bi];
        std::memset(static_cast<void*>(&b), 0, offsetof(ContactBatch, pointCount));
        std::memset(static_cast<void*>(&b.nx), 0,
                    offsetof(ContactBatch, points) - offsetof(ContactBatch, nx) +
                        sizeof(ContactBatch::Point) * static_cast<std::size_t>(b.pointCount));
        BatchInputs lanes;
        for (std::size_t lane = 0; lane < kBatchLanes; ++lane) {
            b.bodyA[lane] = b.bodyB[lane] = stillRow;
            prefetchLane(bi * kBatchLanes + lane + kPrefetchLanes);
            const std::uint32_t k = manifoldOfLane_[bi * kBatchLanes + lane];
            if (k == ~0u) continue;
            const ContactPair& pair = contacts.pairs[k];
            const Manifold& mf = contacts.manifolds[k];
            // Side data: position, velocities and material (the masses are in the mass rows).
            struct Side {
                Vec3 p, v, w;
                float friction = 0, restitution = 0, gravityScale = 0;
                std::int32_t row = 0;
                bool dynamic = false;
            };
            const auto side = [&](std::uint32_t dense, bool isStatic) {
                Side sd;
                if (isStatic) {
                    sd.p = {s.px[dense], s.py[dense], s.pz[dense]};
                    sd.friction = s.friction[dense];
                    sd.restitution = s.restitution[dense];
                    sd.row = stillRow;
                    return sd;
                }
                sd.p = {m.px[dense], m.py[dense], m.pz[dense]};
                sd.v = {m.vx[dense], m.vy[dense], m.vz[dense]};
                sd.w = {m.wx[dense], m.wy[dense], m.wz[dense]};
                sd.friction = m.friction[dense];
                sd.restitution = m.restitution[dense];
                sd.row = solverIndex_[dense];
                sd.dynamic = isDynamic(dense);
                sd.gravityScale = sd.dynamic ? m.gravityScale[dense] : 0.0f;
                return sd;
            };
            const Side A = side(pair.a, pair.aStatic), B = side(pair.b, pair.bStatic);
            b.bodyA[lane] = A.row;
            b.bodyB[lane] = B.row;
            const Vec3 n = mf.normal;
            b.nx[lane] = n.x, b.ny[lane] = n.y, b.nz[lane] = n.z;
            // Geometric mean for friction (a frictionless surface is frictionless against anything), the
            // larger restitution (a ball bounces off a floor that does not).
            b.friction[lane] = friction_ ? std::sqrt(A.friction * B.friction) : 0.0f;
            if (extras) extras->restitution[lane] = bounce ? std::max(A.restitution, B.restitution) : 0.0f;
            const Softness sn = !softStep ? stiff : (A.dynamic && B.dynamic ? dynamicSoft : staticSoft);
            b.biasRate[lane] = sn.biasRate;
            b.massScale[lane] = sn.massScale;
            b.impulseScale[lane] = sn.impulseScale;
            b.slop[lane] = slop;
            lanes.used[lane] = 1.0f;
            lanes.vAx[lane] = A.v.x, lanes.vAy[lane] = A.v.y, lanes.vAz[lane] = A.v.z;
            lanes.wAx[lane] = A.w.x, lanes.wAy[lane] = A.w.y, lanes.wAz[lane] = A.w.z;
            lanes.vBx[lane] = B.v.x, lanes.vBy[lane] = B.v.y, lanes.vBz[lane] = B.v.z;
            lanes.wBx[lane] = B.w.x, lanes.wBy[lane] = B.w.y, lanes.wBz[lane] = B.w.z;
            lanes.normalGravity[lane] = dot(build_.gravity, n) * (B.gravityScale - A.gravityScale);
            for (int i = 0; i < mf.pointCount; ++i) {
                const ContactPoint& cp = mf.points[i];
                ContactBatch::Point& pt = b.points[i];
                // B's anchor is the point; A's is the same world point but in a recycled manifold.
                const Vec3 rA = cp.position + mf.shiftA - A.p, rB = cp.position - B.p;
                pt.rAx[lane] = rA.x, pt.rAy[lane] = rA.y, pt.rAz[lane] = rA.z;
                pt.rBx[lane] = rB.x, pt.rBy[lane] = rB.y, pt.rBz[lane] = rB.z;
                pt.separation[lane] = -cp.depth;
                lanes.point[i][lane] = 1.0f;
                if (warmStarting) {
                    const PointImpulse& carried = warm[k * kMaxManifoldPoints + i];
                    pt.normalImpulse[lane] = carried.normal;
                    pt.tangentImpulse1[lane] = friction_ ? carried.tangent1 : 0.0f;
                    pt.tangentImpulse2[lane] = friction_ ? carried.tangent2 : 0.0f;
                }
            }
        }
        finishBatch(b, extras, lanes, bodies_.mass.data(), friction_);
    }
}

void ContactSolver::loadBodies(const MovingBodies& m, TaskPool& pool) {
    SolverBodies& b = bodies_;
    std::vector<std::uint8_t>& movedInChunk = movedInChunk_;
    movedInChunk.assign(TaskPool::chunkCount(b.count, kBodyChunk), 0);
    pool.forChunks(b.count, kBodyChunk, [&](std::size_t chunk, std::size_t begin, std::size_t end, int) {
        bool moved = false;
        for (std::size_t i = begin; i < end; ++i) {
            const std::uint32_t d = b.moving[i];
            b.velocity[i] = {{m.vx[d], m.vy[d], m.vz[d]}, {m.wx[d], m.wy[d], m.wz[d]}};
            const Vec3 dp{m.px[d] - p0x_[i], m.py[d] - p0y_[i], m.pz[d] - p0z_[i]};
            // q q0^-1 = (vector u, scalar c); the small rotation is 2u, on the short side of the double cover.
            const Quat q{m.qx[d], m.qy[d], m.qz[d], m.qw[d]};
            const Quat delta = q * conjugate(Quat{q0x_[i], q0y_[i], q0z_[i], q0w_[i]});
            const float sign = delta.w < 0 ? -2.0f : 2.0f;
            const Vec3 da{sign * delta.x, sign * delta.y, sign * delta.z};
            b.motion[i] = {dp, da};
            moved |= dp.x != 0 || dp.y != 0 || dp.z != 0 || da.x != 0 || da.y != 0 || da.z != 0;
        }
        movedInChunk[chunk] = moved;
    });
    moved_ = std::find(movedInChunk.begin(), movedInChunk.end(), 1) != movedInChunk.end();
}

void ContactSolver::storeVelocities(MovingBodies& m, TaskPool& pool) const {
    const SolverBodies& b = bodies_;
    pool.forChunks(b.count, kBodyChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) {
            const std::uint32_t d = b.moving[i];
            if ((m.flags[d] & (kFlagKinematic | kFlagFrozen | kFlagAsleep)) != 0) continue;
            const BodyRow& r = b.velocity[i];
            m.vx[d] = r.linear.x, m.vy[d] = r.linear.y, m.vz[d] = r.linear.z;
            m.wx[d] = r.angular.x, m.wy[d] = r.angular.y, m.wz[d] = r.angular.z;
        }
    });
}

BodyRows ContactSolver::rowsFor(int worker) {
    SolverBodies& b = bodies_;
    return BodyRows{b.velocity.data(), b.motion.data(), b.pseudo.data(), b.mass.data(),
                    static_cast<std::int32_t>(b.count + 1 + static_cast<std::uint32_t>(worker))};
}

template <class Kernel>
void ContactSolver::solveRange(const ColorRange& range, const BodyRows& rows, Kernel& kernel, int pass) {
    if (range.overflow) {
        // One lane at a time: these manifolds share bodies.
        for (std::size_t i = 0; i < range.batchCount; ++i)
            for (std::size_t lane = 0; lane < kBatchLanes; ++lane)
                kernel.template operator()<float>(batches_[range.firstBatch + i], lane, rows, pass);
        return;
    }
    for (std::size_t i = 0; i < range.batchCount; ++i)
        kernel.template operator()<simd::FloatW>(batches_[range.firstBatch + i], 0, rows, pass);
}

template <class Kernel>
void ContactSolver::forEachColorInOneRegion(TaskPool& pool, Kernel& kernel, int passes, int firstIteration) {
    // The phases, in the order forEachColor runs them (the large islands' passes after the blocks; here the two
    // overlap, since they share no body: a worker done with the blocks goes on to the large islands).
    phaseWork_.clear();
    phaseWork_.push_back({});
    for (int pass = 0; pass < passes; ++pass) {
        const bool before = crossingFirst(pass, firstIteration);
        const auto colours = [&] {
            for (std::uint32_t c = 0; c < large_.colorCount; ++c) phaseWork_.push_back({large_.firstColor + c, pass});
        };
        if (before) colours();
        if (!slabs_.empty()) phaseWork_.push_back({kSlabsPhase, pass});
        if (!before) colours();
    }
    const int workers = batches_.size() < kBatchesForTwoWorkers ? 1 : pool.threadCount();
    phases_.reset(phaseWork_.size(), workers);
    // The blocks in shares of about equal batch counts (a block's batches follow the previous block's).
    blockShareStart_.assign(static_cast<std::size_t>(workers) + 1, static_cast<std::uint32_t>(blocks_.size()));
    blockShareStart_[0] = 0;
    if (!blocks_.empty()) {
        const auto firstBatchOf = [&](std::size_t bl) { return colors_[blocks_[bl].firstColor].firstBatch; };
        const ColorSpan& last = blocks_.back();
        const ColorRange& lastRange = colors_[last.firstColor + last.colorCount - 1];
        const std::size_t first = firstBatchOf(0), total = lastRange.firstBatch + lastRange.batchCount - first;
        std::uint32_t bl = 0;
        for (int w = 1; w < workers; ++w) {
            const std::size_t target = first + total * static_cast<std::size_t>(w) / static_cast<std::size_t>(workers);
            while (bl < blocks_.size() && firstBatchOf(bl) < target) ++bl;
            blockShareStart_[static_cast<std::size_t>(w)] = bl;
        }
    }
    phases_.setShares(0, blockShareStart_.data());
    for (std::size_t p = 1; p < phaseWork_.size(); ++p) {
        const PhaseWork& w = phaseWork_[p];
        const std::size_t units = w.color == kSlabsPhase ? slabs_.size()
                                  : colors_[w.color].overflow
                                      ? 1
                                      : TaskPool::chunkCount(colors_[w.color].batchCount, kBatchChunk);
        phases_.setEven(p, static_cast<std::uint32_t>(units));
    }
    const bool buildBlocks = blocksPending_;
    const auto region = [&](int worker) {
        const BodyRows rows = rowsFor(worker);
        phases_.run(0, worker, [&](std::uint32_t bl) {
            if (buildBlocks) buildBlock(bl);
            for (int pass = 0; pass < passes; ++pass) solveSpan(blocks_[bl], rows, kernel, pass);
        });
        for (std::size_t p = 1; p < phaseWork_.size(); ++p) {
            const PhaseWork& w = phaseWork_[p];
            phases_.run(p, worker, [&](std::uint32_t unit) {
                if (w.color == kSlabsPhase) {
                    solveSpan(slabs_[unit], rows, kernel, w.pass);
                    return;
                }
                const ColorRange& range = colors_[w.color];
                if (range.overflow) {
                    solveRange(range, rows, kernel, w.pass);
                    return;
                }
                const std::size_t begin = std::size_t{unit} * kBatchChunk;
                solveBatches(range, begin, std::min<std::size_t>(range.batchCount, begin + kBatchChunk), rows, kernel,
                             w.pass);
            });
            phases_.wait(p);
        }
        phases_.wait(0);
    };
    if (workers == 1)
        region(0);
    else
        pool.forEachWorker(region);
    blocksPending_ = false;
}

template <class Kernel>
void ContactSolver::forEachColor(TaskPool& pool, Kernel&& kernel, int passes, const JointPass* joints,
                                 int firstIteration) {
    // Without joints (whose large-island pass runs on the calling thread, across the pool), in one region.
    if (joints == nullptr && pool.threadCount() > 1) {
        forEachColorInOneRegion(pool, kernel, passes, firstIteration);
        return;
    }
    // Blocks share no body with each other or with the large islands: each runs all its iterations in one task.
    if (!blocks_.empty()) {
        pool.forChunks(blocks_.size(), 1, [&](std::size_t, std::size_t begin, std::size_t end, int worker) {
            const BodyRows rows = rowsFor(worker);
            for (std::size_t bl = begin; bl < end; ++bl) {
                if (blocksPending_) buildBlock(bl);
                for (int pass = 0; pass < passes; ++pass) {
                    if (joints) (*joints)(static_cast<std::uint32_t>(bl), pass);
                    solveSpan(blocks_[bl], rows, kernel, pass);
                }
            }
        });
        blocksPending_ = false;
    }
    // The large islands' colours (only the manifolds that cross the slabs, when there are slabs), each across the
    // threads.
    const auto solveColorByColor = [&](int pass) {
        for (std::uint32_t c = 0; c < large_.colorCount; ++c) {
            const ColorRange range = colors_[large_.firstColor + c];
            if (range.overflow) {
                const BodyRows rows = rowsFor(0);
                solveRange(range, rows, kernel, pass);
                continue;
            }
            pool.forChunks(range.batchCount, kBatchChunk,
                           [&](std::size_t, std::size_t begin, std::size_t end, int worker) {
                               solveBatches(range, begin, end, rowsFor(worker), kernel, pass);
                           });
        }
    };
    for (int pass = 0; pass < passes; ++pass) {
        if (joints) (*joints)(static_cast<std::uint32_t>(blocks_.size()), pass);
        // The manifolds that cross the slabs run before them in every other iteration and after them otherwise (and
        // in a warm start or a bounce), so that loads pass both ways across the cut: S5's wall, cut in two, sags
        // 1.0 cm so, 16 cm with the crossing manifolds always after the slabs (2.0 cm uncut).
        const bool before = crossingFirst(pass, firstIteration);
        if (before) solveColorByColor(pass);
        if (!slabs_.empty())
            pool.forChunks(slabs_.size(), 1, [&](std::size_t slab, std::size_t, std::size_t, int worker) {
                solveSpan(slabs_[slab], rowsFor(worker), kernel, pass);
            });
        if (!before) solveColorByColor(pass);
    }
}

void ContactSolver::orderForShock() {
    // Levels by breadth-first search over the contacts between dynamic bodies, from the bodies that touch something
    // that cannot move (level 0). Serial and in manifold order, so the order is the same for every thread count.
    const std::uint32_t bodyCount = bodies_.count;
    const std::int32_t stillRow = static_cast<std::int32_t>(bodyCount);
    constexpr std::uint32_t kUnreached = ~0u;
    adjacencyStart_.assign(bodyCount + 1, 0);
    levelOf_.assign(bodyCount, kUnreached);
    const auto forEachLane = [&](auto&& visit) {
        for (std::size_t bi = 0; bi < batches_.size(); ++bi)
            for (std::size_t lane = 0; lane < kBatchLanes; ++lane)
                if (manifoldOfLane_[bi * kBatchLanes + lane] != ~0u) visit(batches_[bi], lane, bi * kBatchLanes + lane);
    };
    const auto dynamicSide = [&](const ContactBatch& b, std::size_t lane, int side) {
        return bodies_.mass[static_cast<std::uint32_t>(side == 0 ? b.bodyA[lane] : b.bodyB[lane])].inverseMass > 0;
    };
    forEachLane([&](const ContactBatch& b, std::size_t lane, std::size_t) {
        const bool dynA = dynamicSide(b, lane, 0), dynB = dynamicSide(b, lane, 1);
        if (dynA && dynB) {
            adjacencyStart_[static_cast<std::uint32_t>(b.bodyA[lane]) + 1] += 1;
            adjacencyStart_[static_cast<std::uint32_t>(b.bodyB[lane]) + 1] += 1;
        } else {
            const std::int32_t body = dynA ? b.bodyA[lane] : b.bodyB[lane];
            if (body != stillRow) levelOf_[static_cast<std::uint32_t>(body)] = 0;
        }
    });
    for (std::uint32_t i = 0; i < bodyCount; ++i) adjacencyStart_[i + 1] += adjacencyStart_[i];
    std::vector<std::uint32_t>& neighbours = adjacency_;
    neighbours.resize(adjacencyStart_[bodyCount]);
    {
        std::vector<std::uint32_t>& fill = adjacencyFill_;
        fill.assign(adjacencyStart_.begin(), adjacencyStart_.end() - 1);
        forEachLane([&](const ContactBatch& b, std::size_t lane, std::size_t) {
            if (!dynamicSide(b, lane, 0) || !dynamicSide(b, lane, 1)) return;
            const auto a = static_cast<std::uint32_t>(b.bodyA[lane]), c = static_cast<std::uint32_t>(b.bodyB[lane]);
            neighbours[fill[a]++] = c;
            neighbours[fill[c]++] = a;
        });
    }
    std::vector<std::uint32_t>& queue = shockQueue_;
    queue.clear();
    for (std::uint32_t i = 0; i < bodyCount; ++i)
        if (levelOf_[i] == 0) queue.push_back(i);
    for (std::size_t head = 0; head < queue.size(); ++head) {
        const std::uint32_t body = queue[head];
        for (std::uint32_t e = adjacencyStart_[body]; e < adjacencyStart_[body + 1]; ++e) {
            const std::uint32_t other = neighbours[e];
            if (levelOf_[other] == kUnreached) levelOf_[other] = levelOf_[body] + 1, queue.push_back(other);
        }
    }
    // A contact takes part when one side is lower than the other (or cannot move); contacts between bodies on the
    // same level, and in piles that touch nothing still, are left to the iterations.
    forEachLane([&](const ContactBatch& b, std::size_t lane, std::size_t at) {
        const bool dynA = dynamicSide(b, lane, 0), dynB = dynamicSide(b, lane, 1);
        if (!dynA || !dynB) {
            shockOrder_.push_back({0, static_cast<std::uint32_t>(at), dynA ? 1u : 0u});
            return;
        }
        const std::uint32_t la = levelOf_[static_cast<std::uint32_t>(b.bodyA[lane])];
        const std::uint32_t lb = levelOf_[static_cast<std::uint32_t>(b.bodyB[lane])];
        if (la == lb) return;
        shockOrder_.push_back({std::max(la, lb), static_cast<std::uint32_t>(at), la < lb ? 0u : 1u});
    });
    std::stable_sort(shockOrder_.begin(), shockOrder_.end(),
                     [](const ShockContact& x, const ShockContact& y) { return x.level < y.level; });
    for (ShockContact& s : shockOrder_) computeHeldMasses(s);
}

void ContactSolver::computeHeldMasses(ShockContact& s) const {
    const ContactBatch& b = batches_[s.lane / kBatchLanes];
    const std::size_t lane = s.lane % kBatchLanes;
    const bool holdA = s.heldSide == 0;
    const contact_kernels::MassW<float> upper =
        contact_kernels::loadMasses<float>(bodies_.mass.data(), holdA ? b.bodyB + lane : b.bodyA + lane);
    const float upperMass = upper.inverseMass;
    const simd::SymMat3W<float>& upperInertia = upper.inverseInertia;
    const Vec3 n{b.nx[lane], b.ny[lane], b.nz[lane]}, t1{b.t1x[lane], b.t1y[lane], b.t1z[lane]},
        t2{b.t2x[lane], b.t2y[lane], b.t2z[lane]};
    for (int i = 0; i < b.pointCount; ++i) {
        const ContactBatch::Point& p = b.points[i];
        if (p.normalMass[lane] == 0) continue;  // no point here: its masses stay zero
        const Vec3 r =
            holdA ? Vec3{p.rBx[lane], p.rBy[lane], p.rBz[lane]} : Vec3{p.rAx[lane], p.rAy[lane], p.rAz[lane]};
        const auto effective = [&](Vec3 dir) {
            const simd::Vec3W<float> rd = toWide(cross(r, dir));
            return 1.0f / (upperMass + simd::dot(rd, upperInertia * rd));
        };
        s.heldMasses[i][0] = effective(n);
        if (p.tangentMass1[lane] != 0) s.heldMasses[i][1] = effective(t1), s.heldMasses[i][2] = effective(t2);
    }
}

void ContactSolver::propagateShock() {
    if (shockOrder_.empty()) return;
    SolveParams params;
    params.invH = 1.0f / h_;
    params.maxPushOutVelocity = settings_.maxPushOutVelocity;
    // Rigid in the pass for the soft step: a soft contact with its lower body held would take its softness twice.
    params.useBias = settings_.positionCorrection == PositionCorrection::Baumgarte;
    params.moved = moved_;
    const BodyRows rows = rowsFor(0);
    // A body resting on several others is solved against each in turn; passes over its level (with every level
    // below already held) let those contacts agree before the level above holds it in turn.
    for (std::size_t first = 0, last = 0; first < shockOrder_.size(); first = last) {
        while (last < shockOrder_.size() && shockOrder_[last].level == shockOrder_[first].level) ++last;
        for (int pass = 0; pass < kShockPasses; ++pass)
            for (std::size_t at = first; at < last; ++at) solveHeld(shockOrder_[at], rows, params);
    }
}

void ContactSolver::solveHeld(const ShockContact& s, const BodyRows& rows, const SolveParams& params) {
    ContactBatch& b = batches_[s.lane / kBatchLanes];
    const std::size_t lane = s.lane % kBatchLanes;
    // Hold the lower side still for this contact (no mass, no inertia; its velocity is still read), and give
    // the points the effective masses of the upper body alone.
    // The pass is serial, so the lower body's mass row can stand still for this one lane and be put back after.
    MassRow& held = bodies_.mass[static_cast<std::uint32_t>(s.heldSide == 0 ? b.bodyA[lane] : b.bodyB[lane])];
    const MassRow heldMasses = held;
    held = MassRow{};
    float pointMasses[kMaxManifoldPoints][3];
    for (int i = 0; i < b.pointCount; ++i) {
        ContactBatch::Point& p = b.points[i];
        pointMasses[i][0] = p.normalMass[lane], pointMasses[i][1] = p.tangentMass1[lane];
        pointMasses[i][2] = p.tangentMass2[lane];
        p.normalMass[lane] = s.heldMasses[i][0], p.tangentMass1[lane] = s.heldMasses[i][1];
        p.tangentMass2[lane] = s.heldMasses[i][2];
    }
    if (friction_)
        contact_kernels::solve<float, true>(b, lane, rows, params, extrasOf(b));
    else
        contact_kernels::solve<float, false>(b, lane, rows, params, extrasOf(b));
    held = heldMasses;
    for (int i = 0; i < b.pointCount; ++i) {
        ContactBatch::Point& p = b.points[i];
        p.normalMass[lane] = pointMasses[i][0], p.tangentMass1[lane] = pointMasses[i][1];
        p.tangentMass2[lane] = pointMasses[i][2];
    }
}

void ContactSolver::warmStart(TaskPool& pool) {
    forEachColor(pool, []<class F>(ContactBatch& b, std::size_t lane, const BodyRows& rows, int) {
        contact_kernels::warmStart<F>(b, lane, rows);
    });
}

void ContactSolver::solveVelocities(bool useBias, TaskPool& pool, int iterations, bool warmStartFirst,
                                    const JointPass* joints) {
    SolveParams params;
    params.invH = 1.0f / h_;
    params.maxPushOutVelocity = settings_.maxPushOutVelocity;
    params.useBias = useBias && settings_.positionCorrection != PositionCorrection::SplitImpulse;
    params.moved = moved_;
    // With the warm start as pass 0, a block applies it in the same task as its iterations, while its rows are in
    // the core's cache.
    const int first = warmStartFirst ? 1 : 0;
    // The soft step solves friction in its relax iterations only, as Box3D does: in the biased iterations the soft
    // contacts push overlap apart and give under loads, bodies turn a little about their contacts as they do, and
    // friction that resists that motion winds its accumulated impulses up to the Coulomb limit, pairs of contacts
    // under one body pulling against each other; at the limit they let the body slip and jitter (S5's top cubes
    // jittered at 0.3 m/s and crept out of the wall's plane). Without relax iterations friction runs in these.
    const bool friction = friction_ && !(useBias && frictionInRelaxOnly_);
    const auto run = [&]<bool kFriction>() {
        forEachColor(
            pool,
            [&]<class F>(ContactBatch& b, std::size_t lane, const BodyRows& rows, int pass) {
                if (pass < first)
                    contact_kernels::warmStart<F>(b, lane, rows);
                else
                    contact_kernels::solve<F, kFriction>(b, lane, rows, params, extrasOf(b));
            },
            first + iterations, joints, first);
    };
    if (friction)
        run.template operator()<true>();
    else
        run.template operator()<false>();
}

void ContactSolver::solvePositions(TaskPool& pool, int iterations) {
    SolveParams params;
    params.invH = 1.0f / h_;
    params.maxPushOutVelocity = settings_.maxPushOutVelocity;
    forEachColor(
        pool,
        [&]<class F>(ContactBatch& b, std::size_t lane, const BodyRows& rows, int) {
            contact_kernels::solvePositions<F>(b, *extrasOf(b), lane, rows, params);
        },
        iterations, nullptr, 0);
}

void ContactSolver::applyPseudoVelocities(MovingBodies& m, TaskPool& pool) {
    buildPendingBlocks();
    SolverBodies& b = bodies_;
    const float h = h_;
    pool.forChunks(b.count, kBodyChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) {
            const std::uint32_t d = b.moving[i];
            if ((m.flags[d] & (kFlagKinematic | kFlagFrozen | kFlagAsleep)) == 0) {
                const BodyRow& pseudo = b.pseudo[i];
                m.px[d] += pseudo.linear.x * h, m.py[d] += pseudo.linear.y * h, m.pz[d] += pseudo.linear.z * h;
                const Vec3 w{pseudo.angular.x * h, pseudo.angular.y * h, pseudo.angular.z * h};
                if (w != Vec3{}) {
                    const Quat q{m.qx[d], m.qy[d], m.qz[d], m.qw[d]};
                    const Quat dq = Quat{w.x * 0.5f, w.y * 0.5f, w.z * 0.5f, 0.0f} * q;
                    Quat r{q.x + dq.x, q.y + dq.y, q.z + dq.z, q.w + dq.w};
                    const float len = std::sqrt(r.x * r.x + r.y * r.y + r.z * r.z + r.w * r.w);
                    m.qx[d] = r.x / len, m.qy[d] = r.y / len, m.qz[d] = r.z / len, m.qw[d] = r.w / len;
                }
            }
            b.pseudo[i] = BodyRow{};
        }
    });
    std::fill(b.pseudo.begin() + b.count, b.pseudo.end(), BodyRow{});
    // The pseudo impulses start again from zero in the next substep.
    for (std::size_t bi = 0; bi < extras_.size(); ++bi)
        for (int i = 0; i < batches_[bi].pointCount; ++i)
            std::fill(std::begin(extras_[bi].points[i].pseudoImpulse), std::end(extras_[bi].points[i].pseudoImpulse),
                      0.0f);
}

void ContactSolver::applyRestitution(TaskPool& pool) {
    const float threshold = settings_.restitutionThreshold;
    forEachColor(pool, [&]<class F>(ContactBatch& b, std::size_t lane, const BodyRows& rows, int) {
        contact_kernels::restitution<F>(b, *extrasOf(b), lane, rows, threshold);
    });
}

void ContactSolver::storeImpulses(std::vector<PointImpulse>& impulses, TaskPool& pool) {
    buildPendingBlocks();
    // The lanes of a colour hold manifolds far apart in manifold order: written straight from the batches, two
    // threads wrote into the same cache lines all along (S5 at two threads took 3.7 times the CPU time of one).
    resizeDiscarding(impulsesByLane_, batches_.size() * kBatchLanes * kMaxManifoldPoints);
    pool.forChunks(batches_.size(), kManifoldChunk / kBatchLanes,
                   [&](std::size_t, std::size_t first, std::size_t last, int) {
                       for (std::size_t bi = first; bi < last; ++bi) {
                           const ContactBatch& b = batches_[bi];
                           for (std::size_t lane = 0; lane < kBatchLanes; ++lane) {
                               PointImpulse* out = &impulsesByLane_[(bi * kBatchLanes + lane) * kMaxManifoldPoints];
                               for (int i = 0; i < b.pointCount; ++i) {
                                   const ContactBatch::Point& p = b.points[i];
                                   out[i] = {p.normalImpulse[lane], p.tangentImpulse1[lane], p.tangentImpulse2[lane]};
                               }
                               std::fill(out + b.pointCount, out + kMaxManifoldPoints, PointImpulse{});
                           }
                       }
                   });
    // Manifolds without a dynamic body have no lane and keep zero.
    pool.forChunks(impulses.size() / kMaxManifoldPoints, kManifoldChunk,
                   [&](std::size_t, std::size_t begin, std::size_t end, int) {
                       for (std::size_t k = begin; k < end; ++k) {
                           const std::uint32_t lane = k < laneOfManifold_.size() ? laneOfManifold_[k] : ~0u;
                           PointImpulse* to = &impulses[k * kMaxManifoldPoints];
                           if (lane == ~0u)
                               std::fill_n(to, kMaxManifoldPoints, PointImpulse{});
                           else
                               std::copy_n(&impulsesByLane_[std::size_t{lane} * kMaxManifoldPoints], kMaxManifoldPoints,
                                           to);
                       }
                   });
}

}  // namespace rubble::detail
