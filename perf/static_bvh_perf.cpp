// Static BVH: build cost (once per scene, or when edits force a merge) and the per-step query of moving boxes
// against static triangles, on S3's terrain (100 x 100 cells, y = 2 sin(x / 8) cos(z / 8), 20,000 triangles).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <random>
#include <vector>

#include "broadphase/static_bvh.h"
#include "core/parallel.h"
#include "scene/generators.h"
#include "shapes/shape.h"

namespace {

using namespace rubble;
using namespace rubble::detail;

/// Primitives of an S3-style terrain with cells x cells cells over [-50, 50]^2 (scaled up for larger counts, so
/// the triangle size stays S3's).
std::vector<StaticPrimitive> terrainPrimitives(std::uint32_t cells) {
    scene_detail::TerrainParams p;
    p.cells[0] = p.cells[1] = cells;
    const double half = 50.0 * cells / 100.0;
    p.min[0] = p.min[1] = -half;
    p.max[0] = p.max[1] = half;
    p.amplitude = 2;
    p.wavelength[0] = p.wavelength[1] = 8;
    const Shape shape = buildShape(scene_detail::generateTerrain(p));
    std::vector<StaticPrimitive> prims;
    appendStaticPrimitives(shape, {}, 0, prims);
    return prims;
}

float terrainHeight(float x, float z) { return 2 * std::sin(x / 8) * std::cos(z / 8); }

/// n boxes of half extent h (already fattened) in random order, resting in `layers` layers on the terrain over
/// [-side, side]^2.
Bounds pileOnTerrain(std::uint32_t n, float side, float h, int layers, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-side, side);
    Bounds b;
    b.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        const float x = u(rng), z = u(rng);
        const float y = terrainHeight(x, z) + h * float(1 + 2 * int(i % std::uint32_t(layers)));
        b.minX[i] = x - h, b.maxX[i] = x + h, b.minY[i] = y - h, b.maxY[i] = y + h, b.minZ[i] = z - h,
        b.maxZ[i] = z + h;
    }
    return b;
}

