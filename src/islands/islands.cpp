#include "islands/islands.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <utility>

#include "core/parallel.h"

namespace rubble::detail {
namespace {

constexpr std::size_t kBodyChunk = 4096;
constexpr std::size_t kEdgeChunk = 2048;
constexpr std::size_t kIslandChunk = 4096;
/// The constrained bodies are sorted when the edges' sides are fewer than one per this many bodies, else read off
/// their marks in a pass over all bodies.
constexpr std::size_t kSortedListShare = 16;

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
/// Returns the root it linked the other under, or kNoIsland when the two were already one set.
std::uint32_t uniteConcurrent(std::vector<std::uint32_t>& parent, std::uint32_t a, std::uint32_t b) {
    for (;;) {
        a = findConcurrent(parent, a);
        b = findConcurrent(parent, b);
        if (a == b) return kNoIsland;
        if (a < b) std::swap(a, b);
        std::uint32_t expected = a;
        if (std::atomic_ref<std::uint32_t>(parent[a]).compare_exchange_weak(expected, b, std::memory_order_relaxed))
            return b;
    }
}

std::uint32_t findSerial(std::vector<std::uint32_t>& parent, std::uint32_t x) {
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

/// The two sides of edge number e (manifolds first, then the extra edges), and whether each joins islands: a moving
/// body that is neither kinematic nor frozen. Only an edge whose sides both join links them; a side that joins is
/// constrained either way.
struct EdgeSides {
    std::uint32_t a = 0, b = 0;
    bool aJoins = false, bJoins = false;
};

[[gnu::always_inline]] inline EdgeSides sidesOf(std::size_t e, const Contacts& contacts,
                                                std::span<const IslandEdge> extra, const MovingBodies& bodies) {
    EdgeSides s;
    if (e < contacts.pairs.size()) {
        const ContactPair& p = contacts.pairs[e];
        s.a = p.a, s.b = p.b;
        s.aJoins = !p.aStatic && joinsIslands(bodies.flags[p.a]);
        s.bJoins = !p.bStatic && joinsIslands(bodies.flags[p.b]);
    } else {
        const IslandEdge& x = extra[e - contacts.pairs.size()];
        s.a = x.first, s.b = x.second;
        s.aJoins = joinsIslands(bodies.flags[s.a]);
        s.bJoins = joinsIslands(bodies.flags[s.b]);
    }
    return s;
}

std::uint32_t islandOfManifold(const ContactPair& p, const std::vector<std::uint32_t>& islandOf) {
    if (!p.aStatic && islandOf[p.a] != kNoIsland) return islandOf[p.a];
    if (!p.bStatic && islandOf[p.b] != kNoIsland) return islandOf[p.b];
    return kNoIsland;
}

/// While a build runs, islandOf marks the constrained bodies with this until their island is known.
constexpr std::uint32_t kListed = kNoIsland - 1;

/// Rows by a counting sort: items visited in order land in that order within their island (value(x) is what lands).
/// One pass to count, one to place; measured faster than a parallel radix sort of (island, index) keys at every size
/// tried (perf/islands_perf.cpp), since the items are already in index order and the counts fit in cache.
template <class IslandOf, class Value>
void countingSort(std::uint32_t islands, std::size_t items, IslandOf&& islandOf, Value&& value,
                  std::vector<std::uint32_t>& starts, std::vector<std::uint32_t>& rows) {
    starts.assign(std::size_t{islands} + 1, 0);
    for (std::size_t x = 0; x < items; ++x)
        if (const std::uint32_t k = islandOf(x); k != kNoIsland) starts[k + 1] += 1;
    for (std::uint32_t k = 0; k < islands; ++k) starts[k + 1] += starts[k];
    rows.resize(starts[islands]);
    for (std::size_t x = 0; x < items; ++x)
        if (const std::uint32_t k = islandOf(x); k != kNoIsland) rows[starts[k]++] = value(x);
    // Placing advanced each start to the next island's: shift back.
    for (std::uint32_t k = islands; k > 0; --k) starts[k] = starts[k - 1];
    starts[0] = 0;
}

std::uint32_t itself(std::size_t x) { return static_cast<std::uint32_t>(x); }

}  // namespace

void IslandBuilder::build(const Contacts& contacts, std::span<const IslandEdge> extraEdges, const MovingBodies& bodies,
                          TaskPool& pool, Islands& out) {
    const std::uint32_t n = bodies.size();
    // Undo the last build, whose bodies alone hold a parent or an island (bodies may have moved or gone since: the
    // entries are reset whoever holds them now).
    const std::size_t undo = std::max(members_.size(), out.bodies.size());
    pool.forChunks(undo, kBodyChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t k = begin; k < std::min(end, members_.size()); ++k)
            if (const std::uint32_t i = members_[k]; i < parent_.size()) parent_[i] = i;
        for (std::size_t k = begin; k < std::min(end, out.bodies.size()); ++k)
            if (const std::uint32_t i = out.bodies[k]; i < out.islandOf.size()) out.islandOf[i] = kNoIsland;
    });
    for (auto i = static_cast<std::uint32_t>(parent_.size()); i < n; ++i) parent_.push_back(i);
    parent_.resize(n);
    rank_.resize(n);
    out.islandOf.resize(n, kNoIsland);

