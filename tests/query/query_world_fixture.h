#pragma once
// A world of every shape kind for the query tests, and the brute-force answers the queries are checked against:
// every body, every compound child and every triangle tested one by one, with no tree and no filter shortcuts.
// Poses are read back through the public API (World::transform), shapes are built a second time from their
// definitions, so the reference shares only the per-shape tests with the code under test (those are checked against
// closed forms and GJK searches in ray_cast_test.cpp and shape_cast_test.cpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <vector>

#include "narrowphase/gjk.h"
#include "query/query_reference.h"
#include "query/ray_cast.h"
#include "query/shape_cast.h"
#include "rubble/query.h"
#include "rubble/world.h"
#include "shapes/shape.h"

namespace rubble::test {

inline Transform composePose(const Transform& outer, const Transform& inner) {
    return {apply(outer, inner.position), outer.rotation * inner.rotation};
}

/// Vertices of triangle t of a mesh or heightfield in the shape's frame, from the definitions' own numbering.
inline std::array<Vec3, 3> shapeTriangle(const detail::Shape& s, std::uint32_t t) {
    if (s.kind == detail::ShapeKind::TriangleMesh) {
        const auto& m = *s.mesh;
        return {m.vertices[m.indices[3 * t]], m.vertices[m.indices[3 * t + 1]], m.vertices[m.indices[3 * t + 2]]};
    }
    const auto& f = *s.heightfield;
    const std::uint32_t cell = t / 2, r = cell / (f.columns - 1), c = cell % (f.columns - 1);
    auto at = [&](std::uint32_t row, std::uint32_t col) {
        return Vec3{float(col) * f.spacingX, f.heights[row * f.columns + col], float(row) * f.spacingZ};
    };
    if (t % 2 == 0) return {at(r, c), at(r + 1, c), at(r + 1, c + 1)};
    return {at(r, c), at(r + 1, c + 1), at(r, c + 1)};
}

inline std::uint32_t triangleCount(const detail::Shape& s) {
    if (s.kind == detail::ShapeKind::TriangleMesh) return s.mesh->triangleCount();
    return 2 * (s.heightfield->rows - 1) * (s.heightfield->columns - 1);
}

/// The unit direction the queries make of `d` (normalised in double, rounded once): the reference must use the very
/// same one, or grazing rays could go different ways.
inline Vec3 queryDirection(Vec3 d) {
    const double len = std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z);
    return {float(d.x / len), float(d.y / len), float(d.z / len)};
}

/// Brute-force answers over every body of a world.
class QueryReference {
public:
    explicit QueryReference(World& world) : world_(world) {}

    ShapeId addShape(const ShapeDef& def) {
        const ShapeId id = world_.createShape(def);
        shapes_[id.index] = detail::buildShape(def);
        return id;
    }
    const detail::Shape& shapeOf(BodyId b) const { return shapes_.at(world_.bodyShape(b).index); }

    bool accepts(BodyId b, const QueryFilter& f) const {
        const CollisionFilter cf = world_.filter(b);
        if ((cf.category & f.mask) == 0 || (f.category & cf.mask) == 0 || b == f.ignore) return false;
        const BodyType type = world_.bodyType(b);
        if (!(type == BodyType::Static      ? f.includeStatic
              : type == BodyType::Kinematic ? f.includeKinematic
                                            : f.includeDynamic))
            return false;
        return !f.accept || f.accept(b);
    }

    /// Calls fn(shape, pose, child) for each convex piece of a solid body.
    template <class F>
    void forPieces(BodyId b, F&& fn) const {
        const detail::Shape& s = shapeOf(b);
        const Transform pose = world_.transform(b);
        if (s.kind != detail::ShapeKind::Compound) return fn(s, pose, kNoIndex);
        for (std::uint32_t i = 0; i < s.children.size(); ++i)
            fn(*s.children[i].shape, composePose(pose, s.children[i].local), i);
    }

