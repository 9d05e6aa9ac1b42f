#include "islands/sleep.h"

#include <algorithm>
#include <atomic>

#include "core/parallel.h"
#include "storage/flag_scan.h"

namespace rubble::detail {
namespace {

constexpr std::size_t kBodyChunk = 4096;
constexpr std::size_t kManifoldChunk = 2048;
constexpr std::size_t kIslandChunk = 1024;

bool movingKinematic(const MovingBodies& m, std::uint32_t i) {
    return (m.flags[i] & kFlagKinematic) != 0 &&
           (m.vx[i] != 0 || m.vy[i] != 0 || m.vz[i] != 0 || m.wx[i] != 0 || m.wy[i] != 0 || m.wz[i] != 0);
}

std::uint32_t slotOf(const BodyStorage& s, std::uint32_t dense, bool isStatic) {
    return isStatic ? s.statics.slot[dense] : s.moving.slot[dense];
}

/// Runs pick(k) over the islands in parallel chunks and returns the picked ones in island order.
template <class Pick>
void pickIslands(std::uint32_t islands, TaskPool& pool, std::vector<std::vector<std::uint32_t>>& perChunk,
                 std::vector<std::uint32_t>& out, Pick&& pick) {
    perChunk.resize(TaskPool::chunkCount(islands, kIslandChunk));
    pool.forChunks(islands, kIslandChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        perChunk[c].clear();
        for (std::size_t k = begin; k < end; ++k)
            if (pick(static_cast<std::uint32_t>(k))) perChunk[c].push_back(static_cast<std::uint32_t>(k));
    });
    out.clear();
    for (const auto& c : perChunk) out.insert(out.end(), c.begin(), c.end());
}

}  // namespace

void SleepingIslands::linkSleepingIslands(const BodyStorage& storage, const Contacts& contacts, TaskPool& pool,
                                          std::vector<IslandEdge>& edges) {
    if (sleepingBodies_ == 0) return;
    const MovingBodies& m = storage.moving;
    const auto& slots = storage.slots();
    groupLinkedAt_.resize(groups_.size(), 0);
    const std::uint64_t call = ++linkCalls_;
    const auto asleep = [&](std::uint32_t dense) { return (m.flags[dense] & kFlagAsleep) != 0; };
    const std::size_t jointEdges = edges.size();
    const auto link = [&](std::uint32_t dense) {
        const std::uint32_t g = m.sleepGroup[dense];
        if (groupLinkedAt_[g] == call) return;
        groupLinkedAt_[g] = call;
        const Group& group = groups_[g];
        const std::uint32_t first = slots[group.slots[0]].dense;
        for (std::size_t k = 1; k < group.slots.size(); ++k) edges.emplace_back(first, slots[group.slots[k]].dense);
    };
    // The broad phase finds no pair of two sleeping bodies, nor of a sleeping and a static one: a manifold with a
    // sleeping side has an awake (or kinematic) body on the other.
    chunkTouching_.resize(TaskPool::chunkCount(contacts.pairs.size(), kManifoldChunk));
    pool.forChunks(contacts.pairs.size(), kManifoldChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::vector<std::uint32_t>& touching = chunkTouching_[c];
        touching.clear();
        for (std::size_t k = begin; k < end; ++k) {
            const ContactPair& p = contacts.pairs[k];
            if (!p.aStatic && asleep(p.a)) touching.push_back(p.a);
            if (!p.bStatic && asleep(p.b)) touching.push_back(p.b);
        }
    });
    for (const std::vector<std::uint32_t>& touching : chunkTouching_)
        for (const std::uint32_t dense : touching) link(dense);
    // Joints: two bodies of one sleeping island sleep together; a joint to an awake body wakes the island.
    for (std::size_t k = 0; k < jointEdges; ++k) {
        const auto [a, b] = edges[k];
        if (asleep(a) != asleep(b)) link(asleep(a) ? a : b);
    }
}

