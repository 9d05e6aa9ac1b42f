// Multi-resolution grid broad phase: one findPairs per iteration (the whole per-step cost: level set-up, keys,
// radix sort, gather, cells, queries) on the shared scenarios at 1k..1M boxes, and on S4-like scenes (spheres of
// radius 0.5 fattened by their speed over one 60 Hz step) at 100k and 1M, on TaskPool(1) and TaskPool(2).
// items_per_second counts boxes; `pairs` is the size of the candidate list. BM_MultiResolutionGridPile: boxes piled
// onto one point, which must cost linear time.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "broadphase/multi_resolution_grid.h"
#include "core/parallel.h"
#include "support/broadphase_scenarios.h"

namespace {

using namespace rubble::detail;
using rubble::test::Scenario;

/// S4's broad-phase input: n spheres of radius 0.5 uniformly in a cube at 100k per (200 m)^3, each box grown by
/// |v| dt with speeds up to 5 m/s and dt = 1/60 (the fattening the AABB stage applies for speculative contacts).
Bounds makeS4Like(std::uint32_t n, std::uint32_t seed = 4) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const float side = 200.0f * std::cbrt(static_cast<float>(n) / 100000.0f);
    Bounds b;
    b.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        const float x = (unit(rng) - 0.5f) * side, y = (unit(rng) - 0.5f) * side, z = (unit(rng) - 0.5f) * side;
        const float half = 0.5f + 5.0f * unit(rng) / 60.0f;
        b.minX[i] = x - half, b.minY[i] = y - half, b.minZ[i] = z - half;
        b.maxX[i] = x + half, b.maxY[i] = y + half, b.maxZ[i] = z + half;
    }
    return b;
}

void run(benchmark::State& state, const Bounds& bounds, int threads) {
    TaskPool pool(threads);
    MultiResolutionGrid grid;
    std::vector<BodyPair> pairs;
    grid.findPairs(bounds, {}, pool, pairs);  // warm-up: buffers reach their steady size
    for (auto _ : state) {
        grid.findPairs(bounds, {}, pool, pairs);
        benchmark::DoNotOptimize(pairs.data());
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * bounds.size());
    state.counters["pairs"] = static_cast<double>(pairs.size());
    state.counters["levels"] = grid.levelCount();
    state.counters["cells"] = grid.cellCount();
    state.counters["max_per_cell"] = grid.maxBodiesPerCell();
    state.counters["threads"] = threads;
}

/// range(0): scenario; range(1): boxes; range(2): threads.
void BM_MultiResolutionGrid(benchmark::State& state) {
    const auto scenario = static_cast<Scenario>(state.range(0));
    const Bounds bounds = rubble::test::makeScenario(scenario, static_cast<std::uint32_t>(state.range(1)));
    state.SetLabel(std::string(rubble::test::scenarioName(scenario)));
    run(state, bounds, static_cast<int>(state.range(2)));
}

/// range(0): spheres (100k: S4; 1M: the same density in a 431 m cube); range(1): threads.
void BM_MultiResolutionGridS4(benchmark::State& state) {
    const Bounds bounds = makeS4Like(static_cast<std::uint32_t>(state.range(0)));
    state.SetLabel("s4_like");
    run(state, bounds, static_cast<int>(state.range(1)));
}

/// Bodies piled onto one point (issue 38: a `grid` generator with spacing 0): every pair overlaps, and the search
/// must cost time linear in the bodies under the pair budget. range(0): boxes; range(1): threads. "dropped" counts
/// the candidates past the budget.
void BM_MultiResolutionGridPile(benchmark::State& state) {
    const auto n = static_cast<std::uint32_t>(state.range(0));
    const Bounds bounds = rubble::test::pileAtOnePoint(n);
    TaskPool pool(static_cast<int>(state.range(1)));
    MultiResolutionGrid grid;
    std::vector<BodyPair> pairs;
    for (auto _ : state) {
        grid.findPairs(bounds, {}, pool, pairs);
        benchmark::DoNotOptimize(pairs.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * n);
    state.counters["pairs"] = static_cast<double>(pairs.size());
    state.counters["dropped"] = static_cast<double>(grid.droppedPairs());
}

void gridArgs(benchmark::internal::Benchmark* b) {
    b->ArgNames({"scenario", "boxes", "threads"});
    for (const Scenario s : {Scenario::Uniform, Scenario::Clustered, Scenario::MixedSizes})
        for (const long n : {1000L, 10000L, 100000L, 1000000L})
            for (const long threads : {1L, 2L}) b->Args({static_cast<long>(s), n, threads});
    b->Unit(benchmark::kMillisecond)->UseRealTime();
}

void s4Args(benchmark::internal::Benchmark* b) {
    b->ArgNames({"spheres", "threads"});
    for (const long n : {100000L, 1000000L})
        for (const long threads : {1L, 2L}) b->Args({n, threads});
    b->Unit(benchmark::kMillisecond)->UseRealTime();
}

BENCHMARK(BM_MultiResolutionGrid)->Apply(gridArgs);
BENCHMARK(BM_MultiResolutionGridS4)->Apply(s4Args);
BENCHMARK(BM_MultiResolutionGridPile)
    ->ArgNames({"boxes", "threads"})
    ->ArgsProduct({{4000, 16000, 64000}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
