// Static BVH against brute force: every moving box against every primitive with closed-interval tests, on terrains,
// heightfields, degenerate meshes, mixed static bodies, posed meshes and edits between queries; plus determinism
// across thread counts and the quality of the SAH tree.
#include "broadphase/static_bvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <numeric>
#include <random>
#include <thread>
#include <tuple>
#include <vector>

#include "core/parallel.h"
#include "scene/generators.h"
#include "shapes/shape.h"

namespace rubble::detail {
namespace {

/// (moving, body, triangle) with triangle = kWholeBody for body pairs: the flat form both answers are compared in.
using Hit = std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>;

bool boxOverlaps(const Bounds& b, std::uint32_t i, const Aabb& p) {
    return b.minX[i] <= p.max.x && p.min.x <= b.maxX[i] && b.minY[i] <= p.max.y && p.min.y <= b.maxY[i] &&
           b.minZ[i] <= p.max.z && p.min.z <= b.maxZ[i];
}

std::vector<Hit> bruteForce(const Bounds& moving, const std::vector<StaticPrimitive>& prims,
                            const StaticQueryFilter& filter = {}) {
    std::vector<Hit> out;
    for (std::uint32_t i = 0; i < moving.size(); ++i) {
        if (filter.moving.asleep(i)) continue;
        for (const StaticPrimitive& p : prims) {
            if (!boxOverlaps(moving, i, p.box)) continue;
            const std::uint32_t mc = filter.moving.category ? filter.moving.category[i] : ~0u;
            const std::uint32_t mm = filter.moving.mask ? filter.moving.mask[i] : ~0u;
            const std::uint32_t sc = filter.staticCategory ? filter.staticCategory[p.body] : ~0u;
            const std::uint32_t sm = filter.staticMask ? filter.staticMask[p.body] : ~0u;
            if ((mc & sm) == 0 || (sc & mm) == 0) continue;
            out.emplace_back(i, p.body, p.triangle);
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

struct Result {
    std::vector<BodyPair> bodies;
    std::vector<MeshPair> meshes;
    std::vector<std::uint32_t> triangles;
};

Result runQuery(StaticBvh& bvh, const Bounds& moving, TaskPool& pool, const StaticQueryFilter& filter = {}) {
    Result r;
    bvh.query(moving, filter, pool, r.bodies, r.meshes, r.triangles);
    return r;
}

/// Flattens a query result, checking the documented structure on the way: pairs ordered by (moving, body), one
/// MeshPair per (moving, body), each with its triangles ascending and laid out back to back.
std::vector<Hit> flatten(const Result& r) {
    std::vector<Hit> out;
    EXPECT_TRUE(std::is_sorted(r.bodies.begin(), r.bodies.end()));
    EXPECT_TRUE(std::adjacent_find(r.bodies.begin(), r.bodies.end()) == r.bodies.end());
    for (const BodyPair& p : r.bodies) out.emplace_back(p.a, p.b, kWholeBody);
    std::uint32_t expectedFirst = 0;
    for (std::size_t m = 0; m < r.meshes.size(); ++m) {
        const MeshPair& p = r.meshes[m];
        if (m > 0) {
            const MeshPair& q = r.meshes[m - 1];
            EXPECT_TRUE(q.moving < p.moving || (q.moving == p.moving && q.staticBody < p.staticBody));
        }
        EXPECT_EQ(p.firstTriangle, expectedFirst);
        EXPECT_GT(p.triangleCount, 0u);
        expectedFirst += p.triangleCount;
        for (std::uint32_t t = 0; t < p.triangleCount; ++t) {
            if (t > 0) {
                EXPECT_LT(r.triangles[p.firstTriangle + t - 1], r.triangles[p.firstTriangle + t]);
            }
            out.emplace_back(p.moving, p.staticBody, r.triangles[p.firstTriangle + t]);
        }
    }
    EXPECT_EQ(expectedFirst, r.triangles.size());
    std::sort(out.begin(), out.end());
    return out;
}

Shape terrainShape(std::uint32_t cells, double halfSize = 50) {
    scene_detail::TerrainParams p;
    p.cells[0] = p.cells[1] = cells;
    p.min[0] = p.min[1] = -halfSize;
    p.max[0] = p.max[1] = halfSize;
    p.amplitude = 2;
    p.wavelength[0] = p.wavelength[1] = 8;
    return buildShape(scene_detail::generateTerrain(p));
}

/// n boxes over [-extent, extent] in x and z and [yLo, yHi] in y, half extents log-uniform in [0.05, 5] with more
/// small ones (as a pile of bodies of mixed sizes). The first tenth of the boxes, when `touching` primitives are
/// given, are placed exactly touching one of them (a face, an edge or a corner), the case closed intervals decide.
Bounds randomBoxes(std::uint32_t n, float extent, float yLo, float yHi, std::uint32_t seed,
                   const std::vector<StaticPrimitive>* touching = nullptr) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0, 1);
    Bounds b;
    b.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        const float h = 0.05f * std::pow(100.0f, u(rng) * u(rng));
        float x = -extent + 2 * extent * u(rng), y = yLo + (yHi - yLo) * u(rng), z = -extent + 2 * extent * u(rng);
        b.minX[i] = x - h, b.maxX[i] = x + h, b.minY[i] = y - h, b.maxY[i] = y + h, b.minZ[i] = z - h,
        b.maxZ[i] = z + h;
        if (touching != nullptr && !touching->empty() && i < n / 10) {
            const Aabb& p = (*touching)[rng() % touching->size()].box;
            const int kind = int(rng() % 3);
            // Face: share the max-y plane; edge: also the max-x plane; corner: all three max planes.
            b.minY[i] = p.max.y, b.maxY[i] = p.max.y + h;
            b.minX[i] = kind >= 1 ? p.max.x : p.min.x, b.maxX[i] = b.minX[i] + h;
            b.minZ[i] = kind >= 2 ? p.max.z : p.min.z, b.maxZ[i] = b.minZ[i] + h;
        }
    }
    return b;
}

TEST(StaticBvh, TerrainMatchesBruteForce) {
    const Shape terrain = terrainShape(100);
    std::vector<StaticPrimitive> prims;
    appendStaticPrimitives(terrain, {}, 7, prims);
    ASSERT_EQ(prims.size(), 20000u);
    const Bounds moving = randomBoxes(2500, 55, -4, 6, 1, &prims);

    TaskPool pool(2);
    StaticBvh bvh;
    bvh.build(prims, pool);
    EXPECT_EQ(bvh.primitiveCount(), 20000u);
    const Result r = runQuery(bvh, moving, pool);
    const std::vector<Hit> expected = bruteForce(moving, prims);
    EXPECT_GT(expected.size(), 3000u);  // the test means something
    EXPECT_TRUE(r.bodies.empty());
    EXPECT_EQ(flatten(r), expected);
}

TEST(StaticBvh, HeightfieldMatchesBruteForceAndItsNumbering) {
    HeightfieldDef def;
    def.rows = 41;
    def.columns = 57;  // not square, so rows and columns cannot be swapped unnoticed
    def.spacing = {0.75f, 0.5f, 1.25f};
    for (std::uint32_t r = 0; r < def.rows; ++r)
        for (std::uint32_t c = 0; c < def.columns; ++c)
            def.heights.push_back(3 * std::sin(0.3f * float(c)) * std::cos(0.2f * float(r)) + 0.01f * float(c));
    const Shape field = buildShape(def);
    const Transform pose{{-20, 1, -25}, Quat::fromAxisAngle({0, 1, 0}, 0.4f)};
    std::vector<StaticPrimitive> prims;
    appendStaticPrimitives(field, pose, 3, prims);
    ASSERT_EQ(prims.size(), heightfieldTriangleCount(*field.heightfield));
    ASSERT_EQ(prims.size(), 2u * 40 * 56);

    // Numbering: triangle t's box is the box of heightfieldTriangle(t) posed, and the pair of a cell covers the
    // cell's surface as heightfieldHeightAt sees it (the height at the cell's centre lies on one of them).
    for (std::uint32_t t = 0; t < prims.size(); ++t) {
        const auto tri = heightfieldTriangle(*field.heightfield, t);
        ASSERT_EQ(prims[t].triangle, t);
        for (const Vec3& v : tri) {
            const Vec3 w = apply(pose, v);
            EXPECT_TRUE(w.x >= prims[t].box.min.x && w.x <= prims[t].box.max.x && w.y >= prims[t].box.min.y &&
                        w.y <= prims[t].box.max.y && w.z >= prims[t].box.min.z && w.z <= prims[t].box.max.z);
        }
    }
    for (std::uint32_t cell = 0; cell < 40 * 56; ++cell) {
        const std::uint32_t r = cell / 56, c = cell % 56;
        const float x = (float(c) + 0.25f) * 0.75f, z = (float(r) + 0.75f) * 1.25f;  // in triangle 0 of the cell
        const auto tri = heightfieldTriangle(*field.heightfield, 2 * cell);
        const auto h = triangleHeightAt(tri[0], tri[1], tri[2], x, z);
        ASSERT_TRUE(h.has_value()) << "cell " << cell;
        EXPECT_FLOAT_EQ(*h, *heightfieldHeightAt(*field.heightfield, x, z));
    }

    TaskPool pool(2);
    StaticBvh bvh;
    bvh.build(prims, pool);
    const Bounds moving = randomBoxes(2000, 40, -4, 5, 2, &prims);
    const std::vector<Hit> expected = bruteForce(moving, prims);
    EXPECT_GT(expected.size(), 1000u);
    EXPECT_EQ(flatten(runQuery(bvh, moving, pool)), expected);
}

TEST(StaticBvh, DegenerateAndDuplicateTriangles) {
    TriangleMeshDef def;
    def.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}, {2, 0, 0}, {1, 1, 1}, {3, 0, 3}};
    def.indices = {0, 1, 2,   // a proper triangle
                   0, 1, 3,   // collinear: zero area, flat box in y and z
                   4, 4, 4,   // a point
                   0, 0, 5,   // a segment
                   0, 1, 2,   // duplicate of the first
                   2, 1, 0};  // the same, flipped
    // Many copies of one triangle: every centroid coincides, so the SAH has nothing to split on.
    for (int k = 0; k < 300; ++k) def.indices.insert(def.indices.end(), {1, 4, 5});
    const Shape mesh = buildShape(def);
    std::vector<StaticPrimitive> prims;
    appendStaticPrimitives(mesh, {}, 0, prims);
    ASSERT_EQ(prims.size(), 306u);

