// Contact solver kernels: manifolds solved per second by one velocity iteration, the wide kernels (a batch of
// simd::kLanes manifolds per call) against the one-lane scalar kernels over the same rows. 20,000 manifolds over
// 3,000 bodies, about S1's size, so that body rows are fetched from memory the way the real solve meets them.
// BodyRows* compare the two ways of moving a batch's body velocities in and out of lanes: gathers and scatters over
// six SoA arrays (the layout before), and whole AoS rows through simd/transpose.h (the layout now).
// Whole-scene solver time at 1 and 2 threads is in scenes_perf.cpp (the solver_ms counter).
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "solver/contact_batch.h"
#include "support/contact_batches.h"

namespace {

using rubble::detail::BodyRow;
using rubble::detail::BodyRows;
using rubble::detail::ContactBatch;
using rubble::detail::kBatchLanes;

constexpr std::int32_t kBodies = 3000;
constexpr std::size_t kManifolds = 20000;

struct Problem {
    std::vector<ContactBatch> batches;
    std::vector<BodyRow> velocity, motion, pseudo;
    std::vector<rubble::detail::MassRow> mass;

    Problem() {
        std::mt19937 rng(42);
        batches.resize(kManifolds / kBatchLanes);
        std::uniform_int_distribution<std::int32_t> first(0, kBodies - 2 * static_cast<std::int32_t>(kBatchLanes));
        for (ContactBatch& b : batches) rubble::test::fillRandomBatch(b, rng, kBodies, first(rng));
        std::uniform_real_distribution<float> u(-1.0f, 1.0f);
        for (auto* rows : {&velocity, &motion, &pseudo}) {
            rows->resize(kBodies + 2);
            for (BodyRow& r : *rows)
                r = {{0.01f * u(rng), 0.01f * u(rng), 0.01f * u(rng)},
                     {0.01f * u(rng), 0.01f * u(rng), 0.01f * u(rng)}};
            (*rows)[kBodies] = BodyRow{};  // the still row
        }
        rubble::test::fillRandomMassRows(mass, kBodies + 2, kBodies, rng);
    }
    BodyRows bodyRows() { return {velocity.data(), motion.data(), pseudo.data(), mass.data(), kBodies + 1}; }
};

void BM_ContactSolveWide(benchmark::State& state) {
    Problem p;
    const BodyRows rows = p.bodyRows();
    rubble::detail::SolveParams params;
    for (auto _ : state) {
        for (ContactBatch& b : p.batches)
            rubble::detail::contact_kernels::solve<rubble::simd::FloatW, true>(b, 0, rows, params);
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(p.batches.size() * kBatchLanes));
}
BENCHMARK(BM_ContactSolveWide)->Unit(benchmark::kMicrosecond);

void BM_ContactSolveScalar(benchmark::State& state) {
    Problem p;
    const BodyRows rows = p.bodyRows();
    rubble::detail::SolveParams params;
    for (auto _ : state) {
        for (ContactBatch& b : p.batches)
            for (std::size_t lane = 0; lane < kBatchLanes; ++lane)
                rubble::detail::contact_kernels::solve<float, true>(b, lane, rows, params);
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(p.batches.size() * kBatchLanes));
}
BENCHMARK(BM_ContactSolveScalar)->Unit(benchmark::kMicrosecond);

// Each batch: load bodies A and B, nudge them, store them back (what Pair does around a kernel's arithmetic).
void BM_BodyRowsGatherScatterSoA(benchmark::State& state) {
    using rubble::simd::FloatW;
    using rubble::simd::IntW;
    Problem p;
    std::vector<float> soa[6];
    for (std::size_t c = 0; c < 6; ++c) {
        soa[c].resize(p.velocity.size());
        for (std::size_t i = 0; i < p.velocity.size(); ++i)
            soa[c][i] = c < 3 ? p.velocity[i].linear[c] : p.velocity[i].angular[c - 3];
    }
    const FloatW nudge(1e-7f);
    for (auto _ : state) {
        for (const ContactBatch& b : p.batches)
            for (const std::int32_t* body : {b.bodyA, b.bodyB}) {
                const IntW index = rubble::simd::loadInt<IntW>(body);
                FloatW v[6];
                for (std::size_t c = 0; c < 6; ++c) v[c] = rubble::simd::gather(soa[c].data(), index) + nudge;
                for (std::size_t c = 0; c < 6; ++c) rubble::simd::scatter(soa[c].data(), index, v[c]);
            }
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(p.batches.size() * kBatchLanes));
}
BENCHMARK(BM_BodyRowsGatherScatterSoA)->Unit(benchmark::kMicrosecond);

void BM_BodyRowsTransposeAoS(benchmark::State& state) {
    using rubble::simd::FloatW;
    using rubble::simd::IntW;
    Problem p;
    float* rows = reinterpret_cast<float*>(p.velocity.data());
    const FloatW nudge(1e-7f);
    for (auto _ : state) {
        for (const ContactBatch& b : p.batches)
            for (const std::int32_t* body : {b.bodyA, b.bodyB}) {
                FloatW v[rubble::simd::kRowFloats];
                rubble::simd::loadRowsTransposed(rows, body, v);
                for (std::size_t c = 0; c < 6; ++c) v[c] = v[c] + nudge;
                rubble::simd::storeRowsTransposed(rows, rubble::simd::loadInt<IntW>(body), v);
            }
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(p.batches.size() * kBatchLanes));
}
BENCHMARK(BM_BodyRowsTransposeAoS)->Unit(benchmark::kMicrosecond);

}  // namespace
