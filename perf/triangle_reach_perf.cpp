// The triangle reach tests (narrowphase/triangle_reach.h) on one core, on bodies resting on a wavy grid mesh (1 m
// cells, 2 m amplitude, 8 m wavelength, like S3's terrain): each body with the triangles its bounds overlap (grown by
// the margin), the batch the stage hands over. items_per_second counts triangles.
//   BM_TriangleReach*/0 the tests one triangle at a time (the scalar form), /1 in SIMD lanes: same inputs, same
//     answers (tests/narrowphase/triangle_reach_test.cpp). BM_BoxTriangleAxes the same for the box kernel's SAT
//     (triangle_pairs.h), which the stage runs for boxes instead of a reach test.
//   BM_TriangleRun*/0 the exact kernel on every triangle of each body, /1 the wide tests first (for a box: its SAT)
//     and the kernel on the triangles they leave (a box's given its SAT's answer): the stage's way. Both give the same
//     manifolds.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include "narrowphase/triangle_pairs.h"
#include "narrowphase/triangle_reach.h"
#include "shapes/mesh_adjacency.h"
#include "shapes/shape.h"

namespace {

using namespace rubble;
using namespace rubble::detail;

constexpr float kMargin = 0.02f;
constexpr int kCells = 50;

enum class Body { Sphere, Capsule, Box };

float terrainHeight(float x, float z) {
    constexpr float kPi = 3.14159265f;
    return 2.0f * std::sin(2 * kPi * x / 8) * std::cos(2 * kPi * z / 8);
}

struct Terrain {
    TriangleMesh mesh;
    MeshAdjacency adjacency;
    Terrain() {
        for (int r = 0; r <= kCells; ++r)
            for (int c = 0; c <= kCells; ++c)
                mesh.vertices.push_back({float(c), terrainHeight(float(c), float(r)), float(r)});
        for (int r = 0; r < kCells; ++r)
            for (int c = 0; c < kCells; ++c) {
                const std::uint32_t p00 = r * (kCells + 1) + c, p10 = p00 + 1, p01 = p00 + kCells + 1, p11 = p01 + 1;
                mesh.indices.insert(mesh.indices.end(), {p00, p01, p11, p00, p11, p10});
            }
        adjacency = buildMeshAdjacency(mesh);
    }
};

/// One body and its triangles in SoA (padded as the wide tests read them) with their active edges.
struct BodyBatch {
    Vec3 center;
    CapsuleSegment capsule;
    TriangleBox box;
    float radius = 0;
    std::size_t count = 0;
    std::vector<float> lanes[9];
    std::vector<std::uint8_t> active;
    TriangleLanes view() const {
        return {{lanes[0].data(), lanes[3].data(), lanes[6].data()},
                {lanes[1].data(), lanes[4].data(), lanes[7].data()},
                {lanes[2].data(), lanes[5].data(), lanes[8].data()}};
    }
    TriangleVertices triangle(std::size_t k) const {
        TriangleVertices t;
        for (int v = 0; v < 3; ++v) t[v] = {lanes[3 * v][k], lanes[3 * v + 1][k], lanes[3 * v + 2][k]};
        return t;
    }
};

std::vector<BodyBatch> makeBodies(Body kind) {
    static const Terrain terrain;
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<BodyBatch> bodies;
    while (bodies.size() < 512) {
        BodyBatch b;
        const float x = 5 + 40 * u(rng), z = 5 + 40 * u(rng);
        // Resting on the surface or just above it, within a few centimetres.
        const float lift = 0.06f * u(rng) - 0.02f;
        Vec3 lo, hi;
        if (kind == Body::Sphere) {
            b.radius = 0.5f;
            b.center = {x, terrainHeight(x, z) + b.radius + lift, z};
            lo = b.center - Vec3{b.radius, b.radius, b.radius}, hi = b.center + Vec3{b.radius, b.radius, b.radius};
        } else if (kind == Body::Capsule) {
            const Quat q = Quat::fromAxisAngle({0, 1, 0}, 6.28f * u(rng)) *
                           Quat::fromAxisAngle({0, 0, 1}, 1.5707963f + 0.3f * (u(rng) - 0.5f));
            b.center = {x, terrainHeight(x, z) + 0.3f + lift, z};
            b.capsule = capsuleSegmentOf({b.center, q}, 0.5f, 0.3f);
            const Vec3 e{std::fabs(b.capsule.halfAxis.x) + 0.3f, std::fabs(b.capsule.halfAxis.y) + 0.3f,
                         std::fabs(b.capsule.halfAxis.z) + 0.3f};
            lo = b.center - e, hi = b.center + e;
        } else {
            const Quat q =
                Quat::fromAxisAngle({0, 1, 0}, 6.28f * u(rng)) * Quat::fromAxisAngle({1, 0, 0}, 0.4f * (u(rng) - 0.5f));
            b.center = {x, terrainHeight(x, z) + 0.5f + lift, z};
            b.box = triangleBox({b.center, q}, {0.5f, 0.5f, 0.5f});
            const float e = 0.5f * std::sqrt(3.0f);
            lo = b.center - Vec3{e, e, e}, hi = b.center + Vec3{e, e, e};
        }
        lo = lo - Vec3{kMargin, kMargin, kMargin}, hi = hi + Vec3{kMargin, kMargin, kMargin};
        std::vector<TriangleVertices> tris;
        for (int r = std::max(0, int(lo.z)); r <= std::min(kCells - 1, int(hi.z)); ++r)
            for (int c = std::max(0, int(lo.x)); c <= std::min(kCells - 1, int(hi.x)); ++c)
                for (std::uint32_t t : {std::uint32_t(2 * (r * kCells + c)), std::uint32_t(2 * (r * kCells + c) + 1)}) {
                    const std::uint32_t* i = &terrain.mesh.indices[3 * t];
                    const TriangleVertices tri{terrain.mesh.vertices[i[0]], terrain.mesh.vertices[i[1]],
                                               terrain.mesh.vertices[i[2]]};
                    const float ylo = std::min({tri[0].y, tri[1].y, tri[2].y});
                    const float yhi = std::max({tri[0].y, tri[1].y, tri[2].y});
                    if (yhi < lo.y || ylo > hi.y) continue;
                    tris.push_back(tri);
                    b.active.push_back(terrain.adjacency.activeEdges[t]);
                }
        if (tris.empty()) continue;
        b.count = tris.size();
        for (std::size_t k = 0; k < triangleLanesPadded(b.count); ++k)
            for (int v = 0; v < 3; ++v) {
                const Vec3 p = tris[std::min(k, b.count - 1)][v];
                b.lanes[3 * v].push_back(p.x), b.lanes[3 * v + 1].push_back(p.y), b.lanes[3 * v + 2].push_back(p.z);
            }
        bodies.push_back(std::move(b));
    }
    return bodies;
}

/// The stage's test per kind: the reach tests for spheres and capsules, the box kernel's whole SAT for boxes
/// (`axes`, whose kind marks the triangles left for the kernel).
void reachTests(Body kind, const BodyBatch& b, bool wide, bool* inReach, BoxTriangleAxis* axes) {
    switch (kind) {
        case Body::Sphere:
            (wide ? sphereTrianglesInReach : sphereTrianglesInReachScalar)(b.center, b.radius, kMargin, b.view(),
                                                                           b.count, inReach);
            break;
        case Body::Capsule:
            (wide ? capsuleTrianglesInReach : capsuleTrianglesInReachScalar)(b.capsule, kMargin, b.view(), b.count,
                                                                             inReach);
            break;
        case Body::Box:
            (wide ? boxTriangleAxes : boxTriangleAxesScalar)(b.box, kMargin, b.view(), b.count, axes);
            for (std::size_t k = 0; k < b.count; ++k) inReach[k] = axes[k].kind >= 0;
            break;
    }
}

/// The exact kernel; a box given its SAT's answer when `axis` is set.
int kernel(Body kind, const BodyBatch& b, std::size_t k, const BoxTriangleAxis* axis, Manifold& m) {
    const TriangleVertices t = b.triangle(k);
    switch (kind) {
        case Body::Sphere:
            return collideSphereTriangle(b.center, b.radius, t, b.active[k], kMargin, m);
        case Body::Capsule:
            return collideCapsuleTriangle(b.capsule, t, b.active[k], kMargin, m);
        case Body::Box:
            return axis ? collideBoxTriangle(b.box, t, b.active[k], kMargin, *axis, m)
                        : collideBoxTriangle(b.box, t, b.active[k], kMargin, m);
    }
    return 0;
}

std::size_t triangleCount(const std::vector<BodyBatch>& bodies) {
    std::size_t n = 0;
    for (const BodyBatch& b : bodies) n += b.count;
    return n;
}

/// What the reach tests write, sized for the longest run of triangles (padded to whole SIMD batches).
struct ReachOutputs {
    std::unique_ptr<bool[]> inReach;
    std::vector<BoxTriangleAxis> axes;