    /// Every hit of the ray, sorted as castRayAll sorts.
    std::vector<RayHit> rayAll(Vec3 origin, Vec3 direction, float maxT, const QueryFilter& f = {}) const {
        const Vec3 dir = queryDirection(direction);
        std::vector<RayHit> hits;
        const detail::Ray ray{origin, dir, maxT};
        for (const BodyId b : world_.bodies()) {
            if (!accepts(b, f)) continue;
            const detail::Shape& s = shapeOf(b);
            const Transform pose = world_.transform(b);
            if (s.staticOnly()) {
                const detail::Ray local = detail::toLocal(pose, ray);
                for (std::uint32_t t = 0; t < triangleCount(s); ++t) {
                    const auto tri = shapeTriangle(s, t);
                    detail::SurfaceHit h;
                    if (detail::rayTriangle(local, tri[0], tri[1], tri[2], f.hitBackFaces, h))
                        hits.push_back({b, origin + dir * h.t, rotate(pose.rotation, h.normal), h.t, t, kNoIndex});
                }
                continue;
            }
            // Into the body's frame, then the child's: the same roundings as the world's path, so that grazing rays
            // go the same way in both.
            const detail::Ray local = detail::toLocal(pose, ray);
            auto test = [&](const detail::Shape& piece, const detail::Ray& pieceRay, Quat toWorld,
                            std::uint32_t child) {
                detail::SurfaceHit h;
                const detail::RayResult r = detail::rayConvex(piece, pieceRay, h);
                if (r == detail::RayResult::Miss || (r == detail::RayResult::StartsInside && !f.hitFromInside)) return;
                const Vec3 n = r == detail::RayResult::StartsInside ? -dir : rotate(toWorld, h.normal);
                hits.push_back({b, origin + dir * h.t, n, h.t, kNoIndex, child});
            };
            if (s.kind != detail::ShapeKind::Compound) {
                test(s, local, pose.rotation, kNoIndex);
            } else {
                for (std::uint32_t i = 0; i < s.children.size(); ++i)
                    test(*s.children[i].shape, detail::toLocal(s.children[i].local, local),
                         pose.rotation * s.children[i].local.rotation, i);
            }
        }
        std::sort(hits.begin(), hits.end(), [](const RayHit& a, const RayHit& b) {
            if (a.distance != b.distance) return a.distance < b.distance;
            if (a.body.index != b.body.index) return a.body.index < b.body.index;
            if (a.child != b.child) return a.child < b.child;
            return a.triangle < b.triangle;
        });
        return hits;
    }

    /// Calls fn(body, gjkShape, child, triangle) for every convex piece and every non-degenerate triangle of every
    /// accepted body; triangle vertices live in `storage` during the call.
    template <class F>
    void forEveryPiece(const QueryFilter& f, F&& fn) const {
        for (const BodyId b : world_.bodies()) {
            if (!accepts(b, f)) continue;
            const detail::Shape& s = shapeOf(b);
            if (s.staticOnly()) {
                const Transform pose = world_.transform(b);
                for (std::uint32_t t = 0; t < triangleCount(s); ++t) {
                    const auto tri = shapeTriangle(s, t);
                    if (detail::degenerateTriangle(tri[0], tri[1], tri[2])) continue;
                    const Vec3 storage[3] = {tri[0], tri[1], tri[2]};
                    fn(b, detail::gjkTriangle(storage, pose), kNoIndex, t);
                }
                continue;
            }
            forPieces(b, [&](const detail::Shape& piece, const Transform& p, std::uint32_t child) {
                fn(b, detail::gjkShapeOf(piece, p), child, kNoIndex);
            });
        }
    }

private:
    World& world_;
    std::map<unsigned, detail::Shape> shapes_;
};

