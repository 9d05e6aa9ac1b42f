// The character controller's moves per second (issue 22): range(0) characters walking about a level of a 100 x 100 m
// mesh floor (20,000 triangles) with 400 static boxes (walls, steps), among range(1) dynamic boxes resting on the
// floor. Only the characters' updates are timed (the world's step between them is not); the first query after each
// step brings the query trees up to date, so that cost, which grows with the moving bodies, is in the updates.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "rubble/character.h"
#include "rubble/world.h"

namespace {

void buildLevel(rubble::World& world, int dynamicBoxes) {
    rubble::TriangleMeshDef mesh;
    constexpr int kSide = 100;
    for (int i = 0; i <= kSide; ++i)
        for (int k = 0; k <= kSide; ++k)
            mesh.vertices.push_back({static_cast<float>(i - kSide / 2), 0, static_cast<float>(k - kSide / 2)});
    const auto at = [](int i, int k) { return static_cast<std::uint32_t>(i * (kSide + 1) + k); };
    for (int i = 0; i < kSide; ++i)
        for (int k = 0; k < kSide; ++k)
            mesh.indices.insert(mesh.indices.end(),
                                {at(i, k), at(i, k + 1), at(i + 1, k), at(i + 1, k), at(i, k + 1), at(i + 1, k + 1)});
    rubble::BodyDef floor;
    floor.type = rubble::BodyType::Static;
    floor.shape = world.createShape(mesh);
    world.createBody(floor);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> place(-45, 45), size(0.1f, 1.5f);
    for (int b = 0; b < 400; ++b) {
        rubble::BodyDef box;
        box.type = rubble::BodyType::Static;
        const rubble::Vec3 half{size(rng), 0.5f * size(rng), size(rng)};
        box.shape = world.createShape(rubble::BoxDef{half});
        box.position = {place(rng), half.y, place(rng)};
        world.createBody(box);
    }
    const rubble::ShapeId crate = world.createShape(rubble::BoxDef{{0.25f, 0.25f, 0.25f}});
    for (int b = 0; b < dynamicBoxes; ++b) {
        rubble::BodyDef box;
        box.shape = crate;
        box.position = {place(rng), 0.25f, place(rng)};
        world.createBody(box);
    }
}

void BM_CharacterUpdates(benchmark::State& state) {
    rubble::WorldSettings settings;
    settings.threads = 1;
    settings.effects = rubble::EffectSet::defaults().with(rubble::Effect::Sleeping);
    rubble::World world(settings);
    buildLevel(world, static_cast<int>(state.range(1)));
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> place(-40, 40), heading(-3.14159f, 3.14159f);
    std::vector<std::unique_ptr<rubble::CharacterController>> characters;
    std::vector<rubble::Vec3> walk;
    for (int c = 0; c < state.range(0); ++c) {
        characters.push_back(
            std::make_unique<rubble::CharacterController>(world, rubble::Vec3{place(rng), 3, place(rng)}));
        walk.push_back({});
    }
    constexpr float kDt = 1.0f / 60.0f;
    for (int k = 0; k < 60; ++k) world.step(kDt);  // the crates settle and sleep
    long updates = 0, sweeps = 0, step = 0;
    for (auto _ : state) {
        if (step++ % 60 == 0)
            for (std::size_t c = 0; c < characters.size(); ++c) {
                // A new heading every second; back towards the middle near the floor's edge.
                const rubble::Vec3 p = characters[c]->position();
                const float a = std::max(std::fabs(p.x), std::fabs(p.z)) > 40 ? std::atan2(-p.z, -p.x) : heading(rng);
                walk[c] = {4 * std::cos(a), 0, 4 * std::sin(a)};
            }
        for (std::size_t c = 0; c < characters.size(); ++c) sweeps += characters[c]->update(kDt, walk[c]).sweeps;
        updates += static_cast<long>(characters.size());
        state.PauseTiming();
        world.step(kDt);
        state.ResumeTiming();
    }
    state.counters["updates_per_s"] = benchmark::Counter(static_cast<double>(updates), benchmark::Counter::kIsRate);
    state.counters["sweeps_per_update"] = static_cast<double>(sweeps) / static_cast<double>(updates);
}

}  // namespace

BENCHMARK(BM_CharacterUpdates)
    ->ArgNames({"characters", "crates"})
    ->ArgsProduct({{1, 100}, {0, 10000}})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();
