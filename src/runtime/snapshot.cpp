// Snapshots: poses out of the world's SoA arrays into slot-indexed SoA arrays, and the render side's blend of two.
#include "runtime/snapshot.h"

#include <algorithm>
#include <cmath>

#include "world_access.h"

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
            out.generation[slot] = slots[slot].generation;
            out.px[slot] = s.px[i], out.py[slot] = s.py[i], out.pz[slot] = s.pz[i];
            out.qx[slot] = s.qx[i], out.qy[slot] = s.qy[i], out.qz[slot] = s.qz[i], out.qw[slot] = s.qw[i];
            out.shape[slot] = s.shape[i];
            out.flags[slot] = kSnapshotStatic;
        }
        for (std::uint32_t i = 0; i < m.size(); ++i) {
            const std::uint32_t slot = m.slot[i];
            out.generation[slot] = slots[slot].generation;
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
    // Bodies in both snapshots blend; the rest (new bodies, and everything when alpha is 1) take the newer pose.
    // Branch-free per slot so that the loop vectorises: a body not in the older snapshot blends with weight 1.
    const std::uint32_t* genOld = older.generation.data();
    const std::uint32_t* genNew = newer.generation.data();
    for (std::size_t s = 0; s < shared; ++s) {
        const float a = genOld[s] == genNew[s] ? alpha : 1.0f;
        const float b = 1.0f - a;
        out.px[s] = older.px[s] * b + newer.px[s] * a;
        out.py[s] = older.py[s] * b + newer.py[s] * a;
        out.pz[s] = older.pz[s] * b + newer.pz[s] * a;
        // Normalised lerp along the shortest arc: q and -q are the same rotation, so the older one is flipped into
        // the newer one's hemisphere first. For the rotation of one step nlerp is within 1e-4 rad of slerp.
        const float d = older.qx[s] * newer.qx[s] + older.qy[s] * newer.qy[s] + older.qz[s] * newer.qz[s] +
                        older.qw[s] * newer.qw[s];
        const float bs = d < 0 ? -b : b;
        const float x = older.qx[s] * bs + newer.qx[s] * a, y = older.qy[s] * bs + newer.qy[s] * a;
        const float z = older.qz[s] * bs + newer.qz[s] * a, w = older.qw[s] * bs + newer.qw[s] * a;
        const float len2 = x * x + y * y + z * z + w * w;
        const float inv = len2 > 0 ? 1.0f / std::sqrt(len2) : 0.0f;
        out.qx[s] = x * inv, out.qy[s] = y * inv, out.qz[s] = z * inv, out.qw[s] = w * inv;
    }
    std::copy(newer.px.begin() + static_cast<std::ptrdiff_t>(shared), newer.px.end(), out.px.begin() + shared);
    std::copy(newer.py.begin() + static_cast<std::ptrdiff_t>(shared), newer.py.end(), out.py.begin() + shared);
    std::copy(newer.pz.begin() + static_cast<std::ptrdiff_t>(shared), newer.pz.end(), out.pz.begin() + shared);
    std::copy(newer.qx.begin() + static_cast<std::ptrdiff_t>(shared), newer.qx.end(), out.qx.begin() + shared);
    std::copy(newer.qy.begin() + static_cast<std::ptrdiff_t>(shared), newer.qy.end(), out.qy.begin() + shared);
    std::copy(newer.qz.begin() + static_cast<std::ptrdiff_t>(shared), newer.qz.end(), out.qz.begin() + shared);
    std::copy(newer.qw.begin() + static_cast<std::ptrdiff_t>(shared), newer.qw.end(), out.qw.begin() + shared);
}

}  // namespace rubble
