// Sweep-and-prune and its radix sort. SAP runs on the shared broad-phase scenarios at S4's density from 1k to 1M
// boxes on 1 and 2 threads, cold (the kept order is forgotten, so every iteration radix-sorts) and steady (the
// boxes jiggle a little between iterations, as a simulation step would move them, so the insertion path and the
// kept order are what is measured). items_per_second counts bodies; "pairs" is the pairs found per call.
// Uniform 1M is SAP's worst case (each box meets about n / side candidates on the swept axis), so the big sizes
// run a fixed small number of iterations. BM_SweepAndPrunePile: boxes piled onto one point, which must cost linear
// time.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include "broadphase/radix_sort.h"
#include "broadphase/sweep_and_prune.h"
#include "core/parallel.h"
#include "support/broadphase_scenarios.h"

namespace {

using namespace rubble::detail;
using rubble::test::Scenario;

// Per-step motion of the steady variant, per axis. What decides whether the kept order pays is the motion in units
// of the spacing of the minima on the swept axis (side / n: 2 mm at 100k, 0.4 mm at 1M); 1 mm is about half a
// spacing at 100k, a slowly settling scene. Faster motion at these densities makes the insertion pass bail out to
// the radix sort, which the "insertion" counter shows.
constexpr float kSteadyJiggle = 0.001f;

enum class Mode { Cold, Steady };

/// range(0): bodies; range(1): threads; range(2): scenario; range(3): mode.
void BM_SweepAndPrune(benchmark::State& state) {
    const auto n = static_cast<std::uint32_t>(state.range(0));
    TaskPool pool(static_cast<int>(state.range(1)));
    const auto scenario = static_cast<Scenario>(state.range(2));
    const auto mode = static_cast<Mode>(state.range(3));
    Bounds bounds = rubble::test::makeScenario(scenario, n);
    std::vector<std::uint32_t> slots(n);
    std::iota(slots.begin(), slots.end(), 0u);
    // Jiggles are precomputed as alternating +d / -d offsets so the timed loop only applies them, and the scene
    // stays where it started however many iterations run.
    Bounds moved = bounds;
    rubble::test::jiggle(moved, kSteadyJiggle, 7);

    SweepAndPrune sap;
    std::vector<BodyPair> out;
    sap.findPairs(bounds, slots.data(), n, {}, pool, out);  // warm-up: buffers sized, order kept
    std::size_t pairs = 0, insertions = 0, calls = 0;
    for (auto _ : state) {
        if (mode == Mode::Cold) {
            sap.reset();
        } else {
            state.PauseTiming();
            std::swap(bounds, moved);
            state.ResumeTiming();
        }
        sap.findPairs(bounds, slots.data(), n, {}, pool, out);
        pairs += out.size();
        insertions += sap.lastUsedInsertionSort();
        ++calls;
        benchmark::DoNotOptimize(out.data());
    }
    state.counters["pairs"] = static_cast<double>(pairs) / static_cast<double>(calls);
    state.counters["insertion"] = static_cast<double>(insertions) / static_cast<double>(calls);
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * n);
    state.SetLabel(std::string(rubble::test::scenarioName(scenario)) + (mode == Mode::Cold ? "/cold" : "/steady"));
}

