// Sphere-, capsule-, box- and hull-triangle contact kernels (narrowphase/triangle_pairs.h) on one core.
// items_per_second counts pairs processed, manifolds_per_second the pairs that gave a manifold. Pose sets: resting
// (bodies lying on a flat 10 x 10 grid mesh with its adjacency flags, colliding with the triangles under them: face
// contacts and ghost-suppressed edges) and random (random triangles, random rotations, overlapping or within the
// margin: every feature kind). The hull is a 24-point rock (about 0.8 x 0.6 x 0.7 m; its face and edge counts are
// printed as counters).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "narrowphase/hull_pairs.h"
#include "narrowphase/triangle_pairs.h"
#include "shapes/mesh_adjacency.h"
#include "shapes/shape.h"

namespace {

using namespace rubble;
using namespace rubble::detail;

constexpr float kMargin = 0.05f;

struct Pair {
    Transform pose;  // body pose (sphere: position only)
    TriangleVertices tri;
    std::uint8_t flags;
};

Quat randomRotation(std::mt19937& rng) {
    std::normal_distribution<float> g;
    const float x = g(rng), y = g(rng), z = g(rng), w = g(rng);
    const float n = std::sqrt(x * x + y * y + z * z + w * w);
    return {x / n, y / n, z / n, w / n};
}

std::vector<Pair> makePairs(bool resting, float lift) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<Pair> pairs;
    if (resting) {
        TriangleMesh grid;
        const int n = 10;
        for (int r = 0; r <= n; ++r)
            for (int c = 0; c <= n; ++c) grid.vertices.push_back({float(c), 0.0f, float(r)});
        for (int r = 0; r < n; ++r)
            for (int c = 0; c < n; ++c) {
                const std::uint32_t p00 = r * (n + 1) + c, p10 = p00 + 1, p01 = p00 + n + 1, p11 = p01 + 1;
                grid.indices.insert(grid.indices.end(), {p00, p01, p11, p00, p11, p10});
            }
        const MeshAdjacency adj = buildMeshAdjacency(grid);
        while (pairs.size() < 4096) {
            const float x = 1 + 8 * u(rng), z = 1 + 8 * u(rng);
            // The two triangles of the cell under the body and the cell's neighbour along x.
            const std::uint32_t cell = std::uint32_t(z) * n + std::uint32_t(x);
            for (std::uint32_t t : {2 * cell, 2 * cell + 1, 2 * cell + 2}) {
                const std::uint32_t* i = &grid.indices[3 * t];
                pairs.push_back({{{x, lift - 0.01f, z}, Quat::fromAxisAngle({0, 1, 0}, 6.28f * u(rng))},
                                 {grid.vertices[i[0]], grid.vertices[i[1]], grid.vertices[i[2]]},
                                 adj.activeEdges[t]});
            }
        }
    } else {
        while (pairs.size() < 4096) {
            TriangleVertices tri{Vec3{2 * u(rng) - 1, 2 * u(rng) - 1, 2 * u(rng) - 1},
                                 Vec3{2 * u(rng) - 1, 2 * u(rng) - 1, 2 * u(rng) - 1},
                                 Vec3{2 * u(rng) - 1, 2 * u(rng) - 1, 2 * u(rng) - 1}};
            const float a = u(rng), b = u(rng) * (1 - a);
            const Vec3 on = tri[0] + (tri[1] - tri[0]) * a + (tri[2] - tri[0]) * b;
            const Vec3 off{u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f};
            pairs.push_back({{on + off * (2 * lift), randomRotation(rng)}, tri, kAllEdgesActive});
        }
    }
    return pairs;
}

template <class Kernel>
void run(benchmark::State& state, const std::vector<Pair>& pairs, Kernel kernel) {
    std::int64_t points = 0, manifolds = 0;
    for (auto _ : state) {
        for (const Pair& p : pairs) {
            Manifold m;
            const int count = kernel(p, m);
            points += count;
            manifolds += count > 0;
            benchmark::DoNotOptimize(m);
        }
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(pairs.size()));
    state.counters["points_per_pair"] =
        static_cast<double>(points) / static_cast<double>(state.iterations() * pairs.size());
    state.counters["manifolds_per_second"] =
        benchmark::Counter(static_cast<double>(manifolds), benchmark::Counter::kIsRate);
}

