// The islands stage against a second algorithm: breadth-first search over the same graph gives the components, and
// the canonical labels and rows follow from them directly. The parallel union-find must match it exactly, on any
// thread count, with static, kinematic and frozen bodies in the graph and with extra (joint) edges. Only constrained
// bodies (a side of a manifold or an extra edge) are in islands.
#include <gtest/gtest.h>

#include <algorithm>
#include <queue>
#include <random>

#include "core/parallel.h"
#include "islands/islands.h"

namespace rubble::detail {
namespace {

struct Graph {
    MovingBodies bodies;
    Contacts contacts;
    std::vector<IslandEdge> extra;
};

/// n moving bodies (about one in ten kinematic, one in fifty frozen), m manifolds of which a fifth touch a static
/// body, and e extra edges. Edges mostly join near indices, so that islands of many sizes form.
Graph randomGraph(std::uint32_t n, std::uint32_t m, std::uint32_t e, std::uint32_t seed) {
    std::mt19937 rng(seed);
    Graph g;
    for (std::uint32_t i = 0; i < n; ++i) {
        g.bodies.pushBack();
        const std::uint32_t r = rng() % 100;
        g.bodies.flags[i] = r < 10 ? kFlagKinematic : r < 12 ? kFlagFrozen : r < 20 ? kFlagAsleep : 0;
    }
    const auto near = [&](std::uint32_t a) {
        const std::uint32_t span = (rng() % 4 == 0) ? n : 8;
        return std::min(n - 1, a + static_cast<std::uint32_t>(rng() % span));
    };
    for (std::uint32_t k = 0; k < m; ++k) {
        ContactPair p;
        p.a = rng() % n;
        p.b = near(p.a);
        if (rng() % 5 == 0) {
            (rng() % 2 ? p.aStatic : p.bStatic) = true;
        }
        if (p.a == p.b && !p.aStatic && !p.bStatic) p.bStatic = true;
        g.contacts.pairs.push_back(p);
        g.contacts.manifolds.emplace_back();
    }
    for (std::uint32_t k = 0; k < e; ++k) {
        const std::uint32_t a = rng() % n;
        g.extra.emplace_back(a, near(a));
    }
    return g;
}

/// Components by breadth-first search, labelled as the stage promises.
Islands bruteForce(const Graph& g) {
    const std::uint32_t n = g.bodies.size();
    std::vector<std::vector<std::uint32_t>> adjacent(n);
    const auto joins = [&](std::uint32_t i) { return joinsIslands(g.bodies.flags[i]); };
    for (const ContactPair& p : g.contacts.pairs)
        if (!p.aStatic && !p.bStatic && joins(p.a) && joins(p.b))
            adjacent[p.a].push_back(p.b), adjacent[p.b].push_back(p.a);
    for (const auto& [a, b] : g.extra)
        if (joins(a) && joins(b)) adjacent[a].push_back(b), adjacent[b].push_back(a);
    std::vector<bool> constrained(n, false);
    for (const ContactPair& p : g.contacts.pairs) {
        if (!p.aStatic) constrained[p.a] = true;
        if (!p.bStatic) constrained[p.b] = true;
    }
    for (const auto& [a, b] : g.extra) constrained[a] = constrained[b] = true;
    Islands out;
    out.islandOf.assign(n, kNoIsland);
    std::vector<std::vector<std::uint32_t>> members;
    for (std::uint32_t s = 0; s < n; ++s) {
        if (!joins(s) || !constrained[s] || out.islandOf[s] != kNoIsland) continue;
        const auto k = static_cast<std::uint32_t>(members.size());
        members.emplace_back();
        std::queue<std::uint32_t> open;
        open.push(s);
        out.islandOf[s] = k;
        while (!open.empty()) {
            const std::uint32_t x = open.front();
            open.pop();
            members[k].push_back(x);
            for (std::uint32_t y : adjacent[x])
                if (out.islandOf[y] == kNoIsland) out.islandOf[y] = k, open.push(y);
        }
        std::sort(members[k].begin(), members[k].end());
    }
    out.bodyStart.push_back(0);
    for (const auto& row : members) {
        out.bodies.insert(out.bodies.end(), row.begin(), row.end());
        out.bodyStart.push_back(static_cast<std::uint32_t>(out.bodies.size()));
        out.largest = std::max(out.largest, static_cast<std::uint32_t>(row.size()));
    }
    std::vector<std::vector<std::uint32_t>> manifolds(members.size());
    for (std::uint32_t c = 0; c < g.contacts.pairs.size(); ++c) {
        const ContactPair& p = g.contacts.pairs[c];
        std::uint32_t k = kNoIsland;
        if (!p.aStatic && joins(p.a))
            k = out.islandOf[p.a];
        else if (!p.bStatic && joins(p.b))
            k = out.islandOf[p.b];
        if (k != kNoIsland) manifolds[k].push_back(c);
    }
    out.manifoldStart.push_back(0);
    for (const auto& row : manifolds) {
        out.manifolds.insert(out.manifolds.end(), row.begin(), row.end());
        out.manifoldStart.push_back(static_cast<std::uint32_t>(out.manifolds.size()));
    }
    return out;
}

void expectSame(const Islands& want, const Islands& got, const char* what) {
    SCOPED_TRACE(what);
    EXPECT_EQ(want.islandOf, got.islandOf);
    EXPECT_EQ(want.bodyStart, got.bodyStart);
    EXPECT_EQ(want.bodies, got.bodies);
    EXPECT_EQ(want.manifoldStart, got.manifoldStart);
    EXPECT_EQ(want.manifolds, got.manifolds);
    EXPECT_EQ(want.largest, got.largest);
}

struct Size {
    std::uint32_t bodies, manifolds, extra;
};

class IslandsAgainstBfs : public ::testing::TestWithParam<Size> {};

TEST_P(IslandsAgainstBfs, SerialAndParallelMatchBreadthFirstSearchOnAnyThreadCount) {
    const Size size = GetParam();
    for (std::uint32_t seed : {1u, 2u, 3u}) {
        const Graph g = randomGraph(size.bodies, size.manifolds, size.extra, seed);
        const Islands want = bruteForce(g);
        Islands serial;
        IslandBuilder::buildSerial(g.contacts, g.extra, g.bodies, serial);
        expectSame(want, serial, "serial");
        for (int threads : {1, 2, 3}) {
            TaskPool pool(threads);
            IslandBuilder builder;
            Islands got;
            builder.build(g.contacts, g.extra, g.bodies, pool, got);
            expectSame(want, got, threads == 1 ? "1 thread" : threads == 2 ? "2 threads" : "3 threads");
            // A second build with the same builder (reused scratch) gives the same rows.
            builder.build(g.contacts, g.extra, g.bodies, pool, got);
            expectSame(want, got, "rebuilt");
        }
    }
}

// From empty and tiny graphs to sizes that span many parallel chunks (bodies in chunks of 4096, edges of 2048).
INSTANTIATE_TEST_SUITE_P(Sizes, IslandsAgainstBfs,
                         ::testing::Values(Size{0, 0, 0}, Size{1, 0, 0}, Size{5, 3, 0}, Size{60, 40, 10},
                                           Size{1000, 800, 0}, Size{1000, 0, 900}, Size{20000, 30000, 2000},
                                           Size{50000, 5000, 500}));

// A build clears only what the last one listed: one builder and one output over graphs of other sizes and edges
// (bodies added and removed between steps) must still match a fresh search every time.
TEST(Islands, ReusedBuilderClearsWhatTheLastBuildListed) {
    TaskPool pool(2);
    IslandBuilder builder;
    Islands got;
    std::uint32_t seed = 10;
    for (const Size size : {Size{20000, 15000, 500}, Size{5000, 200, 50}, Size{30000, 400, 0}, Size{30000, 30000, 0},
                            Size{100, 0, 0}, Size{8000, 4000, 4000}}) {
        const Graph g = randomGraph(size.bodies, size.manifolds, size.extra, ++seed);
        builder.build(g.contacts, g.extra, g.bodies, pool, got);
        expectSame(bruteForce(g), got, "reused");
    }
}

TEST(Islands, ManifoldRowsFollowAppendedManifolds) {
    Graph g = randomGraph(300, 200, 0, 7);
    TaskPool pool(2);
    IslandBuilder builder;
    Islands got;
    builder.build(g.contacts, g.extra, g.bodies, pool, got);
    // Append manifolds inside existing islands (as waking restores them) and reassign: rows equal a full rebuild's.
    for (std::uint32_t k = 0; k < got.count(); k += 3) {
        ContactPair p;
        p.a = got.bodies[got.bodyStart[k]];
        p.b = 0;
        p.bStatic = true;
        g.contacts.pairs.push_back(p);
        g.contacts.manifolds.emplace_back();
    }
    builder.assignManifolds(g.contacts, got);
    expectSame(bruteForce(g), got, "appended");
}

}  // namespace
}  // namespace rubble::detail