/// A random world of `count` bodies of every kind (spheres, boxes, capsules, hulls, compounds; static, kinematic and
/// dynamic) in a 60 m cube, plus a bumpy static mesh with a few zero-area triangles below it and a tilted static
/// heightfield. Dynamic bodies get random velocities; nothing has gravity.
inline std::vector<BodyId> buildMixedWorld(QueryReference& ref, World& world, std::uint32_t count, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1), size(0.2f, 1.2f);
    std::vector<ShapeId> shapes;
    shapes.push_back(ref.addShape(SphereDef{0.7f}));
    shapes.push_back(ref.addShape(BoxDef{{0.8f, 0.4f, 1.1f}}));
    shapes.push_back(ref.addShape(CapsuleDef{0.4f, 0.9f}));
    for (int h = 0; h < 2; ++h) {
        ConvexHullDef hull;
        for (int i = 0; i < 14; ++i) hull.points.push_back(Vec3{u(rng), u(rng), u(rng)} * size(rng));
        shapes.push_back(ref.addShape(hull));
    }
    CompoundDef compound;
    compound.children.push_back({SphereDef{0.5f}, {{0, 1, 0}, {}}});
    compound.children.push_back({BoxDef{{0.6f, 0.3f, 0.3f}}, {{0.2f, -0.5f, 0}, Quat::fromAxisAngle({0, 0, 1}, 0.4f)}});
    compound.children.push_back({CapsuleDef{0.2f, 0.5f}, {{-0.6f, 0, 0.3f}, Quat::fromAxisAngle({1, 0, 0}, 1.2f)}});
    shapes.push_back(ref.addShape(compound));

    std::vector<BodyId> bodies;
    for (std::uint32_t i = 0; i < count; ++i) {
        BodyDef def;
        def.shape = shapes[rng() % shapes.size()];
        const int kind = int(rng() % 10);
        def.type = kind < 3 ? BodyType::Static : kind < 4 ? BodyType::Kinematic : BodyType::Dynamic;
        def.position = Vec3{u(rng), u(rng), u(rng)} * 30.0f;
        def.orientation = randomRotation(rng);
        if (def.type != BodyType::Static) {
            def.linearVelocity = Vec3{u(rng), u(rng), u(rng)} * 3.0f;
            def.angularVelocity = Vec3{u(rng), u(rng), u(rng)};
        }
        def.gravityScale = 0;
        def.filter.category = 1u << (rng() % 4);
        bodies.push_back(world.createBody(def));
    }

    // Terrain: 24 x 24 cells over [-36, 36]^2 at y = -32 + bumps, plus zero-area triangles.
    TriangleMeshDef mesh;
    const int cells = 24;
    for (int r = 0; r <= cells; ++r)
        for (int c = 0; c <= cells; ++c)
            mesh.vertices.push_back(
                {-36 + 3.0f * c, -32 + 1.5f * std::sin(0.7f * c) * std::cos(0.5f * r), -36 + 3.0f * r});
    for (int r = 0; r < cells; ++r)
        for (int c = 0; c < cells; ++c) {
            const auto v = [&](int rr, int cc) { return std::uint32_t(rr * (cells + 1) + cc); };
            mesh.indices.insert(mesh.indices.end(), {v(r, c), v(r + 1, c), v(r + 1, c + 1)});
            mesh.indices.insert(mesh.indices.end(), {v(r, c), v(r + 1, c + 1), v(r, c + 1)});
        }
    mesh.indices.insert(mesh.indices.end(), {0, 0, 5, 3, 4, 5, 7, 7, 7});  // a repeated vertex, collinear, a point
    BodyDef ground;
    ground.type = BodyType::Static;
    ground.shape = ref.addShape(mesh);
    bodies.push_back(world.createBody(ground));

    HeightfieldDef field;
    field.rows = 12;
    field.columns = 14;
    for (std::uint32_t i = 0; i < field.rows * field.columns; ++i) field.heights.push_back(u(rng));
    field.spacing = {2.5f, 1.5f, 2.0f};
    BodyDef hill;
    hill.type = BodyType::Static;
    hill.shape = ref.addShape(field);
    hill.position = {-10, 31, -8};
    hill.orientation = Quat::fromAxisAngle({1, 0.3f, 0}, 0.5f);
    bodies.push_back(world.createBody(hill));
    return bodies;
}

/// A ray from somewhere in a 90 m cube, aimed within a metre of a random point of the world (a body's position
/// when `world` is given) or in a random direction, with a random reach (sometimes unbounded).
struct RandomRay {
    Vec3 origin, dir;
    float maxT;
};
inline RandomRay randomRay(std::mt19937& rng, const World* world = nullptr) {
    std::uniform_real_distribution<float> u(-45, 45), reach(5, 120), jitter(-1, 1);
    const float maxT = rng() % 4 == 0 ? std::numeric_limits<float>::infinity() : reach(rng);
    const Vec3 origin{u(rng), u(rng), u(rng)};
    if (world == nullptr || rng() % 5 == 0) return {origin, randomUnit(rng), maxT};
    const std::vector<BodyId> bodies = world->bodies();
    const Vec3 target = world->position(bodies[rng() % bodies.size()]) + Vec3{jitter(rng), jitter(rng), jitter(rng)};
    const Vec3 d = target - origin;
    return {origin, d / length(d), maxT};
}

}  // namespace rubble::test