bool SleepingIslands::wakeTouched(const Islands& islands, BodyStorage& storage, IntegrationScratch& integration,
                                  Contacts& contacts, std::vector<PointImpulse>& impulses, ContactCache& cache,
                                  TaskPool& pool) {
    sleepingPartnersIndexed_ = false;
    MovingBodies& m = storage.moving;
    const std::uint32_t count = islands.count();
    touchedByKinematic_.assign(count, 0);
    pool.forChunks(contacts.pairs.size(), kManifoldChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t k = begin; k < end; ++k) {
            const ContactPair& p = contacts.pairs[k];
            if (p.aStatic || p.bStatic) continue;
            std::uint32_t island = kNoIsland;
            if (movingKinematic(m, p.a)) island = islands.islandOf[p.b];
            if (movingKinematic(m, p.b)) island = islands.islandOf[p.a];
            // Several manifolds may mark one island; they all store the same value.
            if (island != kNoIsland)
                std::atomic_ref<std::uint8_t>(touchedByKinematic_[island]).store(1, std::memory_order_relaxed);
        }
    });
    if (sleepingBodies_ == 0) return false;

    std::vector<std::uint32_t> waking;
    pickIslands(count, pool, chunkIslands_, waking, [&](std::uint32_t k) {
        bool asleep = false, awake = false;
        for (std::uint32_t at = islands.bodyStart[k]; at < islands.bodyStart[k + 1]; ++at)
            ((m.flags[islands.bodies[at]] & kFlagAsleep) ? asleep : awake) = true;
        return asleep && (awake || touchedByKinematic_[k]);
    });
    if (waking.empty()) return false;
    // Integrate velocities skipped the sleeping bodies in this step: the non-default integrators' offsets are stale.
    if (integration.dx.size() == m.size())
        for (std::uint32_t k : waking)
            for (std::uint32_t at = islands.bodyStart[k]; at < islands.bodyStart[k + 1]; ++at) {
                const std::uint32_t i = islands.bodies[at];
                if (!(m.flags[i] & kFlagAsleep)) continue;
                integration.dx[i] = integration.dy[i] = integration.dz[i] = 0;
                integration.ex[i] = integration.ey[i] = integration.ez[i] = 0;
            }
    restored_.clear();
    for (std::uint32_t k : waking)
        for (std::uint32_t at = islands.bodyStart[k]; at < islands.bodyStart[k + 1]; ++at) {
            const std::uint32_t i = islands.bodies[at];
            if (m.flags[i] & kFlagAsleep) wakeGroup(m.sleepGroup[i], storage, restored_);
        }
    cache.restoreIntoStep(restored_, storage, contacts, impulses);
    return !restored_.empty();
}

void SleepingIslands::fallAsleep(const Islands& islands, const Contacts& contacts,
                                 const std::vector<PointImpulse>& impulses, const ContactCache& cache,
                                 BodyStorage& storage, const ShapeBoundsTable& shapes, const SleepSettings& settings,
                                 float dt, TaskPool& pool) {
    sleepingPartnersIndexed_ = false;
    MovingBodies& m = storage.moving;
    const std::uint32_t count = islands.count();
    if (touchedByKinematic_.size() != count) touchedByKinematic_.assign(count, 0);
    const float linearSq = settings.linearThreshold * settings.linearThreshold;
    const float angularSq = settings.angularThreshold * settings.angularThreshold;
    // A body in no island touches nothing (or is kinematic or frozen): it rests, and falls asleep, on its own.
    chunkLone_.resize(TaskPool::chunkCount(m.size(), kBodyChunk));
    pool.forChunks(m.size(), kBodyChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::vector<std::uint32_t>& lone = chunkLone_[c];
        lone.clear();
        for (std::size_t i = begin; (i = nextWithout(m.flags.data(), i, end, kFlagAsleep)) < end; ++i) {
            const std::uint32_t island = islands.islandOf[i];
            const bool alone = island == kNoIsland;
            if (alone && !joinsIslands(m.flags[i])) continue;
            const float v = m.vx[i] * m.vx[i] + m.vy[i] * m.vy[i] + m.vz[i] * m.vz[i];
            const float w = m.wx[i] * m.wx[i] + m.wy[i] * m.wy[i] + m.wz[i] * m.wz[i];
            const float reach = shapes.reach[m.shape[i]];
            const bool rests = v < linearSq && w < angularSq && w * reach * reach < linearSq &&
                               (m.flags[i] & kFlagNoSleep) == 0 && (alone || !touchedByKinematic_[island]);
            m.sleepTimer[i] = rests ? m.sleepTimer[i] + dt : 0.0f;
            if (alone && m.sleepTimer[i] >= settings.timeToSleep) lone.push_back(static_cast<std::uint32_t>(i));
        }
    });
    std::vector<std::uint32_t> sleeping;
    pickIslands(count, pool, chunkIslands_, sleeping, [&](std::uint32_t k) {
        for (std::uint32_t at = islands.bodyStart[k]; at < islands.bodyStart[k + 1]; ++at) {
            const std::uint32_t i = islands.bodies[at];
            if ((m.flags[i] & kFlagAsleep) || m.sleepTimer[i] < settings.timeToSleep) return false;
        }
        return true;
    });
    const auto newGroup = [&] {
        const std::uint32_t g = groupIds_.acquire().index;
        if (g == groups_.size()) groups_.emplace_back();
        groups_[g].slots.clear();
        groups_[g].manifolds.clear();
        return g;
    };
    const auto putToSleep = [&](std::uint32_t i, std::uint32_t g) {
        m.flags[i] |= kFlagAsleep;
        m.vx[i] = m.vy[i] = m.vz[i] = m.wx[i] = m.wy[i] = m.wz[i] = 0;
        m.sleepGroup[i] = g;
        groups_[g].slots.push_back(m.slot[i]);
        noteChange(m.slot[i]);
        sleepingBodies_ += 1;
    };
    const auto sleepIsland = [&](std::uint32_t k) {
        const std::uint32_t g = newGroup();
        Group& group = groups_[g];
        for (std::uint32_t at = islands.bodyStart[k]; at < islands.bodyStart[k + 1]; ++at)
            putToSleep(islands.bodies[at], g);
        for (std::uint32_t at = islands.manifoldStart[k]; at < islands.manifoldStart[k + 1]; ++at) {
            const std::uint32_t c = islands.manifolds[at];
            const ContactPair& p = contacts.pairs[c];
            // Pairs with a kinematic (or frozen) body are found again every step: that body is never asleep.
            if ((!p.aStatic && !joinsIslands(m.flags[p.a])) || (!p.bStatic && !joinsIslands(m.flags[p.b]))) continue;
            KeptManifold& kept = group.manifolds.emplace_back();
            kept.key = cache.currentKey(c);
            kept.pair = p;
            kept.pair.a = slotOf(storage, p.a, p.aStatic);
            kept.pair.b = slotOf(storage, p.b, p.bStatic);
            kept.manifold = contacts.manifolds[c];
            std::copy_n(impulses.begin() + static_cast<std::ptrdiff_t>(c) * kMaxManifoldPoints, kMaxManifoldPoints,
                        kept.impulses);
        }
    };
    // Groups are made in the islands' canonical order, lone bodies among them by index (an island is named by its
    // smallest body), as if each lone body were an island of its own.
    std::size_t next = 0;
    for (const std::vector<std::uint32_t>& lone : chunkLone_)
        for (const std::uint32_t i : lone) {
            for (; next < sleeping.size() && islands.bodies[islands.bodyStart[sleeping[next]]] < i; ++next)
                sleepIsland(sleeping[next]);
            putToSleep(i, newGroup());
        }
    for (; next < sleeping.size(); ++next) sleepIsland(sleeping[next]);
}

