// World queries against brute force over every body of a random world of every shape kind (query_world_fixture.h):
// rays (all hits and closest), filters, bodies moved, added and removed after a step, concurrent queries, sphere and
// shape casts, and overlaps.
//
// Tolerances: rays take the same per-shape tests as the reference, on the same float poses and frames, so the hits
// must agree to rounding (1e-5; the lists body for body, child for child, triangle for triangle). Casts are
// compared with the GJK search of query_reference.h: never past its contact by more than 1e-4 m (rounding over the
// world's 100 m), and short of it by at most 2e-3 m (the sweep tolerance over the closing speed). Overlaps are
// compared with GJK distances per piece, and pieces within 1e-5 m of touching may go either way.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <thread>
#include <vector>

#include "query/query_world_fixture.h"

namespace rubble::test {
namespace {

using detail::Aabb;

void expectSameHits(const std::vector<RayHit>& got, const std::vector<RayHit>& want, int ray) {
    ASSERT_EQ(got.size(), want.size()) << "ray " << ray;
    for (std::size_t i = 0; i < got.size(); ++i) {
        EXPECT_EQ(got[i].body, want[i].body) << "ray " << ray << " hit " << i;
        EXPECT_EQ(got[i].child, want[i].child) << "ray " << ray << " hit " << i;
        EXPECT_EQ(got[i].triangle, want[i].triangle) << "ray " << ray << " hit " << i;
        EXPECT_NEAR(got[i].distance, want[i].distance, 1e-5f * (1 + want[i].distance)) << "ray " << ray;
        EXPECT_LT(length(got[i].normal - want[i].normal), 1e-5f) << "ray " << ray;
        EXPECT_LT(length(got[i].point - want[i].point), 1e-4f) << "ray " << ray;
    }
}

/// Rays through the world, castRayAll and castRay against the reference. Returns the number of hits seen.
std::size_t compareRays(const World& world, const QueryReference& ref, std::uint32_t seed, int rays,
                        const QueryFilter& filter = {}) {
    std::mt19937 rng(seed);
    std::size_t total = 0;
    for (int i = 0; i < rays; ++i) {
        const RandomRay r = randomRay(rng, &world);
        std::vector<RayHit> got = {RayHit{}};  // castRayAll appends: what was there stays
        const std::size_t added = world.castRayAll(r.origin, r.dir, r.maxT, got, filter);
        EXPECT_EQ(added, got.size() - 1);
        got.erase(got.begin());
        const std::vector<RayHit> want = ref.rayAll(r.origin, r.dir, r.maxT, filter);
        expectSameHits(got, want, i);
        const std::optional<RayHit> closest = world.castRay(r.origin, r.dir, r.maxT, filter);
        EXPECT_EQ(closest.has_value(), !want.empty()) << "ray " << i;
        if (closest && !want.empty()) expectSameHits({*closest}, {want.front()}, i);
        total += want.size();
    }
    return total;
}

TEST(QueryWorld, CastRayAllMatchesBruteForceInAMixedWorld) {
    World world;
    QueryReference ref(world);
    buildMixedWorld(ref, world, 2000, 21);
    // Before any step: statics are still pending in the broad phase, moving bodies were never bounded.
    EXPECT_GT(compareRays(world, ref, 22, 150), 100u);
    world.step(1.0f / 60);
    EXPECT_GT(compareRays(world, ref, 23, 150), 100u);
}

TEST(QueryWorld, FiltersChooseTheBodiesSeen) {
    World world;
    QueryReference ref(world);
    const std::vector<BodyId> bodies = buildMixedWorld(ref, world, 600, 31);
    world.step(1.0f / 60);
    QueryFilter masks;
    masks.mask = 0b0101;  // categories 0 and 2 only
    masks.category = 0b0010;
    EXPECT_GT(compareRays(world, ref, 32, 60, masks), 10u);
    for (const int kind : {0, 1, 2}) {
        QueryFilter types;
        types.includeStatic = kind == 0;
        types.includeKinematic = kind == 1;
        types.includeDynamic = kind == 2;
        EXPECT_GT(compareRays(world, ref, 33 + kind, 60, types), 0u);
    }
    QueryFilter predicate;
    predicate.ignore = bodies[5];
    predicate.accept = [](BodyId b) { return b.index % 3 != 0; };
    EXPECT_GT(compareRays(world, ref, 36, 60, predicate), 10u);
    QueryFilter triangles;
    triangles.hitBackFaces = true;
    triangles.hitFromInside = false;
    EXPECT_GT(compareRays(world, ref, 37, 60, triangles), 10u);
}

TEST(QueryWorld, SeesBodiesMovedAddedAndRemovedSinceTheStep) {
    World world;
    QueryReference ref(world);
    std::vector<BodyId> bodies = buildMixedWorld(ref, world, 800, 41);
    world.step(1.0f / 60);
    compareRays(world, ref, 42, 40);  // builds the trees at these poses

    std::mt19937 rng(43);
    std::uniform_real_distribution<float> u(-30, 30);
    // Moved through the API (moving and static bodies alike): the tree is refitted, the static BVH edited.
    for (int i = 0; i < 60; ++i) {
        const BodyId b = bodies[rng() % (bodies.size() - 2)];
        world.setTransform(b, {u(rng), u(rng), u(rng)}, randomRotation(rng));
    }
    EXPECT_GT(compareRays(world, ref, 44, 60), 20u);

    // As many moving bodies removed as added (dense indices shuffle while the count stays: the refit path), and
    // static bodies removed and added (edits of the static BVH: tombstones and its secondary tree) ...
    const ShapeId shape = world.bodyShape(bodies[0]);
    for (int i = 0; i < 60; ++i) {
        const std::size_t k = rng() % (bodies.size() - 2);
        const BodyType type = world.bodyType(bodies[k]);
        world.destroyBody(bodies[k]);
        bodies.erase(bodies.begin() + std::ptrdiff_t(k));
        BodyDef def;
        def.shape = shape;
        def.type = type == BodyType::Static ? BodyType::Static : BodyType::Dynamic;
        def.position = {u(rng), u(rng), u(rng)};
        bodies.insert(bodies.begin(), world.createBody(def));
    }
    EXPECT_GT(compareRays(world, ref, 45, 60), 20u);
    // ... and more added than removed (a rebuild), without a step in between.
    for (int i = 0; i < 30; ++i) {
        BodyDef def;
        def.shape = shape;
        def.position = {u(rng), u(rng), u(rng)};
        world.createBody(def);
    }
    EXPECT_GT(compareRays(world, ref, 46, 60), 20u);

    // Steps move everything; fast bodies spread until the refitted tree is rebuilt for its cost.
    for (const BodyId b : world.bodies())
        if (world.bodyType(b) != BodyType::Static) world.setLinearVelocity(b, Vec3{u(rng), u(rng), u(rng)} * 0.5f);
    for (int s = 0; s < 8; ++s) {
        world.step(0.25f);
        compareRays(world, ref, 47 + std::uint32_t(s), 15);
    }
}

TEST(QueryWorld, ConcurrentQueriesAgreeWithSerialOnes) {
    World world;
    QueryReference ref(world);
    const std::vector<BodyId> bodies = buildMixedWorld(ref, world, 1000, 51);
    world.step(1.0f / 60);
    world.setTransform(bodies[3], {1, 2, 3}, {});  // the first query of each thread finds the trees stale
    std::mt19937 rng(52);
    std::vector<RandomRay> rays;
    for (int i = 0; i < 400; ++i) rays.push_back(randomRay(rng, &world));
    std::vector<std::vector<RayHit>> results(2);
    std::vector<std::thread> threads;
    for (int t = 0; t < 2; ++t)
        threads.emplace_back([&, t] {
            for (const RandomRay& r : rays) world.castRayAll(r.origin, r.dir, r.maxT, results[std::size_t(t)]);
        });
    for (std::thread& t : threads) t.join();
    std::vector<RayHit> serial;
    for (const RandomRay& r : rays) world.castRayAll(r.origin, r.dir, r.maxT, serial);
    for (const auto& result : results) {
        ASSERT_EQ(result.size(), serial.size());
        for (std::size_t i = 0; i < serial.size(); ++i) {
            EXPECT_EQ(result[i].body, serial[i].body);
            EXPECT_EQ(result[i].distance, serial[i].distance);
        }
    }
}

/// First contact of a cast over every piece and triangle, by the GJK search; a capsule around the whole sweep
/// (the swept volume of the cast's bounding sphere) screens out pieces it cannot reach.
struct CastReference {
    bool hit = false;
    double t = 0;
    BodyId body;
    bool ambiguous = false;
};

CastReference castReference(const QueryReference& ref, const std::vector<detail::GjkShape>& parts, float boundingRadius,
                            Vec3 start, Vec3 dir, float maxT) {
    detail::GjkShape swept;
    swept.core = detail::GjkShape::Core::Segment;
    swept.radius = boundingRadius + 1e-3f;
    swept.halfHeight = 0.5f * maxT;
    swept.pose = {start + dir * (0.5f * maxT), Quat::fromAxisAngle(cross({0, 1, 0}, dir), std::acos(dir.y))};
    if (std::fabs(dir.y) > 0.9999f) swept.pose.rotation = dir.y > 0 ? Quat{} : Quat{1, 0, 0, 0};
    CastReference best;
    ref.forEveryPiece({}, [&](BodyId b, const detail::GjkShape& piece, std::uint32_t, std::uint32_t triangle) {
        if (triangle != kNoIndex) {  // one-sided: skip triangles the cast meets from behind
            const Vec3* p = piece.points;
            if (dot(rotate(piece.pose.rotation, cross(p[1] - p[0], p[2] - p[0])), dir) >= 0) return;
        }
        if (detail::gjkDistance(swept, piece).status == detail::GjkStatus::Separated) return;
        for (const detail::GjkShape& part : parts) {
            const SweepReference r = sweepReference(part, dir, maxT, piece, 1.5e-4);
            if (r.kind == SweepReference::Kind::Miss) continue;
            if (r.kind == SweepReference::Kind::Ambiguous) {
                best.ambiguous = true;
                continue;
            }
            if (!best.hit || r.t < best.t) best.hit = true, best.t = r.t, best.body = b;
        }
    });
    return best;
}

void compareCast(const std::optional<ShapeCastHit>& got, const CastReference& want, int i) {
    if (want.ambiguous) return;
    ASSERT_EQ(got.has_value(), want.hit) << "cast " << i;
    if (!got) return;
    EXPECT_LE(got->distance, want.t + 1e-4) << "cast " << i << " went past the first contact";
    EXPECT_GE(got->distance, want.t - 2e-3) << "cast " << i;
    if (std::fabs(got->distance - want.t) > 1e-3) {
        EXPECT_EQ(got->body, want.body) << "cast " << i;
    }
    EXPECT_NEAR(length(got->normal), 1, 1e-4) << "cast " << i;
}

TEST(QueryWorld, CastSphereMatchesBruteForce) {
    World world;
    QueryReference ref(world);
    buildMixedWorld(ref, world, 250, 61);
    world.step(1.0f / 60);
    std::mt19937 rng(62);
    std::uniform_real_distribution<float> radius(0.05f, 1.5f);
    int hits = 0;
    for (int i = 0; i < 50; ++i) {
        const RandomRay r = randomRay(rng, &world);
        const float maxT = std::isfinite(r.maxT) ? r.maxT : 150;
        const float rad = radius(rng);
        detail::GjkShape sphere;
        sphere.radius = rad;
        sphere.pose.position = r.origin;
        const CastReference want = castReference(ref, {sphere}, rad, r.origin, r.dir, maxT);
        const auto got = world.castSphere(r.origin, rad, r.dir, maxT);
        compareCast(got, want, i);
        hits += got.has_value();
    }
    EXPECT_GT(hits, 10);
}

TEST(QueryWorld, CastShapeOfEveryKindMatchesBruteForce) {
    World world;
    QueryReference ref(world);
    buildMixedWorld(ref, world, 120, 71);
    world.step(1.0f / 60);
    const detail::Shape box = detail::buildShape(BoxDef{{0.5f, 0.3f, 0.8f}});
    const detail::Shape capsule = detail::buildShape(CapsuleDef{0.3f, 0.7f});
    const ConvexHullDef hullDef{{{0, 1, 0}, {1, -0.5f, 0}, {-1, -0.5f, 0.3f}, {0, -0.5f, -1}, {0.2f, 0.1f, 0.9f}}};
    const detail::Shape hull = detail::buildShape(hullDef);
    const ShapeId ids[] = {world.createShape(BoxDef{{0.5f, 0.3f, 0.8f}}), world.createShape(CapsuleDef{0.3f, 0.7f}),
                           world.createShape(hullDef)};
    const detail::Shape* shapes[] = {&box, &capsule, &hull};
    std::mt19937 rng(72);
    int hits = 0;
    for (int i = 0; i < 45; ++i) {
        const int k = i % 3;
        const RandomRay r = randomRay(rng, &world);
        const float maxT = std::isfinite(r.maxT) ? r.maxT : 150;
        const Transform start{r.origin, randomRotation(rng)};
        const detail::GjkShape part = detail::gjkShapeOf(*shapes[k], start);
        const Aabb& lb = shapes[k]->localBounds;
        const float bound = length(Vec3{std::max(std::fabs(lb.min.x), std::fabs(lb.max.x)),
                                        std::max(std::fabs(lb.min.y), std::fabs(lb.max.y)),
                                        std::max(std::fabs(lb.min.z), std::fabs(lb.max.z))});
        const CastReference want = castReference(ref, {part}, bound, r.origin, r.dir, maxT);
        const auto got = world.castShape(ids[k], start, r.dir, maxT);
        compareCast(got, want, i);
        hits += got.has_value();
    }
    EXPECT_GT(hits, 8);
}

TEST(QueryWorld, OverlapsMatchBruteForce) {
    World world;
    QueryReference ref(world);
    buildMixedWorld(ref, world, 600, 81);
    world.step(1.0f / 60);
    const ConvexHullDef hullDef{{{0, 2, 0}, {2, -1, 0}, {-2, -1, 0.6f}, {0, -1, -2}, {0.4f, 0.2f, 1.8f}}};
    CompoundDef compoundDef;
    compoundDef.children.push_back({SphereDef{1.5f}, {{0, 2, 0}, {}}});
    compoundDef.children.push_back({BoxDef{{1, 2, 0.5f}}, {{1, -1, 0}, Quat::fromAxisAngle({0, 1, 0}, 0.7f)}});
    const ShapeId hull = world.createShape(hullDef), compound = world.createShape(compoundDef);
    const detail::Shape hullShape = detail::buildShape(hullDef), compoundShape = detail::buildShape(compoundDef);

    std::mt19937 rng(82);
    std::uniform_real_distribution<float> u(-40, 40), size(0.2f, 6);
    std::size_t total = 0;
    for (int i = 0; i < 80; ++i) {
        const Vec3 c{u(rng), u(rng), u(rng)};
        // The query as GJK pieces, and the world's answer.
        std::vector<detail::GjkShape> parts;
        std::vector<BodyId> got;
        detail::Shape box;
        const int kind = i % 4;
        if (kind == 0) {
            const float r = size(rng);
            detail::GjkShape s;
            s.radius = r;
            s.pose.position = c;
            parts.push_back(s);
            world.overlapSphere(c, r, got);
        } else if (kind == 1) {
            const Vec3 h{size(rng), size(rng), size(rng)};
            box.kind = detail::ShapeKind::Box;
            box.halfExtents = h;
            parts.push_back(detail::gjkShapeOf(box, {c, {}}));
            world.overlapAabb(c - h, c + h, got);
        } else if (kind == 2) {
            const Transform pose{c, randomRotation(rng)};
            parts.push_back(detail::gjkShapeOf(hullShape, pose));
            world.overlapShape(hull, pose, got);
        } else {
            const Transform pose{c, randomRotation(rng)};
            for (const auto& child : compoundShape.children)
                parts.push_back(detail::gjkShapeOf(*child.shape, composePose(pose, child.local)));
            world.overlapShape(compound, pose, got);
        }
        // Brute force: the smallest GJK distance of each body to any part; within 1e-5 m of touching is either.
        std::map<unsigned, std::pair<BodyId, float>> nearest;
        ref.forEveryPiece({}, [&](BodyId b, const detail::GjkShape& piece, std::uint32_t, std::uint32_t) {
            for (const detail::GjkShape& part : parts) {
                const detail::GjkResult g = detail::gjkDistance(part, piece);
                const float d = g.status == detail::GjkStatus::Separated ? g.distance : -1.0f;
                auto [it, fresh] = nearest.try_emplace(b.index, b, d);
                if (!fresh) it->second.second = std::min(it->second.second, d);
            }
        });
        EXPECT_TRUE(std::is_sorted(got.begin(), got.end(), [](BodyId a, BodyId b) { return a.index < b.index; }));
        for (const auto& [slot, entry] : nearest) {
            const bool reported = std::find(got.begin(), got.end(), entry.first) != got.end();
            if (std::fabs(entry.second) < 1e-5f) continue;
            EXPECT_EQ(reported, entry.second < 0) << "query " << i << " body " << slot << " gap " << entry.second;
        }
        for (const BodyId b : got) EXPECT_TRUE(nearest.count(b.index)) << "query " << i;
        total += got.size();
    }
    EXPECT_GT(total, 30u);
}

}  // namespace
}  // namespace rubble::test