    TaskPool pool(2);
    StaticBvh bvh;
    bvh.build(prims, pool);
    Bounds moving = randomBoxes(1500, 4, -1, 2, 3, &prims);
    // Boxes that touch only the point triangle or only the segment's end.
    const std::uint32_t n = moving.size();
    moving.resize(n + 2);
    moving.minX[n] = 1, moving.maxX[n] = 1, moving.minY[n] = 1, moving.maxY[n] = 2, moving.minZ[n] = 1,
    moving.maxZ[n] = 1;
    moving.minX[n + 1] = 3, moving.maxX[n + 1] = 4, moving.minY[n + 1] = -1, moving.maxY[n + 1] = 0,
                    moving.minZ[n + 1] = 3, moving.maxZ[n + 1] = 3.5f;
    const std::vector<Hit> expected = bruteForce(moving, prims);
    EXPECT_GT(expected.size(), 1000u);
    EXPECT_EQ(flatten(runQuery(bvh, moving, pool)), expected);
    EXPECT_LE(bvh.stats().depth, 12u);  // middle splits of the coincident copies keep the tree balanced
}

/// Static boxes, spheres and capsules (whole-body primitives) next to two meshes, under a category filter and
/// sleeping moving bodies.
TEST(StaticBvh, StaticBodiesMixedWithMeshesAndFiltered) {
    std::vector<Shape> shapes;
    shapes.push_back(buildShape(BoxDef{{1, 0.5f, 2}}));
    shapes.push_back(buildShape(SphereDef{0.7f}));
    shapes.push_back(buildShape(CapsuleDef{0.3f, 1}));
    const Shape terrain = terrainShape(30, 15);
    std::vector<StaticPrimitive> prims;
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(-1, 1);
    const std::uint32_t bodies = 400;
    for (std::uint32_t body = 0; body < bodies; ++body) {
        if (body == 17 || body == 230) {
            appendStaticPrimitives(terrain, {{0, body == 17 ? 0.0f : 3.0f, 0}, {}}, body, prims);
            continue;
        }
        const Transform pose{{20 * u(rng), 3 * u(rng), 20 * u(rng)},
                             Quat::fromAxisAngle({u(rng), u(rng), u(rng)}, 3 * u(rng))};
        appendStaticPrimitives(shapes[body % 3], pose, body, prims);
    }
    ASSERT_EQ(prims.size(), 398u + 2 * 1800u);

    std::vector<std::uint32_t> staticCategory(bodies), staticMask(bodies);
    for (std::uint32_t b = 0; b < bodies; ++b) staticCategory[b] = 1u << (b % 4), staticMask[b] = ~0u;
    staticMask[17] = 0b0111;  // the first terrain ignores category 8
    const Bounds moving = randomBoxes(3000, 22, -4, 6, 5, &prims);
    std::vector<std::uint32_t> category(moving.size()), mask(moving.size());
    std::vector<std::uint8_t> flags(moving.size());
    for (std::uint32_t i = 0; i < moving.size(); ++i) {
        category[i] = 1u << (i % 4);
        mask[i] = i % 5 == 0 ? 0b1010 : ~0u;
        flags[i] = i % 7 == 0 ? 0x10 : 0;
    }
    StaticQueryFilter filter;
    filter.moving = {category.data(), mask.data(), flags.data(), 0x10};
    filter.staticCategory = staticCategory.data();
    filter.staticMask = staticMask.data();

    TaskPool pool(2);
    StaticBvh bvh;
    bvh.build(prims, pool);
    const Result unfiltered = runQuery(bvh, moving, pool);
    EXPECT_EQ(flatten(unfiltered), bruteForce(moving, prims));
    EXPECT_GT(unfiltered.bodies.size(), 100u);
    EXPECT_GT(unfiltered.meshes.size(), 100u);
    const Result filtered = runQuery(bvh, moving, pool, filter);
    const std::vector<Hit> expected = bruteForce(moving, prims, filter);
    EXPECT_LT(expected.size(), flatten(unfiltered).size());
    EXPECT_EQ(flatten(filtered), expected);
}