void BM_StaticBvhBuild(benchmark::State& state) {
    const std::vector<StaticPrimitive> prims = terrainPrimitives(std::uint32_t(state.range(0)));
    TaskPool pool(int(state.range(1)));
    StaticBvh bvh;
    for (auto _ : state) {
        bvh.build(prims, pool);
        benchmark::DoNotOptimize(bvh.trees()[0]->nodes.data());
    }
    state.counters["triangles"] = double(prims.size());
    state.counters["nodes"] = double(bvh.stats().nodes);
    state.counters["depth"] = double(bvh.stats().depth);
    state.counters["sah"] = bvh.stats().sahCost;
}
// 100 x 100 cells = 20,000 triangles (S3); 1000 x 1000 = 2,000,000.
BENCHMARK(BM_StaticBvhBuild)
    ->ArgsProduct({{100, 1000}, {1, 2}})
    ->ArgNames({"cells", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// A step's batch of edits: n unit boxes scattered over a 1 km square floor (issue 38's static world), built into
/// a tree on one thread, as the step does with the statics added since the last one.
void BM_StaticBvhBuildScattered(benchmark::State& state) {
    const auto n = std::uint32_t(state.range(0));
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> cell(-500, 499);
    std::vector<StaticPrimitive> prims;
    for (std::uint32_t i = 0; i < n; ++i) {
        const auto x = float(cell(rng)), z = float(cell(rng));
        prims.push_back({{{x - 0.5f, 0, z - 0.5f}, {x + 0.5f, 1, z + 0.5f}}, i, kWholeBody});
    }
    const auto quality = state.range(1) != 0 ? StaticBvh::BuildQuality::Quick : StaticBvh::BuildQuality::Sah;
    StaticBvh::Tree tree;
    for (auto _ : state) {
        StaticBvh::buildTree(tree, prims, nullptr, quality);
        benchmark::DoNotOptimize(tree.nodes.data());
    }
    state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_StaticBvhBuildScattered)
    ->ArgsProduct({{1000, 16000}, {0, 1}})
    ->ArgNames({"boxes", "quick"})
    ->Unit(benchmark::kMicrosecond);

/// Queries `moving` every iteration. Argument 1 (`resting`) = 1: the same boxes every time, as a resting pile, so
/// the query filters the hits it kept (see static_bvh.h); 0: the boxes alternate between two places a metre apart,
/// so every query walks the tree.
void runQuery(benchmark::State& state, const std::vector<StaticPrimitive>& prims, const Bounds& moving) {
    TaskPool pool(int(state.range(0)));
    const bool resting = state.range(1) != 0;
    StaticBvh bvh;
    bvh.build(prims, pool);
    Bounds moved = moving;
    for (std::uint32_t i = 0; i < moved.size(); ++i) moved.minX[i] += 1.0f, moved.maxX[i] += 1.0f;
    std::vector<BodyPair> bodies;
    std::vector<MeshPair> meshes;
    std::vector<std::uint32_t> triangles;
    bool there = false;
    for (auto _ : state) {
        bvh.query(resting || !there ? moving : moved, {}, pool, bodies, meshes, triangles);
        there = !there;
        benchmark::DoNotOptimize(triangles.data());
    }
    state.counters["pairs"] = double(meshes.size() + bodies.size());
    state.counters["triangles"] = double(triangles.size());
    state.SetItemsProcessed(state.iterations() * moving.size());
}

/// S3 at rest: 4,000 bodies of half size 0.5 (+ 0.05 margin) piled in layers over the middle 50 x 50 m of the
/// terrain, in S3's creation order (layer, then x, then z), jittered by up to a quarter of the 1.25 m pitch.
Bounds s3Pile() {
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> jitter(-0.3f, 0.3f);
    const float h = 0.55f;
    Bounds b;
    b.resize(4000);
    for (std::uint32_t i = 0; i < 4000; ++i) {
        const std::uint32_t layer = i / 1600, x = i % 1600 / 40, z = i % 40;
        const float px = -24.375f + 1.25f * float(x) + jitter(rng), pz = -24.375f + 1.25f * float(z) + jitter(rng);
        const float py = terrainHeight(px, pz) + h * float(1 + 2 * layer);
        b.minX[i] = px - h, b.maxX[i] = px + h, b.minY[i] = py - h, b.maxY[i] = py + h, b.minZ[i] = pz - h,
        b.maxZ[i] = pz + h;
    }
    return b;
}

void BM_StaticBvhQueryS3(benchmark::State& state) {
    static const std::vector<StaticPrimitive> prims = terrainPrimitives(100);
    static const Bounds moving = s3Pile();
    runQuery(state, prims, moving);
}
BENCHMARK(BM_StaticBvhQueryS3)
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->ArgNames({"threads", "resting"})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

/// 100,000 small boxes (half size 0.15) near the surface of the whole 20,000-triangle terrain, in random order
/// (no coherence between consecutive queries: the cache's worst case).
void BM_StaticBvhQuerySmallBoxes(benchmark::State& state) {
    static const std::vector<StaticPrimitive> prims = terrainPrimitives(100);
    static const Bounds moving = pileOnTerrain(100000, 50, 0.15f, 4, 2);
    runQuery(state, prims, moving);
}
BENCHMARK(BM_StaticBvhQuerySmallBoxes)
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->ArgNames({"threads", "resting"})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

/// Issue 19's static floor: side x side unit boxes added one at a time (as a level loads), then the first step's
/// static work: the commit and a query of 100 boxes falling onto the middle. Time: the first step's part only (the
/// hitch a player would see); the counter `add_us` is the cost per static body paid while adding.
void BM_StaticFloorFirstStep(benchmark::State& state) {
    const auto side = std::uint32_t(state.range(0));
    TaskPool pool(int(state.range(1)));
    std::vector<StaticPrimitive> floor;
    floor.reserve(std::size_t(side) * side);
    for (std::uint32_t i = 0; i < side; ++i)
        for (std::uint32_t j = 0; j < side; ++j) {
            const float x = float(i) - 0.5f * float(side), z = float(j) - 0.5f * float(side);
            floor.push_back({{{x - 0.5f, -1, z - 0.5f}, {x + 0.5f, 0, z + 0.5f}}, i * side + j, kWholeBody});
        }
    // Spheres of radius 0.5 (boxes fattened to 0.55) just above the floor's top at y = 0, over its middle.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-20, 20);
    Bounds falling;
    falling.resize(100);
    for (std::uint32_t i = 0; i < falling.size(); ++i) {
        const float x = u(rng), z = u(rng);
        falling.minX[i] = x - 0.55f, falling.maxX[i] = x + 0.55f, falling.minY[i] = -0.05f, falling.maxY[i] = 1.05f;
        falling.minZ[i] = z - 0.55f, falling.maxZ[i] = z + 0.55f;
    }
    std::vector<BodyPair> bodies;
    std::vector<MeshPair> meshes;
    std::vector<std::uint32_t> triangles;
    double addSeconds = 0;
    for (auto _ : state) {
        StaticBvh bvh;
        const auto addBegin = std::chrono::steady_clock::now();
        for (const StaticPrimitive& p : floor) bvh.insert({&p, 1}, pool);
        const auto stepBegin = std::chrono::steady_clock::now();
        bvh.query(falling, {}, pool, bodies, meshes, triangles);
        const auto stepEnd = std::chrono::steady_clock::now();
        benchmark::DoNotOptimize(bodies.data());
        addSeconds += std::chrono::duration<double>(stepBegin - addBegin).count();
        state.SetIterationTime(std::chrono::duration<double>(stepEnd - stepBegin).count());
    }
    state.counters["statics"] = double(floor.size());
    state.counters["add_us"] = 1e6 * addSeconds / double(state.iterations()) / double(floor.size());
    state.counters["pairs"] = double(bodies.size());
}
BENCHMARK(BM_StaticFloorFirstStep)
    ->ArgsProduct({{316, 1000}, {1, 2}})
    ->ArgNames({"side", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(5)  // the timed part is short and the adding long: the default would run it thousands of times
    ->UseManualTime();

}  // namespace
