#include "contacts.h"

#include <atomic>

#include "parallel.h"

namespace rubble::detail {
namespace {

constexpr std::size_t kChunk = 1024;

std::uint64_t hashOf(const ContactKey& k) {
    // Three words folded with odd multipliers and a final avalanche: keys differ in few bits (neighbouring slots).
    std::uint64_t h = k.slots * 0x9E3779B97F4A7C15ull;
    h ^= (k.generations + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
    h ^= (k.parts + 0x165667B19E3779F9ull) * 0xD6E8FEB86659FD93ull;
    h ^= h >> 32;
    h *= 0xD6E8FEB86659FD93ull;
    return h ^ (h >> 29);
}

std::uint32_t slotOf(const BodyStorage& s, std::uint32_t dense, bool isStatic) {
    return isStatic ? s.statics.slot[dense] : s.moving.slot[dense];
}

}  // namespace

void ContactCache::warmStart(const Contacts& contacts, const BodyStorage& storage, TaskPool& pool,
                             std::vector<PointImpulse>& impulses) {
    const std::size_t n = contacts.manifolds.size();
    currentKeys_.resize(n);
    impulses.resize(n * kMaxManifoldPoints);
    const std::size_t mask = table_.empty() ? 0 : table_.size() - 1;
    std::vector<std::uint32_t> chunkManifolds(TaskPool::chunkCount(n, kChunk)), chunkPoints(chunkManifolds.size());
    const auto& slots = storage.slots();
    pool.forChunks(n, kChunk, [&](std::size_t chunk, std::size_t begin, std::size_t end, int) {
        std::uint32_t manifolds = 0, points = 0;
        std::fill(impulses.begin() + begin * kMaxManifoldPoints, impulses.begin() + end * kMaxManifoldPoints,
                  PointImpulse{});
        // Manifolds come in canonical order, which changes little from step to step: the entry after the last
        // match is tried before the table, so a settled scene reads last step's entries in order, not at random.
        std::size_t next = previous_.size();
        for (std::size_t m = begin; m < end; ++m) {
            const ContactPair& p = contacts.pairs[m];
            const std::uint32_t slotA = slotOf(storage, p.a, p.aStatic), slotB = slotOf(storage, p.b, p.bStatic);
            ContactKey key;
            key.slots = (std::uint64_t{slotA} << 32) | slotB;
            key.generations = (std::uint64_t{slots[slotA].generation} << 32) | slots[slotB].generation;
            key.parts = (std::uint64_t{p.triangle} << 32) | (std::uint64_t{p.childA} << 16) | p.childB;
            currentKeys_[m] = key;
            if (table_.empty()) continue;
            std::uint32_t found = 0;  // entry + 1, 0 for none
            if (next < previous_.size() && previous_[next].key == key) {
                found = static_cast<std::uint32_t>(next + 1);
            } else {
                // Linear probing in a table at most half full: a miss ends at the first empty cell.
                for (std::size_t at = hashOf(key) & mask;; at = (at + 1) & mask) {
                    const std::uint32_t entry = table_[at];
                    if (entry == 0) break;
                    if (previous_[entry - 1].key == key) {
                        found = entry;
                        break;
                    }
                }
            }
            if (found == 0) continue;
            next = found;  // the entry after this one
            const Entry& old = previous_[found - 1];
            ++manifolds;
            const Manifold& now = contacts.manifolds[m];
            bool taken[kMaxManifoldPoints] = {};
            bool matched[kMaxManifoldPoints] = {};
            for (int i = 0; i < now.pointCount; ++i)
                for (int j = 0; j < old.pointCount; ++j)
                    if (!taken[j] && now.points[i].feature == old.features[j]) {
                        impulses[m * kMaxManifoldPoints + i] = old.impulses[j];
                        taken[j] = matched[i] = true;
                        ++points;
                        break;
                    }
            for (int i = 0; i < now.pointCount; ++i) {
                if (matched[i]) continue;
                int best = -1;
                float bestDistanceSq = kContactMatchDistance * kContactMatchDistance;
                for (int j = 0; j < old.pointCount; ++j) {
                    const Vec3 d = now.points[i].position - old.positions[j];
                    const float distanceSq = dot(d, d);
                    if (!taken[j] && distanceSq < bestDistanceSq) best = j, bestDistanceSq = distanceSq;
                }
                if (best < 0) continue;
                impulses[m * kMaxManifoldPoints + i] = old.impulses[best];
                taken[best] = true;
                ++points;
            }
        }
        chunkManifolds[chunk] = manifolds;
        chunkPoints[chunk] = points;
    });
    matchedManifolds_ = matchedPoints_ = 0;
    for (std::size_t c = 0; c < chunkManifolds.size(); ++c)
        matchedManifolds_ += chunkManifolds[c], matchedPoints_ += chunkPoints[c];
}

void ContactCache::remember(const Contacts& contacts, const std::vector<PointImpulse>& impulses, TaskPool& pool) {
    const std::size_t n = contacts.manifolds.size();
    previous_.resize(n);
    std::size_t size = 16;
    while (size < 2 * n) size *= 2;
    table_.assign(size, 0);
    const std::size_t mask = size - 1;
    pool.forChunks(n, kChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t m = begin; m < end; ++m) {
            Entry& e = previous_[m];
            e.key = currentKeys_[m];
            e.pointCount = contacts.manifolds[m].pointCount;
            for (int i = 0; i < e.pointCount; ++i) {
                e.features[i] = contacts.manifolds[m].points[i].feature;
                e.positions[i] = contacts.manifolds[m].points[i].position;
                e.impulses[i] = impulses[m * kMaxManifoldPoints + i];
            }
            // Claim the first free cell of the probe sequence. Which cell a key ends up in may depend on the
            // threads' timing, but every key is in the table exactly once, so every lookup finds the same entry.
            for (std::size_t at = hashOf(e.key) & mask;; at = (at + 1) & mask) {
                std::uint32_t expected = 0;
                if (std::atomic_ref<std::uint32_t>(table_[at])
                        .compare_exchange_strong(expected, static_cast<std::uint32_t>(m + 1),
                                                 std::memory_order_relaxed))
                    break;
            }
        }
    });
}