    // One pass over the edges links the constrained bodies and lists them. When they can only be few, each chunk
    // lists the sides it meets (repeats included) to be sorted. Else the list is read off in one pass over the bodies,
    // cheaper than sorting most of them: a body is constrained if it got a parent, or if islandOf marks it, which only
    // the roots that took another set in and the sides of edges that link nothing need. Both give the same list.
    const std::size_t edges = contacts.pairs.size() + extraEdges.size();
    const bool sortSides = 2 * edges * kSortedListShare < n;
    chunkMembers_.resize(TaskPool::chunkCount(edges, kEdgeChunk));
    const auto markListed = [&](std::uint32_t i) {  // every thread that marks a body writes the same value
        std::atomic_ref<std::uint32_t>(out.islandOf[i]).store(kListed, std::memory_order_relaxed);
    };
    // The choice is made once per chunk, not per edge: the loop is this stage's hot path in dense scenes.
    const auto linkChunk = [&]<bool kListSides>(std::size_t begin, std::size_t end, std::vector<std::uint32_t>& sides) {
        for (std::size_t e = begin; e < end; ++e) {
            const EdgeSides s = sidesOf(e, contacts, extraEdges, bodies);
            if constexpr (kListSides) {
                if (s.aJoins) sides.push_back(s.a);
                if (s.bJoins) sides.push_back(s.b);
                if (s.aJoins && s.bJoins) uniteConcurrent(parent_, s.a, s.b);
            } else if (s.aJoins && s.bJoins) {
                // An edge from a body to itself links nothing, and leaves the body unmarked unless marked here.
                const std::uint32_t root = uniteConcurrent(parent_, s.a, s.b);
                if (root != kNoIsland || s.a == s.b) markListed(root != kNoIsland ? root : s.a);
            } else {
                if (s.aJoins) markListed(s.a);
                if (s.bJoins) markListed(s.b);
            }
        }
    };
    pool.forChunks(edges, kEdgeChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::vector<std::uint32_t>& sides = chunkMembers_[c];
        sides.clear();
        if (sortSides)
            linkChunk.template operator()<true>(begin, end, sides);
        else
            linkChunk.template operator()<false>(begin, end, sides);
    });
    if (sortSides) {
        sortItems_.clear();
        for (const std::vector<std::uint32_t>& chunk : chunkMembers_)
            sortItems_.insert(sortItems_.end(), chunk.begin(), chunk.end());
        radixSortBits(sortItems_.data(), sortItems_.size(), 0, std::bit_width(n), sortScratch_, pool);
        sortItems_.erase(std::unique(sortItems_.begin(), sortItems_.end()), sortItems_.end());
        members_.assign(sortItems_.begin(), sortItems_.end());
    } else {
        // Chunks of bodies count theirs, then each writes its own at the offset the counts give.
        chunkCounts_.assign(TaskPool::chunkCount(n, kBodyChunk), 0);
        pool.forChunks(n, kBodyChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
            std::uint32_t marks = 0;
            for (std::size_t i = begin; i < end; ++i) marks += parent_[i] != i || out.islandOf[i] == kListed;
            chunkCounts_[c] = marks;
        });
        std::uint32_t offset = 0;
        for (std::uint32_t& count : chunkCounts_) offset += std::exchange(count, offset);
        members_.resize(offset);
        pool.forChunks(n, kBodyChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
            std::uint32_t at = chunkCounts_[c];
            for (std::size_t i = begin; i < end; ++i)
                if (parent_[i] != i || out.islandOf[i] == kListed) members_[at++] = static_cast<std::uint32_t>(i);
        });
    }
    const std::size_t listed = members_.size();

    // Number the roots in index order: per-chunk root counts, prefix-summed by one thread.
    const std::size_t chunks = TaskPool::chunkCount(listed, kBodyChunk);
    chunkCounts_.assign(chunks, 0);
    pool.forChunks(listed, kBodyChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::uint32_t roots = 0;
        for (std::size_t k = begin; k < end; ++k) {
            const std::uint32_t i = members_[k];
            const std::uint32_t r = findConcurrent(parent_, i);
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
    pool.forChunks(listed, kBodyChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::uint32_t next = chunkCounts_[c];
        for (std::size_t k = begin; k < end; ++k)
            if (const std::uint32_t i = members_[k]; out.islandOf[i] == i) rank_[i] = next++;
    });
    pool.forChunks(listed, kBodyChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t k = begin; k < end; ++k) out.islandOf[members_[k]] = rank_[out.islandOf[members_[k]]];
    });
    countingSort(
        islands, listed, [&](std::size_t k) { return out.islandOf[members_[k]]; },
        [&](std::size_t k) { return members_[k]; }, out.bodyStart, out.bodies);

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
        [&](std::size_t m) { return islandOfManifold(contacts.pairs[m], out.islandOf); }, itself, out.manifoldStart,
        out.manifolds);
}

