// Snapshots: poses out of the world's SoA arrays into slot-indexed SoA arrays, and the render side's blend of two.
#include "runtime/snapshot.h"

#include <algorithm>
#include <cmath>

#include "simd/simd.h"
#include "world/world_access.h"

namespace rubble {
namespace detail {

namespace {

constexpr std::size_t kPublishChunk = 4096;

std::uint8_t snapshotFlags(std::uint8_t bodyFlags) {
    std::uint8_t f = 0;
    if (bodyFlags & kFlagKinematic) f |= kSnapshotKinematic;
    if (bodyFlags & kFlagAsleep) f |= kSnapshotAsleep;
    if (bodyFlags & kFlagFrozen) f |= kSnapshotFrozen;
    return f;
}

void resizeAll(Snapshot& s, std::size_t n) {
    s.generation.assign(n, 0);
    for (auto* a : {&s.px, &s.py, &s.pz, &s.qx, &s.qy, &s.qz}) a->assign(n, 0.0f);
    s.qw.assign(n, 1.0f);
    s.shape.assign(n, 0);
    s.flags.assign(n, 0);
}

}  // namespace

void writeSnapshot(const World& world, bool layoutChanged, Snapshot& out) {
    const World::Impl& w = WorldAccess::of(world);
    const MovingBodies& m = w.bodies.moving;
    const auto& slots = w.bodies.slots();
    if (layoutChanged || out.generation.size() != slots.size()) {
        resizeAll(out, slots.size());
        const StaticBodies& s = w.bodies.statics;
        for (std::uint32_t i = 0; i < s.size(); ++i) {
            const std::uint32_t slot = s.slot[i];
            out.generation[slot] = w.bodies.idAt(slot).generation;
            out.px[slot] = s.px[i], out.py[slot] = s.py[i], out.pz[slot] = s.pz[i];
            out.qx[slot] = s.qx[i], out.qy[slot] = s.qy[i], out.qz[slot] = s.qz[i], out.qw[slot] = s.qw[i];
            out.shape[slot] = s.shape[i];
            out.flags[slot] = kSnapshotStatic;
        }
        for (std::uint32_t i = 0; i < m.size(); ++i) {
            const std::uint32_t slot = m.slot[i];
            out.generation[slot] = w.bodies.idAt(slot).generation;
            out.shape[slot] = m.shape[i];
        }
    }
    // The world keeps the centre of mass; the renderer wants the shape's origin: p - R c. Chunks write disjoint
    // slots, so they need no merging.
    w.pool->forChunks(m.size(), kPublishChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) {
            const std::uint32_t slot = m.slot[i];
            const Quat q{m.qx[i], m.qy[i], m.qz[i], m.qw[i]};
            const Vec3 origin = Vec3{m.px[i], m.py[i], m.pz[i]} - rotate(q, {m.lcx[i], m.lcy[i], m.lcz[i]});
            out.px[slot] = origin.x, out.py[slot] = origin.y, out.pz[slot] = origin.z;
            out.qx[slot] = q.x, out.qy[slot] = q.y, out.qz[slot] = q.z, out.qw[slot] = q.w;
            out.flags[slot] = snapshotFlags(m.flags[i]);
        }
    });
}

}  // namespace detail