    explicit ReachOutputs(const std::vector<BodyBatch>& bodies) {
        std::size_t padded = 0;
        for (const BodyBatch& b : bodies) padded = std::max(padded, triangleLanesPadded(b.count));
        inReach = std::make_unique<bool[]>(padded);
        axes.resize(padded);
    }
};

void reach(benchmark::State& state, Body kind) {
    const std::vector<BodyBatch> bodies = makeBodies(kind);
    const bool wide = state.range(0) != 0;
    ReachOutputs out(bodies);
    bool* const inReach = out.inReach.get();
    BoxTriangleAxis* const axes = out.axes.data();
    std::int64_t kept = 0;
    for (auto _ : state) {
        for (const BodyBatch& b : bodies) {
            reachTests(kind, b, wide, inReach, axes);
            kept += std::count(inReach, inReach + b.count, true);
            benchmark::DoNotOptimize(inReach);
        }
    }
    const auto n = static_cast<std::int64_t>(triangleCount(bodies));
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * n);
    state.counters["kept_share"] = static_cast<double>(kept) / static_cast<double>(state.iterations() * n);
    state.counters["triangles_per_body"] = static_cast<double>(n) / static_cast<double>(bodies.size());
}

void runs(benchmark::State& state, Body kind) {
    const std::vector<BodyBatch> bodies = makeBodies(kind);
    const bool filtered = state.range(0) != 0;
    ReachOutputs out(bodies);
    bool* const inReach = out.inReach.get();
    BoxTriangleAxis* const axes = out.axes.data();
    std::int64_t manifolds = 0;
    for (auto _ : state) {
        for (const BodyBatch& b : bodies) {
            if (filtered)
                reachTests(kind, b, true, inReach, axes);
            else
                std::fill(inReach, inReach + b.count, true);
            for (std::size_t k = 0; k < b.count; ++k) {
                if (!inReach[k]) continue;
                Manifold m;
                manifolds += kernel(kind, b, k, filtered && kind == Body::Box ? &axes[k] : nullptr, m) > 0;
                benchmark::DoNotOptimize(m);
            }
        }
    }
    const auto n = static_cast<std::int64_t>(triangleCount(bodies));
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * n);
    state.counters["manifolds_per_triangle"] =
        static_cast<double>(manifolds) / static_cast<double>(state.iterations() * n);
}

