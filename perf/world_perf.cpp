// Body storage: creation, O(1) removal with swap-remove, and the state hash, at game-world sizes.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>
#include <vector>

#include "rubble/world.h"

namespace {

void createBodies(benchmark::State& state) {
    const auto count = static_cast<int>(state.range(0));
    for (auto _ : state) {
        rubble::World world;
        const rubble::ShapeId box = world.createShape(rubble::BoxDef{});
        rubble::BodyDef def;
        def.shape = box;
        for (int i = 0; i < count; ++i) {
            def.position = {float(i % 100), float(i / 100 % 100), float(i / 10000)};
            benchmark::DoNotOptimize(world.createBody(def));
        }
    }
    state.SetItemsProcessed(state.iterations() * count);
}

/// Remove a random half of the bodies and add them back: every removal moves the last body into the hole.
void churnBodies(benchmark::State& state) {
    const auto count = static_cast<int>(state.range(0));
    rubble::World world;
    const rubble::ShapeId box = world.createShape(rubble::BoxDef{});
    rubble::BodyDef def;
    def.shape = box;
    std::vector<rubble::BodyId> ids;
    for (int i = 0; i < count; ++i) ids.push_back(world.createBody(def));
    std::mt19937 rng(1);
    for (auto _ : state) {
        std::shuffle(ids.begin(), ids.end(), rng);
        for (int i = 0; i < count / 2; ++i) world.destroyBody(ids[i]);
        for (int i = 0; i < count / 2; ++i) ids[i] = world.createBody(def);
    }
    state.SetItemsProcessed(state.iterations() * count);  // count/2 removals + count/2 additions
}

void hashState(benchmark::State& state) {
    const auto count = static_cast<int>(state.range(0));
    rubble::World world;
    const rubble::ShapeId ball = world.createShape(rubble::SphereDef{0.5f});
    rubble::BodyDef def;
    def.shape = ball;
    for (int i = 0; i < count; ++i) world.createBody(def);
    for (auto _ : state) benchmark::DoNotOptimize(world.stateHash());
    state.SetItemsProcessed(state.iterations() * count);
}

}  // namespace

BENCHMARK(createBodies)->Arg(100'000)->Unit(benchmark::kMillisecond);
BENCHMARK(churnBodies)->Arg(100'000)->Unit(benchmark::kMillisecond);
BENCHMARK(hashState)->Arg(100'000)->Unit(benchmark::kMillisecond);
