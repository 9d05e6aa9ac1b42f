#include "islands/islands.h"

#include <algorithm>
#include <atomic>

#include "core/parallel.h"

namespace rubble::detail {
namespace {

constexpr std::size_t kBodyChunk = 4096;
constexpr std::size_t kEdgeChunk = 2048;
constexpr std::size_t kIslandChunk = 4096;

std::uint32_t load(std::vector<std::uint32_t>& parent, std::uint32_t i) {
    return std::atomic_ref<std::uint32_t>(parent[i]).load(std::memory_order_relaxed);
}

/// Root of x with path halving. Parents only ever point at smaller indices of the same set, so a value read late or
/// overwritten by another thread's halving is still an ancestor: every path ends at the root, and no cycle can form.
std::uint32_t findConcurrent(std::vector<std::uint32_t>& parent, std::uint32_t x) {
    for (;;) {
        const std::uint32_t p = load(parent, x);
        if (p == x) return x;
        const std::uint32_t g = load(parent, p);
        if (g == p) return p;
        std::atomic_ref<std::uint32_t>(parent[x]).store(g, std::memory_order_relaxed);
        x = g;
    }
}

/// Links the two sets, the larger root under the smaller. Only a root is ever re-parented, and only by a CAS that
/// sees it still a root, so two threads linking the same root cannot both succeed; a failed CAS retries from the
/// new roots. Sets only ever merge, so "same root" read at any moment is final.
void uniteConcurrent(std::vector<std::uint32_t>& parent, std::uint32_t a, std::uint32_t b) {
    for (;;) {
        a = findConcurrent(parent, a);
        b = findConcurrent(parent, b);
        if (a == b) return;
        if (a < b) std::swap(a, b);
        std::uint32_t expected = a;
        if (std::atomic_ref<std::uint32_t>(parent[a]).compare_exchange_weak(expected, b, std::memory_order_relaxed))
            return;
    }
}

std::uint32_t findSerial(std::vector<std::uint32_t>& parent, std::uint32_t x) {
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

/// The edge of edge number e (manifolds first, then the extra edges), or false when it joins nothing: a side is
/// static, kinematic or frozen.
bool edgeOf(std::size_t e, const Contacts& contacts, std::span<const IslandEdge> extra, const MovingBodies& bodies,
            std::uint32_t& a, std::uint32_t& b) {
    if (e < contacts.pairs.size()) {
        const ContactPair& p = contacts.pairs[e];
        if (p.aStatic || p.bStatic) return false;
        a = p.a, b = p.b;
    } else {
        const IslandEdge& x = extra[e - contacts.pairs.size()];
        a = x.first, b = x.second;
    }
    return joinsIslands(bodies.flags[a]) && joinsIslands(bodies.flags[b]);
}

std::uint32_t islandOfManifold(const ContactPair& p, const std::vector<std::uint32_t>& islandOf) {
    if (!p.aStatic && islandOf[p.a] != kNoIsland) return islandOf[p.a];
    if (!p.bStatic && islandOf[p.b] != kNoIsland) return islandOf[p.b];
    return kNoIsland;
}

/// Rows by a counting sort: items visited in index order land in index order within their island. One pass to
/// count, one to place; measured faster than a parallel radix sort of (island, index) keys at every size tried
/// (perf/islands_perf.cpp), since the items are already in index order and the counts fit in cache.
template <class IslandOf>
void countingSort(std::uint32_t islands, std::size_t items, IslandOf&& islandOf, std::vector<std::uint32_t>& starts,
                  std::vector<std::uint32_t>& rows) {
    starts.assign(std::size_t{islands} + 1, 0);
    for (std::size_t x = 0; x < items; ++x)
        if (const std::uint32_t k = islandOf(x); k != kNoIsland) starts[k + 1] += 1;
    for (std::uint32_t k = 0; k < islands; ++k) starts[k + 1] += starts[k];
    rows.resize(starts[islands]);
    for (std::size_t x = 0; x < items; ++x)
        if (const std::uint32_t k = islandOf(x); k != kNoIsland) rows[starts[k]++] = static_cast<std::uint32_t>(x);
    // Placing advanced each start to the next island's: shift back.
    for (std::uint32_t k = islands; k > 0; --k) starts[k] = starts[k - 1];
    starts[0] = 0;
}

}  // namespace

void IslandBuilder::build(const Contacts& contacts, std::span<const IslandEdge> extraEdges, const MovingBodies& bodies,
                          TaskPool& pool, Islands& out) {
    const std::size_t n = bodies.size();
    parent_.resize(n);
    rank_.resize(n);
    out.islandOf.resize(n);
    pool.forChunks(n, kBodyChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) parent_[i] = static_cast<std::uint32_t>(i);
    });
    const std::size_t edges = contacts.pairs.size() + extraEdges.size();
    pool.forChunks(edges, kEdgeChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t e = begin; e < end; ++e) {
            std::uint32_t a, b;
            if (edgeOf(e, contacts, extraEdges, bodies, a, b)) uniteConcurrent(parent_, a, b);
        }
    });

    // Number the roots in index order: per-chunk root counts, prefix-summed by one thread.
    const std::size_t chunks = TaskPool::chunkCount(n, kBodyChunk);
    chunkCounts_.assign(chunks, 0);
    pool.forChunks(n, kBodyChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::uint32_t roots = 0;
        for (std::size_t i = begin; i < end; ++i) {
            if (!joinsIslands(bodies.flags[i])) {
                out.islandOf[i] = kNoIsland;
                continue;
            }
            const std::uint32_t r = findConcurrent(parent_, static_cast<std::uint32_t>(i));
            out.islandOf[i] = r;
            roots += r == i;
        }
        chunkCounts_[c] = roots;
    });
    std::uint32_t islands = 0;
    for (std::size_t c = 0; c < chunks; ++c) {
        const std::uint32_t roots = chunkCounts_[c];
        chunkCounts_[c] = islands;
        islands += roots;
    }
    pool.forChunks(n, kBodyChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::uint32_t next = chunkCounts_[c];
        for (std::size_t i = begin; i < end; ++i)
            if (out.islandOf[i] == i) rank_[i] = next++;
    });
    pool.forChunks(n, kBodyChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i)
            if (out.islandOf[i] != kNoIsland) out.islandOf[i] = rank_[out.islandOf[i]];
    });
    countingSort(
        islands, n, [&](std::size_t i) { return out.islandOf[i]; }, out.bodyStart, out.bodies);

    std::vector<std::uint32_t>& largest = chunkCounts_;
    largest.assign(TaskPool::chunkCount(islands, kIslandChunk), 0);
    pool.forChunks(islands, kIslandChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::uint32_t most = 0;
        for (std::size_t k = begin; k < end; ++k) most = std::max(most, out.bodyStart[k + 1] - out.bodyStart[k]);
        largest[c] = most;
    });
    out.largest = largest.empty() ? 0 : *std::max_element(largest.begin(), largest.end());

    assignManifolds(contacts, out);
}