void SleepingIslands::wakeGroup(std::uint32_t g, BodyStorage& storage, std::vector<KeptManifold>& out) {
    if (!groupIds_.alive(g)) return;
    Group& group = groups_[g];
    MovingBodies& m = storage.moving;
    const auto& slots = storage.slots();
    for (std::uint32_t slot : group.slots) {
        const std::uint32_t i = slots[slot].dense;
        m.flags[i] &= static_cast<std::uint8_t>(~kFlagAsleep);
        m.sleepTimer[i] = 0;
        noteChange(slot);
    }
    sleepingBodies_ -= static_cast<std::uint32_t>(group.slots.size());
    out.insert(out.end(), group.manifolds.begin(), group.manifolds.end());
    group.slots.clear();
    group.manifolds.clear();
    groupIds_.release(g);
}

void SleepingIslands::noteChange(std::uint32_t slot) {
    if (changesOverflowed_) return;
    // A world whose broad phase does not run (a lone body) drains nothing: past this the list says "look at all".
    constexpr std::size_t kMostListed = std::size_t{1} << 20;
    if (changedSlots_.size() >= kMostListed) {
        changedSlots_.clear();
        changesOverflowed_ = true;
        return;
    }
    changedSlots_.push_back(slot);
}

void SleepingIslands::wake(std::uint32_t dense, BodyStorage& storage) {
    if (storage.moving.flags[dense] & kFlagAsleep)
        wakeGroup(storage.moving.sleepGroup[dense], storage, pendingWarmStarts_);
}

void SleepingIslands::indexSleepingPartners(const BodyStorage& storage, const ContactCache& cache) {
    const auto asleep = [&](std::uint32_t slot) { return storage.sleepingRow(slot) != ~0u; };
    sleepingPartners_.clear();
    const auto add = [&](std::uint32_t a, std::uint32_t b) {
        if (asleep(b)) sleepingPartners_.emplace_back(a, b);
        if (asleep(a)) sleepingPartners_.emplace_back(b, a);
    };
    cache.forEachPair(add);
    for (std::uint32_t g = 0; g < groups_.size(); ++g)
        if (groupIds_.alive(g))
            for (const KeptManifold& k : groups_[g].manifolds) add(k.pair.a, k.pair.b);
    std::sort(sleepingPartners_.begin(), sleepingPartners_.end());
    sleepingPartnersIndexed_ = true;
}

void SleepingIslands::wakeTouching(std::uint32_t slot, BodyStorage& storage, const ContactCache& cache) {
    if (sleepingBodies_ == 0) return;
    if (!sleepingPartnersIndexed_) indexSleepingPartners(storage, cache);
    // A sleeping island that touches the body holds a sleeping partner of it, and waking that partner wakes it.
    const auto& slots = storage.slots();
    auto it = std::lower_bound(sleepingPartners_.begin(), sleepingPartners_.end(), std::pair{slot, 0u});
    for (; it != sleepingPartners_.end() && it->first == slot; ++it)
        if (storage.alive(it->second) && slots[it->second].set == BodySet::Moving)
            wake(slots[it->second].dense, storage);
}

void SleepingIslands::wakeAll(BodyStorage& storage) {
    for (std::uint32_t g = 0; g < groups_.size(); ++g) wakeGroup(g, storage, pendingWarmStarts_);
}

void SleepingIslands::flushWarmStarts(ContactCache& cache) {
    sleepingPartnersIndexed_ = false;
    if (pendingWarmStarts_.empty()) return;
    cache.restoreForWarmStart(pendingWarmStarts_);
    pendingWarmStarts_.clear();
}

}  // namespace rubble::detail
