// Integration stage micro-benchmarks: integrateVelocities + integratePositions over N moving bodies, SIMD (wide
// kernels, chunked on a TaskPool of 1 or 2 threads) against the scalar reference, for each integrator.
// items_per_second counts bodies integrated (both halves of a step).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/parallel.h"
#include "integrate/integrate.h"
#include "storage/body_storage.h"

namespace {

using namespace rubble;
using namespace rubble::detail;

MovingBodies makeBodies(std::size_t count) {
    std::mt19937 rng(1234);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), pos(0.2f, 1.0f);
    MovingBodies b;
    for (std::size_t k = 0; k < count; ++k) {
        const std::uint32_t i = b.pushBack();
        b.slot[i] = i;
        b.px[i] = 100 * u(rng), b.py[i] = 100 * u(rng), b.pz[i] = 100 * u(rng);
        float q[4] = {u(rng), u(rng), u(rng), u(rng)};
        const float len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        b.qx[i] = q[0] / len, b.qy[i] = q[1] / len, b.qz[i] = q[2] / len, b.qw[i] = q[3] / len;
        b.irw[i] = 1;
        b.vx[i] = u(rng), b.vy[i] = u(rng), b.vz[i] = u(rng);
        b.wx[i] = u(rng), b.wy[i] = u(rng), b.wz[i] = u(rng);
        b.invMass[i] = pos(rng);
        b.invIx[i] = pos(rng), b.invIy[i] = pos(rng), b.invIz[i] = pos(rng);
        b.gravityScale[i] = 1;
        b.linearDamping[i] = 0.05f, b.angularDamping[i] = 0.05f;
    }
    return b;
}

/// state.range(0): bodies; range(1): threads (0 = scalar reference); range(2): integrator.
void BM_Integrate(benchmark::State& state) {
    const auto count = static_cast<std::size_t>(state.range(0));
    const int threads = static_cast<int>(state.range(1));
    IntegrationParams params;
    params.gravity = {0.0f, -9.81f, 0.0f};
    params.integrator = static_cast<Integrator>(state.range(2));
    MovingBodies bodies = makeBodies(count);
    IntegrationScratch scratch;
    TaskPool pool(threads > 0 ? threads : 1);
    std::vector<std::uint32_t> nonFinite;
    for (auto _ : state) {
        if (threads > 0) {
            integrateVelocities(bodies, params, scratch, pool, nonFinite);
            integratePositions(bodies, params, scratch, pool, nonFinite);
        } else {
            integrateVelocitiesScalar(bodies, params, scratch, nonFinite);
            integratePositionsScalar(bodies, params, scratch, nonFinite);
        }
        benchmark::DoNotOptimize(bodies.px.data());
        benchmark::ClobberMemory();
        nonFinite.clear();
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(count));
    state.counters["bodies"] = static_cast<double>(count);
    state.counters["threads"] = threads;
    state.counters["simd"] = threads > 0 ? 1 : 0;
    state.counters["ns_per_body"] = benchmark::Counter(
        static_cast<double>(count), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
    state.SetLabel(std::string(integratorName(params.integrator)) + (threads > 0 ? " simd" : " scalar"));
}

void integrateArgs(benchmark::internal::Benchmark* b) {
    b->ArgNames({"bodies", "threads", "integrator"});
    for (const long integrator : {0L, 3L})  // semi-implicit Euler (default), RK4 (the most expensive)
        for (const long count : {1000L, 10000L, 100000L, 1000000L})
            for (const long threads : {0L, 1L, 2L}) {
                if (integrator != 0 && count != 100000) continue;
                b->Args({count, threads, integrator});
            }
    b->Args({100000, 2, 1});  // explicit Euler
    b->Args({100000, 2, 2});  // Verlet
    b->Unit(benchmark::kMicrosecond)->UseRealTime();
}

BENCHMARK(BM_Integrate)->Apply(integrateArgs);

}  // namespace