namespace {

/// The pose arrays of a snapshot as plain pointers, so that the blend loop can promise the compiler they do not
/// overlap (restrict) and vectorise.
template <class F>
struct PosesOf {
    F *px, *py, *pz, *qx, *qy, *qz, *qw;
};
struct Poses {
    static PosesOf<const float> of(const Snapshot& s) {
        return {s.px.data(), s.py.data(), s.pz.data(), s.qx.data(), s.qy.data(), s.qz.data(), s.qw.data()};
    }
    static PosesOf<float> of(Snapshot& s) {
        return {s.px.data(), s.py.data(), s.pz.data(), s.qx.data(), s.qy.data(), s.qz.data(), s.qw.data()};
    }
};

/// Blends slot s (and the lanes after it, for wide F) of a and b with weights 1 - alpha and alpha.
template <class F>
void blendLanes(std::size_t s, PosesOf<const float> a, PosesOf<const float> b, float alpha, PosesOf<float> o) {
    using simd::load;
    const F wb = simd::broadcast<F>(alpha), wa = simd::broadcast<F>(1.0f - alpha);
    const F zero = simd::broadcast<F>(0.0f), one = simd::broadcast<F>(1.0f);
    simd::store(o.px + s, load<F>(a.px + s) * wa + load<F>(b.px + s) * wb);
    simd::store(o.py + s, load<F>(a.py + s) * wa + load<F>(b.py + s) * wb);
    simd::store(o.pz + s, load<F>(a.pz + s) * wa + load<F>(b.pz + s) * wb);
    // Normalised lerp along the shortest arc: q and -q are the same rotation, so the older one is flipped into the
    // newer one's hemisphere first. For the rotation of one step nlerp is within 1e-4 rad of slerp.
    const F ax = load<F>(a.qx + s), ay = load<F>(a.qy + s), az = load<F>(a.qz + s), aw = load<F>(a.qw + s);
    const F bx = load<F>(b.qx + s), by = load<F>(b.qy + s), bz = load<F>(b.qz + s), bw = load<F>(b.qw + s);
    const F d = ax * bx + ay * by + az * bz + aw * bw;
    const F ws = simd::select(d < zero, zero - wa, wa);
    const F x = ax * ws + bx * wb, y = ay * ws + by * wb, z = az * ws + bz * wb, w = aw * ws + bw * wb;
    const F len2 = x * x + y * y + z * z + w * w;
    const F inv = simd::select(len2 > zero, one / simd::sqrt(len2), zero);
    simd::store(o.qx + s, x * inv);
    simd::store(o.qy + s, y * inv);
    simd::store(o.qz + s, z * inv);
    simd::store(o.qw + s, w * inv);
}

/// Blends the first `count` slots, in SIMD lanes, then gives every slot whose generation differs (a body new in the
/// newer snapshot) the newer pose.
void blendPoses(PosesOf<const float> a, PosesOf<const float> b, const std::uint32_t* genA, const std::uint32_t* genB,
                float alpha, std::size_t count, PosesOf<float> o) {
    const std::size_t wide = simd::roundDownToLanes<simd::FloatW>(count);
    std::size_t s = 0;
    for (; s < wide; s += simd::kLanes) blendLanes<simd::FloatW>(s, a, b, alpha, o);
    for (; s < count; ++s) blendLanes<float>(s, a, b, alpha, o);
    for (s = 0; s < count; ++s)
        if (genA[s] != genB[s]) {
            o.px[s] = b.px[s], o.py[s] = b.py[s], o.pz[s] = b.pz[s];
            o.qx[s] = b.qx[s], o.qy[s] = b.qy[s], o.qz[s] = b.qz[s], o.qw[s] = b.qw[s];
        }
}

template <class T>
void copyInto(const std::vector<T>& from, std::vector<T>& to) {
    to.resize(from.size());
    std::copy(from.begin(), from.end(), to.begin());
}

}  // namespace

void interpolateSnapshots(const Snapshot& older, const Snapshot& newer, float alpha, RenderFrame& out) {
    alpha = std::isnan(alpha) ? 1.0f : std::clamp(alpha, 0.0f, 1.0f);
    out.step = newer.step;
    out.olderStep = older.step;
    out.alpha = alpha;
    out.time = older.time + (newer.time - older.time) * alpha;
    out.clockTime = newer.clockTime;
    out.profile = newer.profile;
    out.stats = newer.stats;
    copyInto(newer.generation, out.generation);
    copyInto(newer.shape, out.shape);
    copyInto(newer.flags, out.flags);
    const std::size_t n = newer.generation.size();
    out.bodyCount = static_cast<std::uint32_t>(
        n - static_cast<std::size_t>(std::count(newer.generation.begin(), newer.generation.end(), 0u)));
    for (auto* a : {&out.px, &out.py, &out.pz, &out.qx, &out.qy, &out.qz, &out.qw}) a->resize(n);
    const std::size_t shared = &older == &newer || alpha == 1.0f ? 0 : std::min(n, older.generation.size());
    // Bodies in both snapshots blend; slots past the older snapshot's (and every slot when alpha is 1) copy the newer
    // pose.
    blendPoses(Poses::of(older), Poses::of(newer), older.generation.data(), newer.generation.data(), alpha, shared,
               Poses::of(out));
    std::copy(newer.px.begin() + static_cast<std::ptrdiff_t>(shared), newer.px.end(), out.px.begin() + shared);
    std::copy(newer.py.begin() + static_cast<std::ptrdiff_t>(shared), newer.py.end(), out.py.begin() + shared);
    std::copy(newer.pz.begin() + static_cast<std::ptrdiff_t>(shared), newer.pz.end(), out.pz.begin() + shared);
    std::copy(newer.qx.begin() + static_cast<std::ptrdiff_t>(shared), newer.qx.end(), out.qx.begin() + shared);
    std::copy(newer.qy.begin() + static_cast<std::ptrdiff_t>(shared), newer.qy.end(), out.qy.begin() + shared);
    std::copy(newer.qz.begin() + static_cast<std::ptrdiff_t>(shared), newer.qz.end(), out.qz.begin() + shared);
    std::copy(newer.qw.begin() + static_cast<std::ptrdiff_t>(shared), newer.qw.end(), out.qw.begin() + shared);
}

}  // namespace rubble
