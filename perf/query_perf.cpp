// Scene queries: rays per second (closest hit and all hits) and sphere casts against S3 (4,000 bodies on a
// 20,000-triangle terrain) and S4 (100,000 spheres in a 200 m cube), each after one step of the scene, and the cost of
// bringing the moving bodies' query tree up to date: a full SAH build, a refit, and the first query after a step.
// Items per second are rays (or casts) per second on one thread.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bounds/bounds.h"
#include "broadphase/static_bvh.h"
#include "core/parallel.h"
#include "query/tree_queries.h"
#include "rubble/scene.h"
#include "rubble/world.h"

namespace {

using namespace rubble;

struct Ray {
    Vec3 origin, dir;
};

/// One world per scene file, stepped once, shared by the benchmarks (loading S4 takes a while).
World& sceneWorld(const char* file) {
    struct Entry {
        std::string file;
        std::unique_ptr<World> world;
    };
    static std::vector<Entry> worlds;
    for (Entry& e : worlds)
        if (e.file == file) return *e.world;
    Scene scene = loadScene(std::string(RUBBLE_SOURCE_DIR "/scenes/") + file);
    scene.settings.threads = 1;
    auto world = std::make_unique<World>(scene.settings);
    instantiate(scene, *world);
    world->step(scene.settings.timeStep);
    worlds.push_back({file, std::move(world)});
    return *worlds.back().world;
}

Vec3 unit(Vec3 v) { return v / length(v); }

/// S3: half picking rays (from a camera 40 m up at the pile's edge, down into the pile and the terrain), half bullets
/// (level shots across the pile from outside it).
std::vector<Ray> pileRays(std::uint32_t n) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<Ray> rays;
    for (std::uint32_t i = 0; i < n; ++i) {
        if (i % 2 == 0) {
            const Vec3 eye{-40, 40, -40}, target{25 * u(rng), 5 * u(rng), 25 * u(rng)};
            rays.push_back({eye, unit(target - eye)});
        } else {
            const float a = 3.14159265f * u(rng);
            const Vec3 from{45 * std::cos(a), 8 + 10 * u(rng), 45 * std::sin(a)};
            const Vec3 to{25 * u(rng), 8 + 10 * u(rng), 25 * u(rng)};
            rays.push_back({from, unit(to - from)});
        }
    }
    return rays;
}

/// S4: from random points of the cube in random directions.
std::vector<Ray> sparseRays(std::uint32_t n) {
    std::mt19937 rng(6);
    std::uniform_real_distribution<float> u(-100, 100);
    std::normal_distribution<float> g;
    std::vector<Ray> rays;
    for (std::uint32_t i = 0; i < n; ++i) rays.push_back({{u(rng), u(rng), u(rng)}, unit({g(rng), g(rng), g(rng)})});
    return rays;
}

constexpr std::uint32_t kRays = 4096;

void closestRays(benchmark::State& state, const char* file, std::vector<Ray> (*make)(std::uint32_t), float reach) {
    const World& world = sceneWorld(file);
    const std::vector<Ray> rays = make(kRays);
    world.castRay(rays[0].origin, rays[0].dir, reach);  // brings the query trees up to date outside the timing
    std::size_t hits = 0;
    for (auto _ : state) {
        hits = 0;
        for (const Ray& r : rays) hits += world.castRay(r.origin, r.dir, reach).has_value();
    }
    state.counters["hit_fraction"] = double(hits) / kRays;
    state.SetItemsProcessed(std::int64_t(state.iterations()) * kRays);
}

void allRays(benchmark::State& state, const char* file, std::vector<Ray> (*make)(std::uint32_t), float reach) {
    const World& world = sceneWorld(file);
    const std::vector<Ray> rays = make(kRays);
    std::vector<RayHit> hits;
    world.castRay(rays[0].origin, rays[0].dir, reach);
    for (auto _ : state) {
        hits.clear();
        for (const Ray& r : rays) world.castRayAll(r.origin, r.dir, reach, hits);
        benchmark::DoNotOptimize(hits.data());
    }
    state.counters["hits_per_ray"] = double(hits.size()) / kRays;
    state.SetItemsProcessed(std::int64_t(state.iterations()) * kRays);
}

void sphereCasts(benchmark::State& state, const char* file, std::vector<Ray> (*make)(std::uint32_t), float reach) {
    const World& world = sceneWorld(file);
    const std::vector<Ray> rays = make(1024);
    world.castRay(rays[0].origin, rays[0].dir, reach);
    std::size_t hits = 0;
    for (auto _ : state) {
        hits = 0;
        for (const Ray& r : rays) hits += world.castSphere(r.origin, 0.3f, r.dir, reach).has_value();
    }
    state.counters["hit_fraction"] = double(hits) / 1024;
    state.SetItemsProcessed(std::int64_t(state.iterations()) * 1024);
}

constexpr float kUnbounded = INFINITY;

}  // namespace