void sapArgs(benchmark::internal::Benchmark* b) {
    for (Scenario s : {Scenario::Uniform, Scenario::Clustered, Scenario::MixedSizes})
        for (int mode : {0, 1})
            for (std::int64_t n : {1'000, 10'000, 100'000, 1'000'000})
                for (int threads : {1, 2}) b->Args({n, threads, static_cast<std::int64_t>(s), mode});
}

/// range(0): keys; range(1): threads. (float key, uint32 value) pairs, the SAP's key form.
void BM_RadixSortFloatKeys(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    TaskPool pool(static_cast<int>(state.range(1)));
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> d(-200.0f, 200.0f);
    std::vector<float> source(n), keys(n);
    for (auto& k : source) k = d(rng);
    std::vector<std::uint32_t> values(n);
    RadixSortScratch scratch;
    for (auto _ : state) {
        state.PauseTiming();
        keys = source;
        std::iota(values.begin(), values.end(), 0u);
        state.ResumeTiming();
        radixSort(keys.data(), values.data(), n, scratch, pool);
        benchmark::DoNotOptimize(values.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * n));
}

/// Times sortPairs on copies of `source` with state.range(1) threads.
void timeSortPairs(benchmark::State& state, const std::vector<BodyPair>& source) {
    TaskPool pool(static_cast<int>(state.range(1)));
    std::vector<BodyPair> pairs;
    RadixSortScratch scratch;
    for (auto _ : state) {
        state.PauseTiming();
        pairs = source;
        state.ResumeTiming();
        sortPairs(pairs, pool, scratch);
        benchmark::DoNotOptimize(pairs.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * source.size()));
}

/// range(0): pairs; range(1): threads. Pair lists as the broad phase emits them (indices below 1M).
void BM_SortPairs(benchmark::State& state) {
    std::mt19937 rng(2);
    std::uniform_int_distribution<std::uint32_t> d(0, 999'999);
    std::vector<BodyPair> source(static_cast<std::size_t>(state.range(0)));
    for (auto& p : source) {
        const std::uint32_t a = d(rng), b = d(rng);
        p = {std::min(a, b), std::max(a, b)};
    }
    timeSortPairs(state, source);
}

/// range(0): pairs; range(1): threads. Pair lists of a resting pile: five pairs per body on average, each body with
/// neighbours a little above it in index, in random order (the counting sort by first body; BM_SortPairs' million
/// bodies take the radix sort).
void BM_SortPairsFewPerBody(benchmark::State& state) {
    std::mt19937 rng(3);
    std::vector<BodyPair> source(static_cast<std::size_t>(state.range(0)));
    const auto bodies = static_cast<std::uint32_t>(source.size() / 5);
    std::uniform_int_distribution<std::uint32_t> first(0, bodies - 1), offset(1, 200);
    for (auto& p : source) {
        const std::uint32_t a = first(rng);
        p = {a, a + offset(rng)};
    }
    timeSortPairs(state, source);
}

}  // namespace

/// Bodies piled onto one point (issue 38): every pair overlaps, and the sweep must cost time linear in the bodies
/// under the pair budget. range(0): boxes; range(1): threads. "dropped" counts the candidates past the budget.
void BM_SweepAndPrunePile(benchmark::State& state) {
    const auto n = static_cast<std::uint32_t>(state.range(0));
    const Bounds bounds = rubble::test::pileAtOnePoint(n);
    std::vector<std::uint32_t> slots(n);
    std::iota(slots.begin(), slots.end(), 0u);
    TaskPool pool(static_cast<int>(state.range(1)));
    SweepAndPrune sap;
    std::vector<BodyPair> out;
    for (auto _ : state) {
        sap.findPairs(bounds, slots.data(), n, {}, pool, out);
        benchmark::DoNotOptimize(out.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * n);
    state.counters["pairs"] = static_cast<double>(out.size());
    state.counters["dropped"] = static_cast<double>(sap.droppedPairs());
}

BENCHMARK(BM_SweepAndPrune)->Apply(sapArgs)->Unit(benchmark::kMillisecond)->MinTime(0.2)->UseRealTime();
BENCHMARK(BM_SweepAndPrunePile)
    ->ArgNames({"boxes", "threads"})
    ->ArgsProduct({{4000, 16000, 64000}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_RadixSortFloatKeys)
    ->ArgsProduct({{1'000'000}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(0.2)
    ->UseRealTime();
BENCHMARK(BM_SortPairs)
    ->ArgsProduct({{10'000, 100'000, 1'000'000}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(0.2)
    ->UseRealTime();
BENCHMARK(BM_SortPairsFewPerBody)
    ->ArgsProduct({{50'000, 500'000}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(0.2)
    ->UseRealTime();
