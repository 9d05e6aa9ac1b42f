// Body storage: creation, O(1) removal with swap-remove, and the state hash, at game-world sizes; a large static
// world edited between steps (issue 38: no step of it may take more than twice the median or 1 ms); and a large
// world asleep but for a few bodies.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "rubble/profile.h"
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

/// A floor of 1,000 x 1,000 static unit boxes with 100 spheres dropped on it; between steps range(0) random floor
/// boxes are destroyed and as many static boxes created on the floor (crates placed and removed by a game). One
/// iteration is the edits and one step; the counters give the steps' median and worst step (World::lastProfile's
/// stepMs, so the edits themselves are not in them) over the run, at range(1) threads.
void staticWorldEdits(benchmark::State& state) {
    constexpr int kSide = 1000;
    const auto edits = static_cast<int>(state.range(0));
    rubble::World world(rubble::WorldSettings{.threads = static_cast<int>(state.range(1))});
    const rubble::ShapeId tile = world.createShape(rubble::BoxDef{{0.5f, 0.5f, 0.5f}});
    const rubble::ShapeId ball = world.createShape(rubble::SphereDef{0.5f});
    rubble::BodyDef floor;
    floor.type = rubble::BodyType::Static;
    floor.shape = tile;
    std::vector<rubble::BodyId> statics;
    statics.reserve(kSide * kSide);
    for (int i = 0; i < kSide; ++i)
        for (int j = 0; j < kSide; ++j) {
            floor.position = {i - kSide / 2.0f, -0.5f, j - kSide / 2.0f};
            statics.push_back(world.createBody(floor));
        }
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> across(-20, 20), height(2, 12);
    rubble::BodyDef sphere;
    sphere.shape = ball;
    for (int i = 0; i < 100; ++i) {
        sphere.position = {across(rng), height(rng), across(rng)};
        world.createBody(sphere);
    }
    std::uniform_int_distribution<std::size_t> pick(0, kSide - 1);
    std::vector<double> stepMs;
    for (auto _ : state) {
        for (int e = 0; e < edits; ++e) {
            const std::size_t at = std::min(pick(rng) * kSide + pick(rng), statics.size() - 1);
            world.destroyBody(statics[at]);
            floor.position = {float(pick(rng)) - kSide / 2.0f, 0.5f, float(pick(rng)) - kSide / 2.0f};
            statics[at] = world.createBody(floor);
        }
        world.step(1.0f / 60);
        stepMs.push_back(world.lastProfile().stepMs);
    }
    std::sort(stepMs.begin(), stepMs.end());
    state.counters["median_ms"] = stepMs[stepMs.size() / 2];
    state.counters["worst_ms"] = stepMs.back();
    state.counters["threads"] = static_cast<double>(state.range(1));
}

/// range(0) spheres resting asleep on a static floor (a field of debris in a game), and 100 balls dropped onto it
/// one after another, each waking the few it hits: one iteration is one step, at range(1) threads. A world that
/// sleeps should cost its awake bodies, not its sleepers (issue 38). The counters give the median and worst step.
void sleepingField(benchmark::State& state) {
    const auto count = static_cast<int>(state.range(0));
    rubble::WorldSettings settings{.threads = static_cast<int>(state.range(1))};
    settings.effects = rubble::EffectSet::defaults().with(rubble::Effect::Sleeping);
    rubble::World world(settings);
    const rubble::ShapeId ball = world.createShape(rubble::SphereDef{0.5f});
    const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count))));
    rubble::BodyDef floor;
    floor.type = rubble::BodyType::Static;
    floor.shape = world.createShape(rubble::BoxDef{{0.6f * side + 10, 1, 0.6f * side + 10}});
    floor.position = {0, -1, 0};
    world.createBody(floor);
    rubble::BodyDef sphere;
    sphere.shape = ball;
    for (int i = 0; i < count; ++i) {
        sphere.position = {1.2f * float(i % side - side / 2), 0.5f, 1.2f * float(i / side - side / 2)};
        world.createBody(sphere);
    }
    // Resting from the start, they fall asleep after timeToSleep (0.5 s).
    for (int i = 0; i < 45; ++i) world.step(1.0f / 60);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> across(-0.6f * side, 0.6f * side);
    std::vector<double> stepMs;
    int step = 0;
    for (auto _ : state) {
        if (step++ % 6 == 0) {
            sphere.position = {across(rng), 6, across(rng)};
            world.createBody(sphere);
        }
        world.step(1.0f / 60);
        stepMs.push_back(world.lastProfile().stepMs);
    }
    std::sort(stepMs.begin(), stepMs.end());
    state.counters["median_ms"] = stepMs[stepMs.size() / 2];
    state.counters["worst_ms"] = stepMs.back();
    state.counters["asleep"] = static_cast<double>(world.lastProfile().sleepingBodies);
}

}  // namespace

BENCHMARK(createBodies)->Arg(100'000)->Unit(benchmark::kMillisecond);
BENCHMARK(churnBodies)->Arg(100'000)->Unit(benchmark::kMillisecond);
BENCHMARK(hashState)->Arg(100'000)->Unit(benchmark::kMillisecond);
BENCHMARK(staticWorldEdits)
    ->ArgNames({"edits", "threads"})
    ->ArgsProduct({{0, 100, 1000}, {1, 2}})
    ->Iterations(600)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(sleepingField)
    ->ArgNames({"bodies", "threads"})
    ->ArgsProduct({{250'000, 1'000'000}, {1, 2}})
    ->Iterations(600)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