TEST(StaticBvh, PosedMesh) {
    const Shape terrain = terrainShape(60, 20);
    const Transform pose{{5, -3, 8}, Quat::fromAxisAngle({1, 2, 0.5f}, 0.9f)};
    std::vector<StaticPrimitive> prims;
    appendStaticPrimitives(terrain, pose, 11, prims);
    // Each triangle's box holds its posed vertices and touches each of its faces with one of them.
    const TriangleMesh& mesh = *terrain.mesh;
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        Aabb box{apply(pose, mesh.vertices[mesh.indices[3 * t]]), apply(pose, mesh.vertices[mesh.indices[3 * t]])};
        for (int k = 1; k < 3; ++k) {
            const Vec3 v = apply(pose, mesh.vertices[mesh.indices[3 * t + k]]);
            box.min = {std::min(box.min.x, v.x), std::min(box.min.y, v.y), std::min(box.min.z, v.z)};
            box.max = {std::max(box.max.x, v.x), std::max(box.max.y, v.y), std::max(box.max.z, v.z)};
        }
        ASSERT_EQ(prims[t].box.min, box.min);
        ASSERT_EQ(prims[t].box.max, box.max);
    }
    TaskPool pool(2);
    StaticBvh bvh;
    bvh.build(prims, pool);
    const Bounds moving = randomBoxes(2500, 25, -20, 15, 6, &prims);
    const std::vector<Hit> expected = bruteForce(moving, prims);
    EXPECT_GT(expected.size(), 1000u);
    EXPECT_EQ(flatten(runQuery(bvh, moving, pool)), expected);
}

