// What the machine itself gives a second thread, on the engine's own pool: the ceiling for every 1 -> 2 thread
// ratio the stage and scene benchmarks report. The project's machines are shared virtual ones, and what their two
// vCPUs give varies with the neighbours: on a 2-vCPU AMD EPYC (Zen 5) a register-only loop like the one below ran
// 1.3-2.1x faster on two threads than on one within the same two hours, and Box3D's large_pyramid 1.2-1.9x, so a
// scene's scaling means something only next to these figures, measured in the same sitting.
//
// Compute: each worker runs independent chains of fused multiply-adds in registers, no memory touched (what the
// solver's kernels are made of). Stream: each worker sums an array of its own, larger than the core's caches (what
// building constraint rows and the broad phase's passes are made of). Items are operations (compute) and bytes
// (stream) per second of wall time, at 1 and 2 threads.
#include <benchmark/benchmark.h>

#include <atomic>
#include <cstddef>
#include <vector>

#include "core/parallel.h"
#include "thread_counts.h"

namespace {

using rubble::detail::TaskPool;

/// 128 lanes of independent chains (8 AVX-512 or 16 AVX2 registers): enough to keep a core's FMA units busy
/// whatever their latency, so that two threads on one core's two hyperthreads would share them and show it.
constexpr int kChainLanes = 128;

[[gnu::noinline]] float fmaChains(long rounds) {
    float a[kChainLanes];
    for (int i = 0; i < kChainLanes; ++i) a[i] = 1.0f + 0.001f * static_cast<float>(i);
    for (long r = 0; r < rounds; ++r)
        for (float& x : a) x = x * 0.9999f + 0.0001f;
    float sum = 0;
    for (const float x : a) sum += x;
    return sum;
}

void BM_MachineCompute(benchmark::State& state) {
    const int threads = static_cast<int>(state.range(0));
    TaskPool pool(threads);
    constexpr long kRounds = 1 << 16;
    std::atomic<int> sink{0};
    for (auto _ : state) {
        pool.forEachWorker(
            [&](int) { sink.fetch_add(static_cast<int>(fmaChains(kRounds)), std::memory_order_relaxed); });
    }
    benchmark::DoNotOptimize(sink.load());
    state.SetItemsProcessed(state.iterations() * threads * kRounds * kChainLanes);
}
BENCHMARK(BM_MachineCompute)->Apply(atOneAndTwoThreads);

void BM_MachineStream(benchmark::State& state) {
    const int threads = static_cast<int>(state.range(0));
    TaskPool pool(threads);
    constexpr std::size_t kFloats = std::size_t{32} << 20;  // 128 MB per worker: beyond any cache here
    std::vector<std::vector<float>> arrays(static_cast<std::size_t>(threads));
    pool.forEachWorker([&](int worker) { arrays[static_cast<std::size_t>(worker)].assign(kFloats, 1.0f); });
    std::atomic<int> sink{0};
    for (auto _ : state) {
        pool.forEachWorker([&](int worker) {
            const std::vector<float>& a = arrays[static_cast<std::size_t>(worker)];
            float sums[16] = {};
            for (std::size_t i = 0; i < kFloats; i += 16)
#pragma GCC unroll 16
                for (std::size_t k = 0; k < 16; ++k) sums[k] += a[i + k];
            float sum = 0;
            for (const float s : sums) sum += s;
            sink.fetch_add(static_cast<int>(sum), std::memory_order_relaxed);
        });
    }
    benchmark::DoNotOptimize(sink.load());
    state.SetBytesProcessed(state.iterations() * threads * static_cast<std::int64_t>(kFloats * sizeof(float)));
}
BENCHMARK(BM_MachineStream)->Apply(atOneAndTwoThreads);

}  // namespace