void BM_TriangleReachSphere(benchmark::State& state) { reach(state, Body::Sphere); }
void BM_TriangleReachCapsule(benchmark::State& state) { reach(state, Body::Capsule); }
void BM_BoxTriangleAxes(benchmark::State& state) { reach(state, Body::Box); }
void BM_TriangleRunSphere(benchmark::State& state) { runs(state, Body::Sphere); }
void BM_TriangleRunCapsule(benchmark::State& state) { runs(state, Body::Capsule); }
void BM_TriangleRunBox(benchmark::State& state) { runs(state, Body::Box); }

}  // namespace

BENCHMARK(BM_TriangleReachSphere)->Arg(0)->Arg(1)->ArgName("wide");
BENCHMARK(BM_TriangleReachCapsule)->Arg(0)->Arg(1)->ArgName("wide");
BENCHMARK(BM_BoxTriangleAxes)->Arg(0)->Arg(1)->ArgName("wide");
BENCHMARK(BM_TriangleRunSphere)->Arg(0)->Arg(1)->ArgName("reach_tests");
BENCHMARK(BM_TriangleRunCapsule)->Arg(0)->Arg(1)->ArgName("reach_tests");
BENCHMARK(BM_TriangleRunBox)->Arg(0)->Arg(1)->ArgName("reach_tests");