void IslandBuilder::buildSerial(const Contacts& contacts, std::span<const IslandEdge> extraEdges,
                                const MovingBodies& bodies, Islands& out) {
    const std::uint32_t n = bodies.size();
    std::vector<std::uint32_t> parent(n);
    for (std::uint32_t i = 0; i < n; ++i) parent[i] = i;
    std::vector<std::uint8_t> constrained(n, 0);
    const std::size_t edges = contacts.pairs.size() + extraEdges.size();
    for (std::size_t e = 0; e < edges; ++e) {
        const EdgeSides s = sidesOf(e, contacts, extraEdges, bodies);
        if (s.aJoins) constrained[s.a] = 1;
        if (s.bJoins) constrained[s.b] = 1;
        if (!s.aJoins || !s.bJoins) continue;
        const std::uint32_t a = findSerial(parent, s.a), b = findSerial(parent, s.b);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
    // A root is its set's smallest index, so scanning up meets every root before the rest of its island.
    out.islandOf.assign(n, kNoIsland);
    std::vector<std::uint32_t> size;
    for (std::uint32_t i = 0; i < n; ++i) {
        if (!constrained[i]) continue;
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
        static_cast<std::uint32_t>(size.size()), n, [&](std::size_t i) { return out.islandOf[i]; }, itself,
        out.bodyStart, out.bodies);
    countingSort(
        static_cast<std::uint32_t>(size.size()), contacts.pairs.size(),
        [&](std::size_t m) { return islandOfManifold(contacts.pairs[m], out.islandOf); }, itself, out.manifoldStart,
        out.manifolds);
}

}  // namespace rubble::detail