void ContactCache::restoreIntoStep(std::span<const KeptManifold> kept, const BodyStorage& storage, Contacts& contacts,
                                   std::vector<PointImpulse>& impulses) {
    const auto& slots = storage.slots();
    for (const KeptManifold& k : kept) {
        ContactPair pair = k.pair;
        pair.a = slots[pair.a].dense;
        pair.b = slots[pair.b].dense;
        contacts.pairs.push_back(pair);
        contacts.manifolds.push_back(k.manifold);
        contacts.pointCount += static_cast<std::uint32_t>(k.manifold.pointCount);
        impulses.insert(impulses.end(), std::begin(k.impulses), std::end(k.impulses));
        currentKeys_.push_back(k.key);
    }
}

void ContactCache::restoreForWarmStart(std::span<const KeptManifold> kept) {
    for (const KeptManifold& k : kept) {
        Entry& e = previous_.emplace_back();
        e.key = k.key;
        e.pointCount = k.manifold.pointCount;
        for (int i = 0; i < e.pointCount; ++i) {
            e.features[i] = k.manifold.points[i].feature;
            e.positions[i] = k.manifold.points[i].position;
            e.impulses[i] = k.impulses[i];
        }
    }
    rebuildTable();
}

void ContactCache::rebuildTable() {
    std::size_t size = 16;
    while (size < 2 * previous_.size()) size *= 2;
    table_.assign(size, 0);
    const std::size_t mask = size - 1;
    for (std::size_t m = 0; m < previous_.size(); ++m) {
        std::size_t at = hashOf(previous_[m].key) & mask;
        while (table_[at] != 0) at = (at + 1) & mask;
        table_[at] = static_cast<std::uint32_t>(m + 1);
    }
}

void ContactCache::partnersOf(std::uint32_t slot, std::vector<std::uint32_t>& out) const {
    for (const Entry& e : previous_) {
        const auto a = static_cast<std::uint32_t>(e.key.slots >> 32), b = static_cast<std::uint32_t>(e.key.slots);
        if (a == slot) out.push_back(b);
        if (b == slot) out.push_back(a);
    }
}

}  // namespace rubble::detail