BENCHMARK_CAPTURE(closestRays, S3_pile, "s3_mesh_pile.json", pileRays, kUnbounded)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(allRays, S3_pile, "s3_mesh_pile.json", pileRays, kUnbounded)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(sphereCasts, S3_pile, "s3_mesh_pile.json", pileRays, kUnbounded)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(closestRays, S4_sparse_50m, "s4_sparse.json", sparseRays, 50.0f)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(closestRays, S4_sparse_unbounded, "s4_sparse.json", sparseRays, kUnbounded)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(allRays, S4_sparse_50m, "s4_sparse.json", sparseRays, 50.0f)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(sphereCasts, S4_sparse_50m, "s4_sparse.json", sparseRays, 50.0f)->Unit(benchmark::kMillisecond);

namespace {

/// The boxes the query tree holds for S4's 100,000 spheres after one step.
detail::Bounds sparseBoxes() {
    std::mt19937 rng(42);
    std::uniform_real_distribution<float> u(-100, 100);
    detail::Bounds b;
    b.resize(100000);
    for (std::uint32_t i = 0; i < b.size(); ++i) {
        const float x = u(rng), y = u(rng), z = u(rng);
        b.minX[i] = x - 0.5f, b.minY[i] = y - 0.5f, b.minZ[i] = z - 0.5f;
        b.maxX[i] = x + 0.5f, b.maxY[i] = y + 0.5f, b.maxZ[i] = z + 0.5f;
    }
    return b;
}

/// A full SAH build of the moving bodies' query tree (what a query pays after bodies come or go).
void queryTreeBuild(benchmark::State& state) {
    const detail::Bounds b = sparseBoxes();
    detail::TaskPool pool(int(state.range(0)));
    std::vector<detail::StaticPrimitive> prims(b.size());
    for (std::uint32_t i = 0; i < b.size(); ++i)
        prims[i] = {{{b.minX[i], b.minY[i], b.minZ[i]}, {b.maxX[i], b.maxY[i], b.maxZ[i]}}, i, detail::kWholeBody};
    for (auto _ : state) {
        detail::StaticBvh bvh;
        bvh.build(prims, pool);
        benchmark::DoNotOptimize(bvh.trees()[0]->nodes.data());
    }
    state.SetItemsProcessed(std::int64_t(state.iterations()) * b.size());
}

/// A refit of the same tree (what a query pays after a step that only moved bodies).
void queryTreeRefit(benchmark::State& state) {
    detail::Bounds b = sparseBoxes();
    detail::TaskPool pool(1);
    std::vector<detail::StaticPrimitive> prims(b.size());
    for (std::uint32_t i = 0; i < b.size(); ++i)
        prims[i] = {{{b.minX[i], b.minY[i], b.minZ[i]}, {b.maxX[i], b.maxY[i], b.maxZ[i]}}, i, detail::kWholeBody};
    detail::StaticBvh bvh;
    bvh.build(prims, pool);
    detail::StaticBvh::Tree tree = *bvh.trees()[0];
    for (auto _ : state) benchmark::DoNotOptimize(detail::refitTree(tree, b));
    state.SetItemsProcessed(std::int64_t(state.iterations()) * b.size());
}

/// The first ray after a step of S4: boxes of every body at its pose (SIMD bounds kernel), refit, and the ray.
void firstRayAfterStep(benchmark::State& state) {
    Scene scene = loadScene(RUBBLE_SOURCE_DIR "/scenes/s4_sparse.json");
    scene.settings.threads = int(state.range(0));
    World world(scene.settings);
    instantiate(scene, world);
    world.step(scene.settings.timeStep);
    world.castRay({}, {1, 0, 0}, 10);  // the first build
    for (auto _ : state) {
        state.PauseTiming();
        world.step(scene.settings.timeStep);
        state.ResumeTiming();
        benchmark::DoNotOptimize(world.castRay({}, {1, 0, 0}, 10));
    }
}

/// The first ray after a body was spawned into S4 (a game firing a projectile each frame): refit, a build of the
/// small tree of bodies added since the last full build, and the ray; a full build every 12,500 spawns.
void firstRayAfterSpawn(benchmark::State& state) {
    Scene scene = loadScene(RUBBLE_SOURCE_DIR "/scenes/s4_sparse.json");
    scene.settings.threads = 1;
    World world(scene.settings);
    instantiate(scene, world);
    world.step(scene.settings.timeStep);
    world.castRay({}, {1, 0, 0}, 10);
    BodyDef bullet;
    bullet.shape = world.createShape(SphereDef{0.05f});
    float x = 0;
    for (auto _ : state) {
        bullet.position = {x += 0.01f, 0, 0};
        world.createBody(bullet);
        benchmark::DoNotOptimize(world.castRay({}, {1, 0, 0}, 10));
    }
}

}  // namespace

BENCHMARK(firstRayAfterSpawn)->Unit(benchmark::kMillisecond)->Iterations(200);
BENCHMARK(queryTreeBuild)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(queryTreeRefit)->Unit(benchmark::kMillisecond);
BENCHMARK(firstRayAfterStep)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->Iterations(30);
