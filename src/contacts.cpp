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
    const std::size_t chunks = TaskPool::chunkCount(n, kChunk);
    chunkMatches_.assign(chunks, {});
    chunkMisses_.resize(chunks);
    const auto& slots = storage.slots();
    // Manifolds come in canonical order, which changes little from step to step: each chunk tries last step's
    // entry at its own first index, then always the entry after the last match, so a settled scene reads last
    // step's entries in order. Only the manifolds that guess misses look in the hash table, which is built for
    // them alone: a settled scene builds none.
    pool.forChunks(n, kChunk, [&](std::size_t chunk, std::size_t begin, std::size_t end, int) {
        std::fill(impulses.begin() + begin * kMaxManifoldPoints, impulses.begin() + end * kMaxManifoldPoints,
                  PointImpulse{});
        std::vector<std::uint32_t>& misses = chunkMisses_[chunk];
        misses.clear();
        std::size_t next = begin;
        for (std::size_t m = begin; m < end; ++m) {
            const ContactPair& p = contacts.pairs[m];
            const std::uint32_t slotA = slotOf(storage, p.a, p.aStatic), slotB = slotOf(storage, p.b, p.bStatic);
            ContactKey key;
            key.slots = (std::uint64_t{slotA} << 32) | slotB;
            key.generations = (std::uint64_t{slots[slotA].generation} << 32) | slots[slotB].generation;
            key.parts = (std::uint64_t{p.triangle} << 32) | (std::uint64_t{p.childA} << 16) | p.childB;
            currentKeys_[m] = key;
            if (previous_.empty()) continue;
            if (next < previous_.size() && previous_[next].key == key) {
                carry(contacts.manifolds[m], previous_[next], &impulses[m * kMaxManifoldPoints], chunkMatches_[chunk]);
                ++next;
            } else {
                misses.push_back(static_cast<std::uint32_t>(m));
            }
        }
    });
    std::size_t missCount = 0;
    for (const std::vector<std::uint32_t>& misses : chunkMisses_) missCount += misses.size();
    if (missCount > 0) {
        if (!tableValid_) rebuildTable(pool);
        const std::size_t mask = table_.size() - 1;
        pool.forChunks(chunks, 1, [&](std::size_t chunk, std::size_t, std::size_t, int) {
            for (const std::uint32_t m : chunkMisses_[chunk]) {
                const ContactKey& key = currentKeys_[m];
                // Linear probing in a table at most half full: a miss ends at the first empty cell.
                for (std::size_t at = hashOf(key) & mask;; at = (at + 1) & mask) {
                    const std::uint32_t entry = table_[at];
                    if (entry == 0) break;
                    if (previous_[entry - 1].key == key) {
                        carry(contacts.manifolds[m], previous_[entry - 1],
                              &impulses[std::size_t{m} * kMaxManifoldPoints], chunkMatches_[chunk]);
                        break;
                    }
                }
            }
        });
    }
    matchedManifolds_ = matchedPoints_ = 0;
    for (const Matches& c : chunkMatches_) matchedManifolds_ += c.manifolds, matchedPoints_ += c.points;
}

void ContactCache::carry(const Manifold& now, const Entry& old, PointImpulse* out, Matches& matches) {
    ++matches.manifolds;
    bool taken[kMaxManifoldPoints] = {};
    bool matched[kMaxManifoldPoints] = {};
    for (int i = 0; i < now.pointCount; ++i)
        for (int j = 0; j < old.pointCount; ++j)
            if (!taken[j] && now.points[i].feature == old.features[j]) {
                out[i] = old.impulses[j];
                taken[j] = matched[i] = true;
                ++matches.points;
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
        out[i] = old.impulses[best];
        taken[best] = true;
        ++matches.points;
    }
}

void ContactCache::remember(const Contacts& contacts, const std::vector<PointImpulse>& impulses, TaskPool& pool) {
    const std::size_t n = contacts.manifolds.size();
    previous_.resize(n);
    tableValid_ = false;
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
    tableValid_ = false;
}

void ContactCache::rebuildTable(TaskPool& pool) {
    std::size_t size = 16;
    while (size < 2 * previous_.size()) size *= 2;
    table_.assign(size, 0);
    const std::size_t mask = size - 1;
    pool.forChunks(previous_.size(), kChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t m = begin; m < end; ++m) {
            // Claim the first free cell of the probe sequence. Which cell a key ends up in may depend on the
            // threads' timing, but every key is in the table exactly once, so every lookup finds the same entry.
            for (std::size_t at = hashOf(previous_[m].key) & mask;; at = (at + 1) & mask) {
                std::uint32_t expected = 0;
                if (std::atomic_ref<std::uint32_t>(table_[at])
                        .compare_exchange_strong(expected, static_cast<std::uint32_t>(m + 1),
                                                 std::memory_order_relaxed))
                    break;
            }
        }
    });
    tableValid_ = true;
}

void ContactCache::partnersOf(std::uint32_t slot, std::vector<std::uint32_t>& out) const {
    for (const Entry& e : previous_) {
        const auto a = static_cast<std::uint32_t>(e.key.slots >> 32), b = static_cast<std::uint32_t>(e.key.slots);
        if (a == slot) out.push_back(b);
        if (b == slot) out.push_back(a);
    }
}

}  // namespace rubble::detail