/// The forest's answer against brute force over the primitives of the bodies still alive (`live`, by body).
void expectMatchesLiveBodies(StaticBvh& bvh, const std::vector<std::vector<StaticPrimitive>>& live,
                             const Bounds& moving, TaskPool& pool, const char* when) {
    std::vector<StaticPrimitive> reference;
    for (const auto& p : live) reference.insert(reference.end(), p.begin(), p.end());
    EXPECT_EQ(bvh.primitiveCount(), reference.size()) << when;
    EXPECT_EQ(flatten(runQuery(bvh, moving, pool)), bruteForce(moving, reference)) << when;
}

TEST(StaticBvh, InsertAndRemoveBetweenQueriesWithoutRebuild) {
    const Shape box = buildShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    const Shape smallTerrain = terrainShape(10, 5);
    std::mt19937 rng(8);
    std::uniform_real_distribution<float> u(-30, 30);
    auto bodyPrims = [&](std::uint32_t body) {
        std::vector<StaticPrimitive> out;
        if (body % 50 == 0)
            appendStaticPrimitives(smallTerrain, {{u(rng), 0, u(rng)}, {}}, body, out);
        else
            appendStaticPrimitives(box, {{u(rng), 0.3f * u(rng), u(rng)}, {}}, body, out);
        return out;
    };
    // The live set as a map body -> primitives, the reference for every query.
    std::vector<std::vector<StaticPrimitive>> live(2000);
    std::vector<StaticPrimitive> all;
    for (std::uint32_t b = 0; b < 1500; ++b) {
        live[b] = bodyPrims(b);
        all.insert(all.end(), live[b].begin(), live[b].end());
    }
    TaskPool pool(2);
    StaticBvh bvh;
    bvh.build(all, pool);
    const std::uint32_t nodesAfterBuild = bvh.stats().nodes;
    const StaticBvh::Tree* built = bvh.trees()[0];
    auto builtTreeKept = [&] { return std::find(bvh.trees().begin(), bvh.trees().end(), built) != bvh.trees().end(); };
    const Bounds moving = randomBoxes(2000, 32, -3, 3, 9);
    auto check = [&](const char* when) { expectMatchesLiveBodies(bvh, live, moving, pool, when); };
    check("after build");

    // Round 1: remove a few bodies (one terrain among them), add a few new ones, reuse one removed id.
    for (std::uint32_t b : {3u, 50u, 51u, 777u, 1499u}) {
        bvh.remove(b);
        live[b].clear();
    }
    bvh.remove(1999);  // never present: no effect
    for (std::uint32_t b : {1500u, 1550u, 1600u, 51u}) {
        live[b] = bodyPrims(b);
        bvh.insert(live[b], pool);
    }
    StaticBvhStats s = bvh.stats();
    EXPECT_GT(s.pending, 0u) << "inserts wait for a batch or a commit";
    check("after small edits");
    s = bvh.stats();
    EXPECT_TRUE(builtTreeKept()) << "small edits must not rebuild the built tree";
    EXPECT_EQ(s.parts, 2u);
    EXPECT_GT(s.tombstones, 0u);
    EXPECT_EQ(s.pending, 0u);

    // Round 2: remove an inserted body and a reused id again; remove twice.
    for (std::uint32_t b : {1550u, 51u, 51u}) {
        bvh.remove(b);
        live[b].clear();
    }
    check("after removing inserted bodies");
    EXPECT_TRUE(builtTreeKept());

    // Round 3: many edits cross the merge thresholds, which rebuild off the query: answers are exact while the
    // merges run, and once they have landed, without tombstones.
    for (std::uint32_t b = 100; b < 600; ++b) {
        bvh.remove(b);
        live[b].clear();
    }
    for (std::uint32_t b = 1601; b < 1990; ++b) {
        live[b] = bodyPrims(b);
        bvh.insert(live[b], pool);
    }
    check("after large edits");
    bvh.settle(pool);
    check("after the merges landed");
    s = bvh.stats();
    EXPECT_EQ(s.tombstones, 0u);
    EXPECT_EQ(s.pending, 0u);
    EXPECT_EQ(s.merging, 0u);
    EXPECT_NE(s.nodes, nodesAfterBuild) << "a third of the built tree was removed: it is rebuilt";

    // Everything removed.
    for (std::uint32_t b = 0; b < live.size(); ++b) {
        bvh.remove(b);
        live[b].clear();
    }
    check("after removing everything");
    EXPECT_TRUE(bvh.empty());
}