void sphere(benchmark::State& state, bool resting) {
    const float r = 0.5f;
    run(state, makePairs(resting, r), [&](const Pair& p, Manifold& m) {
        return collideSphereTriangle(p.pose.position, r, p.tri, p.flags, kMargin, m);
    });
}
void capsule(benchmark::State& state, bool resting) {
    const float r = 0.3f;
    run(state, makePairs(resting, r), [&](const Pair& p, Manifold& m) {
        // Lying along its local y rotated to horizontal (resting) or randomly posed.
        const Quat q = resting ? p.pose.rotation * Quat::fromAxisAngle({0, 0, 1}, 1.5707963f) : p.pose.rotation;
        return collideCapsuleTriangle(capsuleSegmentOf({p.pose.position, q}, 0.4f, r), p.tri, p.flags, kMargin, m);
    });
}
void box(benchmark::State& state, bool resting) {
    const Vec3 half{0.4f, 0.3f, 0.35f};
    run(state, makePairs(resting, half.y),
        [&](const Pair& p, Manifold& m) { return collideBoxTriangle(p.pose, half, p.tri, p.flags, kMargin, m); });
}

struct Rock {
    ConvexHull hull;
    HullAdjacency adjacency;
    float reach = 0;  // depth of the lowest vertex below the origin (unchanged by turns about y)
};
const Rock& rock() {
    static const Rock r = [] {
        std::mt19937 rng(17);
        std::uniform_real_distribution<float> u(-1, 1);
        std::vector<Vec3> cloud;
        while (cloud.size() < 24) {
            const Vec3 p{u(rng), u(rng), u(rng)};
            if (dot(p, p) <= 1) cloud.push_back({0.4f * p.x, 0.3f * p.y, 0.35f * p.z});
        }
        Rock k;
        k.hull = *buildShape(ConvexHullDef{cloud}).hull;
        k.adjacency = buildHullAdjacency(k.hull);
        for (const Vec3& v : k.hull.vertices) k.reach = std::max(k.reach, -v.y);
        return k;
    }();
    return r;
}
void hull(benchmark::State& state, bool resting) {
    const Rock& r = rock();
    run(state, makePairs(resting, r.reach), [&](const Pair& p, Manifold& m) {
        return collideHullTriangle(r.hull, r.adjacency, p.pose, p.tri, p.flags, kMargin, m);
    });
    state.counters["hull_faces"] = static_cast<double>(r.hull.faceCount());
    state.counters["hull_edges"] = static_cast<double>(r.adjacency.edges.size());
}

void BM_SphereTriangleResting(benchmark::State& state) { sphere(state, true); }
void BM_SphereTriangleRandom(benchmark::State& state) { sphere(state, false); }
void BM_CapsuleTriangleResting(benchmark::State& state) { capsule(state, true); }
void BM_CapsuleTriangleRandom(benchmark::State& state) { capsule(state, false); }
void BM_BoxTriangleResting(benchmark::State& state) { box(state, true); }
void BM_BoxTriangleRandom(benchmark::State& state) { box(state, false); }
void BM_HullTriangleResting(benchmark::State& state) { hull(state, true); }
void BM_HullTriangleRandom(benchmark::State& state) { hull(state, false); }

BENCHMARK(BM_SphereTriangleResting);
BENCHMARK(BM_SphereTriangleRandom);
BENCHMARK(BM_CapsuleTriangleResting);
BENCHMARK(BM_CapsuleTriangleRandom);
BENCHMARK(BM_BoxTriangleResting);
BENCHMARK(BM_BoxTriangleRandom);
BENCHMARK(BM_HullTriangleResting);
BENCHMARK(BM_HullTriangleRandom);

}  // namespace
