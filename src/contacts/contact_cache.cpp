#include "contacts/contact_cache.h"

#include <algorithm>
#include <atomic>

#include "core/parallel.h"

namespace rubble::detail {
namespace {

constexpr std::size_t kChunk = 1024;
/// How many of last step's entries the in-order guess looks at: pairs that separated leave gaps this wide.
constexpr std::size_t kLookahead = 8;
/// Misses times unmatched entries up to which they are compared directly instead of through the hash table.
constexpr std::size_t kDirectSearchPairs = std::size_t{1} << 16;

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
    carried_.resize(n);
    impulses.resize(n * kMaxManifoldPoints);
    const std::size_t chunks = TaskPool::chunkCount(n, kChunk);
    chunkMatches_.assign(chunks, {});
    chunkMisses_.resize(chunks);
    previousMatched_.assign(previous_.size(), 0);
    // Manifolds come in canonical order, which changes little from step to step: each chunk tries last step's
    // entries from its own first index, then from the entry after the last match, so a settled scene reads last
    // step's entries in order. Only the manifolds the guess misses are looked up afterwards, among the entries it
    // left (directly when both are few, else through the hash table): a settled scene builds no table.
    pool.forChunks(n, kChunk, [&](std::size_t chunk, std::size_t begin, std::size_t end, int) {
        std::fill(impulses.begin() + begin * kMaxManifoldPoints, impulses.begin() + end * kMaxManifoldPoints,
                  PointImpulse{});
        std::fill(carried_.begin() + begin, carried_.begin() + end, std::uint8_t{0});
        std::vector<std::uint32_t>& misses = chunkMisses_[chunk];
        misses.clear();
        // The window starts a little before the chunk's own index: manifolds new since last step shift it back.
        std::size_t next = begin > kLookahead ? begin - kLookahead : 0, window = 2 * kLookahead;
        for (std::size_t m = begin; m < end; ++m) {
            const ContactPair& p = contacts.pairs[m];
            const std::uint32_t slotA = slotOf(storage, p.a, p.aStatic), slotB = slotOf(storage, p.b, p.bStatic);
            ContactKey key;
            key.slots = (std::uint64_t{slotA} << 32) | slotB;
            key.generations = (std::uint64_t{storage.idAt(slotA).generation} << 32) | storage.idAt(slotB).generation;
            key.parts = (std::uint64_t{p.triangle} << 32) | (std::uint64_t{p.childA} << 16) | p.childB;
            currentKeys_[m] = key;
            if (previous_.empty()) continue;
            // A manifold new this step misses and leaves the guess where it was; entries of pairs that separated
            // are skipped by looking a few entries ahead.
            std::size_t at = next;
            const std::size_t last = std::min(previous_.size(), next + window);
            while (at < last && !(previous_[at].key == key)) ++at;
            if (at < last) {
                carry(contacts.manifolds[m], previous_[at], &impulses[m * kMaxManifoldPoints], carried_[m],
                      chunkMatches_[chunk]);
                // Relaxed: each entry is taken by one manifold at most (keys are unique), the flag only says so.
                std::atomic_ref<std::uint8_t>(previousMatched_[at]).store(1, std::memory_order_relaxed);
                next = at + 1;
                window = kLookahead;
            } else {
                misses.push_back(static_cast<std::uint32_t>(m));
            }
        }
    });
    std::size_t missCount = 0;
    for (const std::vector<std::uint32_t>& misses : chunkMisses_) missCount += misses.size();
    if (missCount > 0) {
        // Only last step's entries the in-order pass did not take can match now. When those and the misses are few
        // (a settled scene: pairs that came and went), comparing them all costs less than a table.
        unmatched_.clear();
        for (std::size_t e = 0; e < previous_.size(); ++e)
            if (!previousMatched_[e]) unmatched_.push_back(static_cast<std::uint32_t>(e));
        if (missCount * unmatched_.size() <= kDirectSearchPairs) {
            for (std::size_t chunk = 0; chunk < chunks; ++chunk)
                for (const std::uint32_t m : chunkMisses_[chunk])
                    for (const std::uint32_t e : unmatched_)
                        if (previous_[e].key == currentKeys_[m]) {
                            carry(contacts.manifolds[m], previous_[e], &impulses[std::size_t{m} * kMaxManifoldPoints],
                                  carried_[m], chunkMatches_[chunk]);
                            break;
                        }
            missCount = 0;
        }
    }
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
                              &impulses[std::size_t{m} * kMaxManifoldPoints], carried_[m], chunkMatches_[chunk]);
                        break;
                    }
                }
            }
        });
    }
    matchedManifolds_ = matchedPoints_ = 0;
    for (const Matches& c : chunkMatches_) matchedManifolds_ += c.manifolds, matchedPoints_ += c.points;
}

void ContactCache::carry(const Manifold& now, const Entry& old, PointImpulse* out, std::uint8_t& carried,
                         Matches& matches) {
    ++matches.manifolds;
    const std::uint32_t pointsBefore = matches.points;
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
    if (matches.points != pointsBefore) carried = 1;
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

}  // namespace rubble::detail