// Queries keep the hits of grown boxes across calls (see static_bvh.h). Boxes that drift a little (and stay inside
// their grown boxes), jump, grow, fall asleep and wake, with the body count changing between calls, must still get
// exactly the brute-force answer every time.
TEST(StaticBvh, KeptHitsFollowMovingBoxes) {
    const Shape terrain = terrainShape(60, 30);
    std::vector<StaticPrimitive> prims;
    appendStaticPrimitives(terrain, {}, 3, prims);
    TaskPool pool(2);
    StaticBvh bvh;
    bvh.build(prims, pool);
    Bounds moving = randomBoxes(1200, 32, -3, 3, 21, &prims);
    std::mt19937 rng(22);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<std::uint8_t> flags(2000, 0);
    StaticQueryFilter filter;
    filter.moving.flags = flags.data();
    filter.moving.asleepBit = 1;
    std::size_t total = 0;
    for (int call = 0; call < 40; ++call) {
        for (std::uint32_t i = 0; i < moving.size(); ++i) {
            const float h = moving.maxX[i] - moving.minX[i];
            // Mostly drifts of a hundredth of the size; now and then a jump of up to the size, or a larger box.
            const float step = (rng() % 10 == 0 ? 1.0f : 0.01f) * h;
            const float dx = step * u(rng), dy = step * u(rng), dz = step * u(rng);
            moving.minX[i] += dx, moving.maxX[i] += dx, moving.minY[i] += dy, moving.maxY[i] += dy;
            moving.minZ[i] += dz, moving.maxZ[i] += dz;
            if (rng() % 50 == 0) moving.maxY[i] += 0.5f * h;
            if (rng() % 40 == 0) flags[i] ^= 1;
        }
        if (call == 20) {  // fewer bodies: the last chunk ends earlier
            Bounds fewer = moving;
            fewer.resize(1000);
            moving = fewer;
        }
        if (call == 30) {  // more bodies again
            const Bounds extra = randomBoxes(300, 32, -3, 3, 23, &prims);
            const std::uint32_t n = moving.size();
            moving.resize(n + 300);
            for (std::uint32_t i = 0; i < 300; ++i) {
                moving.minX[n + i] = extra.minX[i], moving.maxX[n + i] = extra.maxX[i];
                moving.minY[n + i] = extra.minY[i], moving.maxY[n + i] = extra.maxY[i];
                moving.minZ[n + i] = extra.minZ[i], moving.maxZ[n + i] = extra.maxZ[i];
            }
        }
        const std::vector<Hit> expected = bruteForce(moving, prims, filter);
        total += expected.size();
        ASSERT_EQ(flatten(runQuery(bvh, moving, pool, filter)), expected) << "call " << call;
    }
    EXPECT_GT(total, 40u * 1000);  // the boxes touch the terrain: the test means something
}

