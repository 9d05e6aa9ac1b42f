// Tree walks of src/query/tree_queries.h against brute force over the primitive boxes: rays and swept boxes (which
// primitives they enter, and the nearest entry when the range shrinks as a closest-hit query's does), box overlaps,
// removed primitives (empty boxes) never reported, and the refit of moved boxes.
//
// Entries are compared to 1e-5 relative: both sides compute the same slab products in float, the tree with a pad
// of ~1e-6 of the coordinates, which may only add primitives whose boxes are that close to the ray.
#include "query/tree_queries.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <set>
#include <vector>

#include "core/parallel.h"
#include "query/query_reference.h"

namespace rubble::detail {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

std::vector<StaticPrimitive> randomBoxes(std::uint32_t n, std::mt19937& rng, float side = 50) {
    std::uniform_real_distribution<float> u(-side, side), size(0.1f, 2.0f);
    std::vector<StaticPrimitive> prims(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        const Vec3 c{u(rng), u(rng), u(rng)}, h{size(rng), size(rng), size(rng)};
        prims[i] = {{c - h, c + h}, i, kWholeBody};
    }
    return prims;
}

/// Entry of the box [lo - e, hi + e] along the ray within [0, maxT], double slabs; negative when missed.
double entry(const Aabb& box, Vec3 e, Vec3 o, Vec3 d, double maxT) {
    double t0 = 0, t1 = maxT;
    const double lo[3] = {double(box.min.x) - e.x, double(box.min.y) - e.y, double(box.min.z) - e.z};
    const double hi[3] = {double(box.max.x) + e.x, double(box.max.y) + e.y, double(box.max.z) + e.z};
    const double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
    for (int a = 0; a < 3; ++a) {
        if (dd[a] == 0) {
            if (oo[a] < lo[a] || oo[a] > hi[a]) return -1;
            continue;
        }
        double n = (lo[a] - oo[a]) / dd[a], f = (hi[a] - oo[a]) / dd[a];
        if (n > f) std::swap(n, f);
        t0 = std::max(t0, n), t1 = std::min(t1, f);
    }
    return t0 <= t1 ? t0 : -1;
}

void compareSweeps(const StaticBvh::Tree& tree, const std::vector<StaticPrimitive>& prims, std::mt19937& rng,
                   Vec3 extent, const std::set<std::uint32_t>& removed = {}) {
    std::uniform_real_distribution<float> u(-60, 60);
    const float pad = boxPad(treeScale(tree) + 60);
    int entered = 0;
    for (int i = 0; i < 300; ++i) {
        const Vec3 o{u(rng), u(rng), u(rng)};
        Vec3 d = test::randomUnit(rng);
        if (i % 10 == 0) d = {0, i % 20 == 0 ? 1.0f : -1.0f, 0};  // axis-aligned: zero components
        const float maxT = i % 3 == 0 ? kInf : 80;
        const TreeSweep sweep(o, d, extent, pad);
        std::set<std::uint32_t> got;
        const float range = maxT;
        sweepTree(tree, sweep, range, [&](const StaticBvh::PrimitiveRef& p, float) { got.insert(p.body); });
        for (const StaticPrimitive& p : prims) {
            if (removed.count(p.body)) {
                EXPECT_FALSE(got.count(p.body)) << "a removed primitive was reported";
                continue;
            }
            const double tight = entry(p.box, extent, o, d, maxT);
            const Vec3 grown = extent + Vec3{2 * pad, 2 * pad, 2 * pad};
            const double loose = entry(p.box, grown, o, d, maxT);
            if (tight >= 0) {
                EXPECT_TRUE(got.count(p.body)) << "ray " << i << " missed box " << p.body;
            }
            if (loose < 0) {
                EXPECT_FALSE(got.count(p.body)) << "ray " << i << " reported box " << p.body;
            }
            entered += tight >= 0;
        }
        // A closest-hit walk that lowers the range to each entry it is given ends at the nearest entry.
        // The tree's entries are into padded boxes, so the answer lies between the nearest entries into the tight
        // and into the doubly padded boxes.
        float closest = maxT;
        double nearest = kInf, nearestLoose = kInf;
        for (const StaticPrimitive& p : prims) {
            if (removed.count(p.body)) continue;
            const double t = entry(p.box, extent, o, d, maxT);
            const double loose = entry(p.box, extent + Vec3{2 * pad, 2 * pad, 2 * pad}, o, d, maxT);
            if (t >= 0) nearest = std::min(nearest, t);
            if (loose >= 0) nearestLoose = std::min(nearestLoose, loose);
        }
        sweepTree(tree, sweep, closest,
                  [&](const StaticBvh::PrimitiveRef&, float t) { closest = std::min(closest, t); });
        if (nearest < kInf) {
            EXPECT_LE(closest, nearest + 1e-5 * (1 + nearest)) << "ray " << i;
            EXPECT_GE(closest, nearestLoose - 1e-5 * (1 + nearest)) << "ray " << i;
        }
    }
    EXPECT_GT(entered, 100);
}

TEST(QueryTrees, SweepsMatchBruteForce) {
    std::mt19937 rng(91);
    TaskPool pool(1);
    const std::vector<StaticPrimitive> prims = randomBoxes(3000, rng);
    StaticBvh bvh;
    bvh.build(prims, pool);
    compareSweeps(*bvh.trees()[0], prims, rng, {});
    compareSweeps(*bvh.trees()[0], prims, rng, {0.5f, 1.5f, 0.2f});
}

TEST(QueryTrees, RemovedPrimitivesAreNeverReported) {
    std::mt19937 rng(92);
    TaskPool pool(1);
    const std::vector<StaticPrimitive> prims = randomBoxes(2000, rng);
    StaticBvh bvh;
    bvh.build(prims, pool);
    std::set<std::uint32_t> removed;
    for (std::uint32_t b = 0; b < 2000; b += 7) {
        bvh.remove(b);
        removed.insert(b);
    }
    compareSweeps(*bvh.trees()[0], prims, rng, {}, removed);
    compareSweeps(*bvh.trees()[0], prims, rng, {1, 1, 1}, removed);
    for (int i = 0; i < 100; ++i) {
        std::set<std::uint32_t> got;
        const Vec3 c{float(i) - 50, 0, 0};
        overlapTree(*bvh.trees()[0], c - Vec3{5, 50, 50}, c + Vec3{5, 50, 50},
                    [&](const StaticBvh::PrimitiveRef& p) { got.insert(p.body); });
        for (const std::uint32_t b : removed) EXPECT_FALSE(got.count(b));
    }
}

TEST(QueryTrees, OverlapsAndRefitsMatchBruteForce) {
    std::mt19937 rng(93);
    TaskPool pool(2);
    std::vector<StaticPrimitive> prims = randomBoxes(5000, rng);
    StaticBvh bvh;
    bvh.build(prims, pool);
    StaticBvh::Tree tree = *bvh.trees()[0];
    const double fresh = sahCost(tree);
    EXPECT_NEAR(fresh, bvh.stats().sahCost, 1e-6 * fresh);

    auto compareOverlaps = [&](const StaticBvh::Tree& t) {
        std::uniform_real_distribution<float> u(-55, 55), size(0.5f, 10);
        for (int i = 0; i < 200; ++i) {
            const Vec3 c{u(rng), u(rng), u(rng)}, h{size(rng), size(rng), size(rng)};
            std::vector<std::uint32_t> got;
            overlapTree(t, c - h, c + h, [&](const StaticBvh::PrimitiveRef& p) { got.push_back(p.body); });
            std::sort(got.begin(), got.end());
            std::vector<std::uint32_t> want;
            for (const StaticPrimitive& p : prims)
                if (p.box.min.x <= c.x + h.x && c.x - h.x <= p.box.max.x && p.box.min.y <= c.y + h.y &&
                    c.y - h.y <= p.box.max.y && p.box.min.z <= c.z + h.z && c.z - h.z <= p.box.max.z)
                    want.push_back(p.body);
            EXPECT_EQ(got, want) << "query " << i;
        }
    };
    compareOverlaps(tree);

    // Move every box a little (as a step does): the refitted tree answers for the new boxes.
    std::uniform_real_distribution<float> step(-0.5f, 0.5f);
    Bounds boxes;
    boxes.resize(prims.size());
    for (StaticPrimitive& p : prims) {
        const Vec3 move{step(rng), step(rng), step(rng)};
        p.box = {p.box.min + move, p.box.max + move};
        const std::uint32_t i = p.body;
        boxes.minX[i] = p.box.min.x, boxes.minY[i] = p.box.min.y, boxes.minZ[i] = p.box.min.z;
        boxes.maxX[i] = p.box.max.x, boxes.maxY[i] = p.box.max.y, boxes.maxZ[i] = p.box.max.z;
    }
    const double refitted = refitTree(tree, boxes);
    EXPECT_LT(refitted, 1.2 * fresh);
    compareOverlaps(tree);
    compareSweeps(tree, prims, rng, {});

    // Scrambled (every box somewhere else): still right, but the cost shows the tree is now poor.
    std::uniform_real_distribution<float> u(-50, 50);
    for (StaticPrimitive& p : prims) {
        const Vec3 c{u(rng), u(rng), u(rng)}, h = (p.box.max - p.box.min) * 0.5f;
        p.box = {c - h, c + h};
        const std::uint32_t i = p.body;
        boxes.minX[i] = p.box.min.x, boxes.minY[i] = p.box.min.y, boxes.minZ[i] = p.box.min.z;
        boxes.maxX[i] = p.box.max.x, boxes.maxY[i] = p.box.max.y, boxes.maxZ[i] = p.box.max.z;
    }
    EXPECT_GT(refitTree(tree, boxes), 3 * fresh);
    compareOverlaps(tree);

    // Fewer boxes than the tree was built for (bodies removed, the last ones swapped into their holes): the leaves
    // past the end get empty boxes and are never reported.
    const std::uint32_t kept = 4000;
    boxes.resize(kept);
    std::set<std::uint32_t> gone;
    for (std::uint32_t b = kept; b < prims.size(); ++b) gone.insert(b);
    refitTree(tree, boxes);
    compareSweeps(tree, prims, rng, {}, gone);
    prims.resize(kept);
    compareOverlaps(tree);
}

}  // namespace
}  // namespace rubble::detail
