#include "narrowphase/pair_sides.h"

#include <atomic>

#include "core/parallel.h"
#include "shapes/shape_extents.h"
#include "simd/transpose.h"
#include "storage/flag_scan.h"

namespace rubble::detail {

static_assert(kPairRowFloats == simd::kRowFloats, "the batched gathers transpose whole rows");

namespace {
/// Moving bodies per task when their rows are written.
constexpr std::size_t kRowChunk = 1024;
/// Pairs per task when their bodies are marked, and bodies per task when the marks are read.
constexpr std::size_t kMarkChunk = 4096;
constexpr std::size_t kMarkScanChunk = 65536;
}  // namespace

Vec3 sizeOf(const Shape& shape) {
    switch (shape.kind) {
        case ShapeKind::Box:
            return shape.halfExtents;
        case ShapeKind::Sphere:
            return {shape.radius, 0, 0};
        case ShapeKind::Capsule:
            return {shape.radius, shape.halfHeight, 0};
        default:
            return {};
    }
}

void ShapeTables::prepare(const std::vector<Shape>& shapes) {
    const std::size_t n = shapes.size();
    for (auto* table : {&sizeX, &sizeY, &sizeZ, &reach}) table->resize(n);
    kind.resize(n);
    for (std::size_t s = 0; s < n; ++s) {
        const Shape& shape = shapes[s];
        kind[s] = shape.kind;
        const Vec3 size = sizeOf(shape);
        sizeX[s] = size.x, sizeY[s] = size.y, sizeZ[s] = size.z;
        reach[s] = rotationReach(shape);
    }
}

void MovingRows::writeRows(const MovingBodies& m, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
        float* p = pose.data() + i * kPairRowFloats;
        float* v = motion.data() + i * kPairRowFloats;
        p[kComX] = m.px[i], p[kComY] = m.py[i], p[kComZ] = m.pz[i];
        p[kRotX] = m.qx[i], p[kRotY] = m.qy[i], p[kRotZ] = m.qz[i], p[kRotW] = m.qw[i];
        p[kLocalComX] = m.lcx[i];
        v[kVelX] = m.vx[i], v[kVelY] = m.vy[i], v[kVelZ] = m.vz[i];
        v[kSpinX] = m.wx[i], v[kSpinY] = m.wy[i], v[kSpinZ] = m.wz[i];
        v[kLocalComY] = m.lcy[i], v[kLocalComZ] = m.lcz[i];
    }
}

void MovingRows::write(const MovingBodies& m, const CandidatePairs& candidates, TaskPool& pool) {
    const std::size_t n = m.size();
    pose.resize(n * kPairRowFloats);
    motion.resize(n * kPairRowFloats);
    const std::size_t sides = 2 * candidates.moving.size() + candidates.statics.size() + candidates.meshes.size();
    if (sides >= n / 4) {
        // Most bodies are in a pair: one streaming pass beats marking them.
        pool.forChunks(n, kRowChunk,
                       [&](std::size_t, std::size_t begin, std::size_t end, int) { writeRows(m, begin, end); });
        return;
    }
    // Few bodies in pairs: mark them (the same byte may be set by two threads, hence atomic), then write the marked
    // rows in a pass that reads one byte per body and clears it.
    inPair_.resize(n, 0);
    const auto mark = [&](std::uint32_t i) {
        std::atomic_ref<std::uint8_t>(inPair_[i]).store(1, std::memory_order_relaxed);
    };
    pool.forChunks(candidates.moving.size(), kMarkChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t k = begin; k < end; ++k) mark(candidates.moving[k].a), mark(candidates.moving[k].b);
    });
    for (const BodyPair& p : candidates.statics) mark(p.a);
    for (const MeshPair& p : candidates.meshes) mark(p.moving);
    pool.forChunks(n, kMarkScanChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; (i = nextWith(inPair_.data(), i, end, 1)) < end; ++i) {
            inPair_[i] = 0;
            writeRows(m, i, i + 1);
        }
    });
}

const Shape& sideShape(const BodyStorage& storage, const std::vector<Shape>& shapes, const ContactPair& p, bool sideB) {
    const std::uint32_t i = sideB ? p.b : p.a;
    const Shape& body = shapes[(sideB ? p.bStatic : p.aStatic) ? storage.statics.shape[i] : storage.moving.shape[i]];
    const std::uint16_t child = sideB ? p.childB : p.childA;
    return child == kNoChild ? body : *body.children[child].shape;
}

Vec3 sphereCenter(const BodyStorage& storage, const MovingRows& rows, const std::vector<Shape>& shapes,
                  const ContactPair& p, bool sideB) {
    const std::uint32_t i = sideB ? p.b : p.a;
    if (!(sideB ? p.bStatic : p.aStatic) && (sideB ? p.childB : p.childA) == kNoChild) {
        const float* pose = rowOf(rows.pose, i);
        return {pose[kComX], pose[kComY], pose[kComZ]};
    }
    return posedSide(storage, rows, shapes, p, sideB).pose.position;
}

}  // namespace rubble::detail