// Edits spoil only the kept hits of the bodies whose grown boxes they overlap (static_bvh.h). Boxes that rest or
// drift inside their grown boxes, some asleep and waking, see statics added on top of them, removed from under
// them, moved (an id removed and inserted elsewhere) and edited far away; a query with no moving boxes between
// edits, and more edits than are tracked one by one, in between. Every answer must be the brute force's.
TEST(StaticBvh, KeptHitsSeeEveryEditThatReachesThem) {
    std::mt19937 rng(31);
    std::uniform_real_distribution<float> u(-1, 1);
    const auto boxAt = [](float x, float y, float z, float h) {
        return Aabb{{x - h, y - h, z - h}, {x + h, y + h, z + h}};
    };
    // Statics: unit boxes scattered over a 60 m floor, one primitive each; `live` by body id.
    std::vector<std::vector<StaticPrimitive>> live(StaticBvh::kEditsTracked + 4000);
    const auto place = [&](std::uint32_t body, const Aabb& box) { live[body] = {{box, body, kWholeBody}}; };
    std::vector<StaticPrimitive> all;
    for (std::uint32_t b = 0; b < 3000; ++b) {
        place(b, boxAt(30 * u(rng), 0.5f * u(rng), 30 * u(rng), 0.5f));
        all.push_back(live[b][0]);
    }
    TaskPool pool(2);
    StaticBvh bvh;
    bvh.build(all, pool);
    // Moving boxes resting just above the floor, a tenth of them asleep at a time.
    Bounds moving = randomBoxes(1500, 30, 0.5f, 1.5f, 32);
    std::vector<std::uint8_t> flags(moving.size(), 0);
    StaticQueryFilter filter;
    filter.moving.flags = flags.data();
    filter.moving.asleepBit = 1;
    const auto check = [&](const char* when, int call) {
        std::vector<StaticPrimitive> reference;
        for (const auto& p : live) reference.insert(reference.end(), p.begin(), p.end());
        ASSERT_EQ(flatten(runQuery(bvh, moving, pool, filter)), bruteForce(moving, reference, filter))
            << when << ", call " << call;
    };
    std::uint32_t nextBody = 3000;
    std::size_t touchedByEdits = 0;
    for (int call = 0; call < 30; ++call) {
        for (std::uint32_t i = 0; i < moving.size(); ++i) {  // drifts far inside the grown boxes
            const float d = 0.001f * u(rng);
            moving.minX[i] += d, moving.maxX[i] += d;
            if (rng() % 10 == 0) flags[i] ^= 1;
        }
        // Edits at a moving box (on top of it, or of the statics under it) and far away, and moves of an id.
        for (int e = 0; e < 20; ++e) {
            const std::uint32_t i = rng() % moving.size();
            const float x = 0.5f * (moving.minX[i] + moving.maxX[i]), z = 0.5f * (moving.minZ[i] + moving.maxZ[i]);
            switch (rng() % 4) {
                case 0: {  // a new static overlapping the moving box
                    place(nextBody, boxAt(x, moving.minY[i], z, 0.3f));
                    bvh.insert(live[nextBody], pool);
                    ++nextBody;
                    ++touchedByEdits;
                    break;
                }
                case 1: {  // remove whatever static the moving box overlaps
                    for (std::uint32_t b = 0; b < nextBody; ++b)
                        if (!live[b].empty() && boxOverlaps(moving, i, live[b][0].box)) {
                            bvh.remove(b);
                            live[b].clear();
                            ++touchedByEdits;
                            break;
                        }
                    break;
                }
                case 2: {  // move a static id from somewhere to this box
                    const std::uint32_t b = rng() % nextBody;
                    bvh.remove(b);
                    place(b, boxAt(x, moving.minY[i], z, 0.2f));
                    bvh.insert(live[b], pool);
                    ++touchedByEdits;
                    break;
                }
                default: {  // far away
                    place(nextBody, boxAt(200 + 10 * u(rng), 0, 10 * u(rng), 0.5f));
                    bvh.insert(live[nextBody], pool);
                    ++nextBody;
                }
            }
        }
        if (call == 10) {  // no moving boxes: the query returns early, and the edits still count after it
            const Bounds none;
            EXPECT_TRUE(flatten(runQuery(bvh, none, pool)).empty());
        }
        if (call == 20) {  // more edits than are tracked: every body looks again
            for (std::uint32_t e = 0; e < StaticBvh::kEditsTracked; ++e) {
                place(nextBody, boxAt(300 + 30 * u(rng), 0, 30 * u(rng), 0.5f));
                bvh.insert(live[nextBody], pool);
                ++nextBody;
            }
            const std::uint32_t i = rng() % moving.size();
            place(nextBody, boxAt(0.5f * (moving.minX[i] + moving.maxX[i]), moving.minY[i],
                                  0.5f * (moving.minZ[i] + moving.maxZ[i]), 0.3f));
            bvh.insert(live[nextBody], pool);
            ++nextBody;
        }
        check("after edits", call);
    }
    EXPECT_GT(touchedByEdits, 300u);  // the edits reached the moving boxes: the test means something
}

// A world that adds many statics one at a time (a level loading) builds its parts as it goes: a commit never has
// more than a batch left to build. Background merges then fold the batches into fewer, larger parts; whatever state
// they are in when a query runs, its answer is the brute force's, and removals made while a merge reads its parts
// reach the merged part.
TEST(StaticBvh, ForestBuiltWhileAddingAndMergedOffTheQuery) {
    const Shape box = buildShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    std::mt19937 rng(21);
    std::uniform_real_distribution<float> u(-60, 60);
    TaskPool pool(2);
    StaticBvh bvh;
    std::vector<std::vector<StaticPrimitive>> live(40000);
    const Bounds moving = randomBoxes(1500, 64, -2, 2, 3);
    auto check = [&](const char* when) { expectMatchesLiveBodies(bvh, live, moving, pool, when); };
    auto add = [&](std::uint32_t body) {
        live[body].clear();
        appendStaticPrimitives(box, {{u(rng), 0.2f * u(rng), u(rng)}, {}}, body, live[body]);
        bvh.insert(live[body], pool);
    };
    auto remove = [&](std::uint32_t body) {
        bvh.remove(body);
        live[body].clear();
    };
    for (std::uint32_t b = 0; b < 30000; ++b) {
        add(b);
        EXPECT_LT(bvh.stats().pending, StaticBvh::kBatchPrimitives);
    }
    EXPECT_GE(bvh.stats().parts, 3u) << "batches were built as the bodies came, and merges cannot all have landed";
    check("after adding");
    // Edits while merges may be running: removals of merged and unmerged bodies, re-used ids, new bodies.
    for (int round = 0; round < 4; ++round) {
        for (std::uint32_t b = std::uint32_t(round); b < 30000; b += 7) remove(b);
        for (std::uint32_t b = std::uint32_t(round); b < 30000; b += 21) add(b);
        for (std::uint32_t b = 30000 + 2000 * std::uint32_t(round); b < 32000 + 2000 * std::uint32_t(round); ++b)
            add(b);
        check("after a round of edits");
    }
    bvh.settle(pool);
    check("after the merges landed");
    const StaticBvhStats s = bvh.stats();
    EXPECT_EQ(s.merging, 0u);
    EXPECT_EQ(s.pending, 0u);
    EXPECT_LT(s.parts, StaticBvh::kMergeFanIn * 3) << "a settled forest has fewer than kMergeFanIn parts per tier";
    EXPECT_LE(std::uint64_t(s.tombstones) * 4, s.primitives);
}

