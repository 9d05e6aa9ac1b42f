// Box-box contact kernel on one core, per pair (collideBoxes), batched with the axis tests in SIMD lanes
// (collideBoxesBatch) and the batched driver's scalar reference. items_per_second counts manifolds (pairs processed).
// Pose sets: resting (cubes and planks lying on a ground box, slightly rotated and sunk: 4-point face contacts),
// random (random sizes, rotations and overlapping offsets: face and edge contacts), and a 50/50 mix of the two.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include "narrowphase/box_box.h"

namespace {

using namespace rubble;
using namespace rubble::detail;

struct BoxPair {
    Transform a, b;
    Vec3 halfA, halfB;
};

Quat randomRotation(std::mt19937& rng) {
    std::normal_distribution<float> g;
    const float x = g(rng), y = g(rng), z = g(rng), w = g(rng);
    const float n = std::sqrt(x * x + y * y + z * z + w * w);
    return {x / n, y / n, z / n, w / n};
}

BoxPair restingPair(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1, 1), size(0.2f, 1.0f);
    BoxPair p;
    p.a = {{0, 0, 0}, {}};
    p.halfA = {20, 0.5f, 20};
    p.halfB = {size(rng), size(rng), size(rng)};
    const Quat yaw = Quat::fromAxisAngle({0, 1, 0}, 3.14159f * u(rng));
    const Quat wobble = Quat::fromAxisAngle({u(rng), 0, u(rng)}, 1e-3f * u(rng));
    p.b = {{10 * u(rng), 0.5f + p.halfB.y - 0.01f * (1 + u(rng)), 10 * u(rng)}, wobble * yaw};
    return p;
}

BoxPair randomPair(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1, 1), size(0.1f, 1.0f), frac(0, 1);
    BoxPair p;
    p.halfA = {size(rng), size(rng), size(rng)};
    p.halfB = {size(rng), size(rng), size(rng)};
    p.a = {{u(rng), u(rng), u(rng)}, randomRotation(rng)};
    Vec3 dir{u(rng), u(rng), u(rng)};
    dir = dir / std::fmax(length(dir), 1e-3f);
    // Offsets up to 70% of the sum of the half diagonals: most pairs overlap (as the pairs a broad phase hands on).
    p.b = {p.a.position + dir * (0.7f * frac(rng) * (length(p.halfA) + length(p.halfB))), randomRotation(rng)};
    return p;
}

std::vector<BoxPair> makePairs(int restingPercent) {
    std::mt19937 rng(42);
    std::uniform_int_distribution<int> pct(0, 99);
    std::vector<BoxPair> pairs(4096);
    for (BoxPair& p : pairs) p = pct(rng) < restingPercent ? restingPair(rng) : randomPair(rng);
    return pairs;
}

/// The pairs in the batched kernel's SoA form (margin 0.02 m for every pair).
struct BoxPairArrays {
    std::vector<float> soa[21];
    explicit BoxPairArrays(const std::vector<BoxPair>& pairs) {
        for (const BoxPair& p : pairs) {
            const float values[21] = {p.a.position.x, p.a.position.y, p.a.position.z, p.a.rotation.x, p.a.rotation.y,
                                      p.a.rotation.z, p.a.rotation.w, p.halfA.x,      p.halfA.y,      p.halfA.z,
                                      p.b.position.x, p.b.position.y, p.b.position.z, p.b.rotation.x, p.b.rotation.y,
                                      p.b.rotation.z, p.b.rotation.w, p.halfB.x,      p.halfB.y,      p.halfB.z,
                                      0.02f};
            for (int f = 0; f < 21; ++f) soa[f].push_back(values[f]);
        }
    }
    BoxPairs view() const {
        return {soa[0].data(),  soa[1].data(),  soa[2].data(),  soa[3].data(),  soa[4].data(),  soa[5].data(),
                soa[6].data(),  soa[7].data(),  soa[8].data(),  soa[9].data(),  soa[10].data(), soa[11].data(),
                soa[12].data(), soa[13].data(), soa[14].data(), soa[15].data(), soa[16].data(), soa[17].data(),
                soa[18].data(), soa[19].data(), soa[20].data()};
    }
};

/// state.range(0): 0 = per pair (collideBoxes into one manifold), 1 = batched SIMD axis tests
/// (collideBoxesBatch), 2 = the batched driver's scalar reference (collideBoxesBatchScalar); 1 and 2 write an array
/// of manifolds.
void collide(benchmark::State& state, int restingPercent) {
    const std::vector<BoxPair> pairs = makePairs(restingPercent);
    const BoxPairArrays arrays(pairs);
    const BoxPairs in = arrays.view();
    std::vector<Manifold> out(pairs.size());
    Manifold m;
    std::size_t points = 0;
    const auto mode = state.range(0);
    for (auto _ : state) {
        if (mode == 0) {
            for (const BoxPair& p : pairs) {
                collideBoxes(p.a, p.halfA, p.b, p.halfB, 0.02f, m);
                points += static_cast<std::size_t>(m.pointCount);
                benchmark::DoNotOptimize(m);
            }
            continue;
        }
        if (mode == 1)
            collideBoxesBatch(in, pairs.size(), out.data());
        else
            collideBoxesBatchScalar(in, pairs.size(), out.data());
        for (const Manifold& k : out) points += static_cast<std::size_t>(k.pointCount);
        benchmark::DoNotOptimize(out.data());
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(pairs.size()));
    state.counters["points_per_manifold"] =
        static_cast<double>(points) / static_cast<double>(state.iterations() * pairs.size());
}

void BM_BoxBoxResting(benchmark::State& state) { collide(state, 100); }
void BM_BoxBoxRandom(benchmark::State& state) { collide(state, 0); }
void BM_BoxBoxMixed(benchmark::State& state) { collide(state, 50); }

BENCHMARK(BM_BoxBoxResting)->Arg(0)->Arg(2)->Arg(1)->ArgName("mode");
BENCHMARK(BM_BoxBoxRandom)->Arg(0)->Arg(2)->Arg(1)->ArgName("mode");
BENCHMARK(BM_BoxBoxMixed)->Arg(0)->Arg(2)->Arg(1)->ArgName("mode");

}  // namespace