void IslandBuilder::assignManifolds(const Contacts& contacts, Islands& out) {
    countingSort(
        out.count(), contacts.pairs.size(),
        [&](std::size_t m) { return islandOfManifold(contacts.pairs[m], out.islandOf); }, out.manifoldStart,
        out.manifolds);
}

void IslandBuilder::buildSerial(const Contacts& contacts, std::span<const IslandEdge> extraEdges,
                                const MovingBodies& bodies, Islands& out) {
    const std::uint32_t n = bodies.size();
    std::vector<std::uint32_t> parent(n);
    for (std::uint32_t i = 0; i < n; ++i) parent[i] = i;
    const std::size_t edges = contacts.pairs.size() + extraEdges.size();
    for (std::size_t e = 0; e < edges; ++e) {
        std::uint32_t a, b;
        if (!edgeOf(e, contacts, extraEdges, bodies, a, b)) continue;
        a = findSerial(parent, a), b = findSerial(parent, b);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
    // A root is its set's smallest index, so scanning up meets every root before the rest of its island.
    out.islandOf.assign(n, kNoIsland);
    std::vector<std::uint32_t> size;
    for (std::uint32_t i = 0; i < n; ++i) {
        if (!joinsIslands(bodies.flags[i])) continue;
        const std::uint32_t r = findSerial(parent, i);
        if (r == i) {
            out.islandOf[i] = static_cast<std::uint32_t>(size.size());
            size.push_back(0);
        } else {
            out.islandOf[i] = out.islandOf[r];
        }
        size[out.islandOf[i]] += 1;
    }
    out.largest = size.empty() ? 0 : *std::max_element(size.begin(), size.end());
    countingSort(
        static_cast<std::uint32_t>(size.size()), n, [&](std::size_t i) { return out.islandOf[i]; }, out.bodyStart,
        out.bodies);
    countingSort(
        static_cast<std::uint32_t>(size.size()), contacts.pairs.size(),
        [&](std::size_t m) { return islandOfManifold(contacts.pairs[m], out.islandOf); }, out.manifoldStart,
        out.manifolds);
}

}  // namespace rubble::detail