// While a step that takes every core runs, background merges wait at their check points (their page faults and
// unmaps would stall the step's threads); once it ends they go on. A merge of eight small batches takes a few
// milliseconds, so one that ignored the gate would have landed in the tenth of a second the test waits.
TEST(StaticBvh, MergesWaitWhileAStepRuns) {
    TaskPool pool(2);
    StaticBvh bvh;
    bvh.stepBegins();
    std::vector<StaticPrimitive> all;
    for (std::uint32_t b = 0; b < StaticBvh::kMergeFanIn * StaticBvh::kBatchPrimitives; ++b) {
        const auto x = float(b % 128), z = float(b / 128);
        all.push_back({{{x, 0, z}, {x + 0.5f, 0.5f, z + 0.5f}}, b, kWholeBody});
        bvh.insert({&all.back(), 1}, pool);
    }
    ASSERT_EQ(bvh.stats().parts, StaticBvh::kMergeFanIn);
    EXPECT_EQ(bvh.stats().merging, StaticBvh::kMergeFanIn) << "the full batches are due for a merge";
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    bvh.commit(pool);
    EXPECT_EQ(bvh.stats().parts, StaticBvh::kMergeFanIn) << "a merge landed while a step ran";
    bvh.stepEnds();
    bvh.settle(pool);
    EXPECT_EQ(bvh.stats().parts, 1u);
    const Bounds moving = randomBoxes(500, 64, -1, 1, 5);
    EXPECT_EQ(flatten(runQuery(bvh, moving, pool)), bruteForce(moving, all));
}

TEST(StaticBvh, EmptyTreeAndEmptyQuery) {
    TaskPool pool(2);
    StaticBvh bvh;
    const Bounds moving = randomBoxes(100, 10, -1, 1, 10);
    Result r = runQuery(bvh, moving, pool);
    EXPECT_TRUE(r.bodies.empty() && r.meshes.empty() && r.triangles.empty());
    bvh.build({}, pool);
    EXPECT_TRUE(bvh.empty());
    EXPECT_TRUE(bvh.trees().empty());
    r = runQuery(bvh, moving, pool);
    EXPECT_TRUE(r.bodies.empty() && r.meshes.empty());

    // A single primitive, then no moving bodies at all; outputs are overwritten, not appended to.
    bvh.build({{{{-100, -100, -100}, {100, 100, 100}}, 5, kWholeBody}}, pool);
    r = runQuery(bvh, moving, pool);
    EXPECT_EQ(r.bodies.size(), 100u);
    r = runQuery(bvh, moving, pool);
    EXPECT_EQ(r.bodies.size(), 100u);
    r = runQuery(bvh, Bounds{}, pool);
    EXPECT_TRUE(r.bodies.empty());
}

TEST(StaticBvh, SameResultForOneAndTwoThreads) {
    // 200 x 200 cells = 80,000 triangles: above the parallel-build threshold, so the build is checked too.
    const Shape terrain = terrainShape(200, 100);
    std::vector<StaticPrimitive> prims;
    appendStaticPrimitives(terrain, {}, 0, prims);
    const Shape box = buildShape(BoxDef{{1, 1, 1}});
    for (std::uint32_t b = 1; b < 200; ++b) appendStaticPrimitives(box, {{float(b) - 100, 1, 0}, {}}, b, prims);
    const Bounds moving = randomBoxes(5000, 100, -3, 4, 11, &prims);

    TaskPool one(1), two(2);
    StaticBvh a, b;
    a.build(prims, one);
    b.build(prims, two);
    const StaticBvh::Tree &ta = *a.trees()[0], &tb = *b.trees()[0];
    ASSERT_EQ(ta.nodes.size(), tb.nodes.size());
    EXPECT_EQ(std::memcmp(ta.nodes.data(), tb.nodes.data(), ta.nodes.size() * sizeof(StaticBvh::Node)), 0);
    ASSERT_EQ(ta.primitives.size(), tb.primitives.size());
    EXPECT_EQ(std::memcmp(ta.primitives.data(), tb.primitives.data(), ta.primitives.size() * sizeof(ta.primitives[0])),
              0);

    const Result r1 = runQuery(a, moving, one), r2 = runQuery(a, moving, two), r3 = runQuery(b, moving, two);
    EXPECT_EQ(r1.bodies, r2.bodies);
    EXPECT_EQ(r1.triangles, r2.triangles);
    ASSERT_EQ(r1.meshes.size(), r2.meshes.size());
    EXPECT_EQ(std::memcmp(r1.meshes.data(), r2.meshes.data(), r1.meshes.size() * sizeof(MeshPair)), 0);
    EXPECT_EQ(r1.triangles, r3.triangles);
    EXPECT_EQ(flatten(r1), bruteForce(moving, prims));
}

/// SAH cost (the measure of StaticBvhStats::sahCost: 1 for the root plus the relative area of every other node and
/// every primitive) of a tree of the same shape as StaticBvh's (four-wide, a node of up to four primitives holds
/// them as lanes, larger ones split twice) whose splits are object medians along the longest centroid axis: the
/// usual cheap baseline.
double medianTreeCost(std::vector<StaticPrimitive> prims) {
    auto area = [](const Aabb& b) {
        const Vec3 d = b.max - b.min;
        return double(d.x) * d.y + double(d.y) * d.z + double(d.z) * d.x;
    };
    using It = std::vector<StaticPrimitive>::iterator;
    auto bounds = [](It first, It last) {
        Aabb b = first->box;
        for (It it = first; it != last; ++it) {
            b.min = {std::min(b.min.x, it->box.min.x), std::min(b.min.y, it->box.min.y),
                     std::min(b.min.z, it->box.min.z)};
            b.max = {std::max(b.max.x, it->box.max.x), std::max(b.max.y, it->box.max.y),
                     std::max(b.max.z, it->box.max.z)};
        }
        return b;
    };
    auto medianSplit = [](It first, It last) {
        Vec3 lo = first->box.min + first->box.max, hi = lo;
        for (It it = first; it != last; ++it) {
            const Vec3 c = it->box.min + it->box.max;
            lo = {std::min(lo.x, c.x), std::min(lo.y, c.y), std::min(lo.z, c.z)};
            hi = {std::max(hi.x, c.x), std::max(hi.y, c.y), std::max(hi.z, c.z)};
        }
        const Vec3 e = hi - lo;
        const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
        auto key = [axis](const StaticPrimitive& p) {
            const Vec3 c = p.box.min + p.box.max;
            return axis == 0 ? c.x : axis == 1 ? c.y : c.z;
        };
        const It mid = first + (last - first) / 2;
        std::nth_element(first, mid, last, [&](const auto& a, const auto& b) { return key(a) < key(b); });
        return mid;
    };
    const double rootArea = area(bounds(prims.begin(), prims.end()));
    double cost = 1;
    std::vector<std::pair<It, It>> stack{{prims.begin(), prims.end()}};
    while (!stack.empty()) {
        const auto [first, last] = stack.back();
        stack.pop_back();
        std::vector<std::pair<It, It>> children;
        if (last - first <= 4) {
            for (It it = first; it != last; ++it) children.push_back({it, it + 1});
        } else {
            const It mid = medianSplit(first, last);
            for (auto [f, l] : {std::pair{first, mid}, std::pair{mid, last}}) {
                if (l - f > 1) {
                    const It m = medianSplit(f, l);
                    children.push_back({f, m});
                    children.push_back({m, l});
                } else {
                    children.push_back({f, l});
                }
            }
        }
        for (auto [f, l] : children) {
            cost += area(bounds(f, l)) / rootArea;
            if (l - f > 1) stack.push_back({f, l});
        }
    }
    return cost;
}

TEST(StaticBvh, SahTreeBeatsMedianSplitsAndStaysShallow) {
    TaskPool pool(2);
    // A terrain plus clusters of small boxes and a few long thin ones: the mix a median split handles badly.
    const Shape terrain = terrainShape(100);
    std::vector<StaticPrimitive> prims;
    appendStaticPrimitives(terrain, {}, 0, prims);
    std::mt19937 rng(12);
    std::normal_distribution<float> g(0, 1);
    std::uniform_real_distribution<float> u(-50, 50);
    std::uint32_t body = 1;
    for (int cluster = 0; cluster < 8; ++cluster) {
        const Vec3 c{u(rng), 10 + 0.2f * u(rng), u(rng)};
        for (int k = 0; k < 500; ++k, ++body) {
            const Vec3 p = c + Vec3{g(rng), g(rng), g(rng)};
            prims.push_back({{p - Vec3{0.1f, 0.1f, 0.1f}, p + Vec3{0.1f, 0.1f, 0.1f}}, body, kWholeBody});
        }
    }
    for (int k = 0; k < 40; ++k, ++body) {
        const float z = u(rng);
        prims.push_back({{{-50, 4, z}, {50, 4.2f, z + 0.2f}}, body, kWholeBody});
    }
    StaticBvh bvh;
    bvh.build(prims, pool);
    const StaticBvhStats s = bvh.stats();
    const double median = medianTreeCost(prims);
    EXPECT_LT(s.sahCost, 0.75 * median) << "SAH " << s.sahCost << " vs median " << median;
    // log4(24,040) is about 7.3 (the tree has 9 levels); a sound SAH tree stays close to it.
    EXPECT_LE(s.depth, 14u);
    EXPECT_EQ(s.primitives, prims.size());

    // On the terrain alone (a regular grid, where the median is already good) SAH still does better (0.83x).
    std::vector<StaticPrimitive> terrainOnly(prims.begin(), prims.begin() + 20000);
    bvh.build(terrainOnly, pool);
    EXPECT_LT(bvh.stats().sahCost, 0.95 * medianTreeCost(terrainOnly));
    EXPECT_LE(bvh.stats().depth, 10u);
}

}  // namespace
}  // namespace rubble::detail
