// Whole-step benchmarks of the standard scenes (../shared/SCENES.md), at 1 and 2 threads. Each iteration is one
// step of the scene's own time step; the counters carry each stage's mean time per step under the profile's names.
// SparseWorldCurve steps S4 scaled from 10k to 1M spheres at S4's density: each stage's growth with the body count
// when the contacts grow with it but stay few (about one manifold per 80 bodies).
#include <benchmark/benchmark.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "rubble/scene.h"
#include "rubble/world.h"

namespace {

void stepWorld(benchmark::State& state, rubble::Scene& scene, int threads, int warmUpSteps) {
    scene.settings.threads = threads;
    rubble::World world(scene.settings);
    rubble::instantiate(scene, world);
    for (int k = 0; k < warmUpSteps; ++k) world.step(scene.settings.timeStep);

    // Constraint-iterations: each contact manifold solved once in one iteration (velocity iterations, and the
    // position iterations where the correction has them), per second of the solver stage.
    const rubble::WorldSettings& ws = scene.settings;
    const bool positionPasses = ws.solver.positionCorrection != rubble::PositionCorrection::Baumgarte;
    const double iterationsPerStep =
        ws.substeps * (ws.velocityIterations + (positionPasses ? ws.positionIterations : 0));
    double stageMs[rubble::kStageCount] = {};
    double constraintIterations = 0;
    for (auto _ : state) {
        world.step(scene.settings.timeStep);
        const rubble::Profile& p = world.lastProfile();
        for (int k = 0; k < rubble::kStageCount; ++k) stageMs[k] += p.stages[k].ms;
        constraintIterations += p.constraints * iterationsPerStep;
    }
    const double solverMs = stageMs[static_cast<int>(rubble::Stage::Solver)];
    if (solverMs > 0)
        state.counters["constraint_iterations_per_s"] = benchmark::Counter(constraintIterations / (solverMs * 1e-3));
    for (int k = 0; k < rubble::kStageCount; ++k)
        state.counters[std::string(rubble::stageName(static_cast<rubble::Stage>(k))) + "_ms"] =
            benchmark::Counter(stageMs[k] / static_cast<double>(state.iterations()));
    state.counters["bodies"] = world.bodyCount();
    state.counters["manifolds"] = world.lastProfile().manifolds;
    state.SetItemsProcessed(state.iterations() * world.bodyCount());
}

void stepScene(benchmark::State& state, const char* file) {
    rubble::Scene scene = rubble::loadScene(std::string(RUBBLE_SOURCE_DIR "/scenes/") + file);
    stepWorld(state, scene, static_cast<int>(state.range(0)), 0);
}

/// S4 with range(0) spheres in a cube scaled to keep its density (100k in a cube of side 200 m); range(1) threads.
/// Two steps first, so that the contact cache and the solver's buffers are warm.
void BM_SparseWorldCurve(benchmark::State& state) {
    std::ifstream file(RUBBLE_SOURCE_DIR "/scenes/s4_sparse.json");
    std::stringstream text;
    text << file.rdbuf();
    std::string json = text.str();
    const auto spheres = static_cast<double>(state.range(0));
    const double half = 100.0 * std::cbrt(spheres / 100000.0);
    const auto replace = [&](const std::string& from, const std::string& to) {
        const std::size_t at = json.find(from);
        if (at == std::string::npos) {
            state.SkipWithError(("s4_sparse.json no longer holds " + from).c_str());
            return false;
        }
        json.replace(at, from.size(), to);
        return true;
    };
    if (!replace("\"count\": 100000", "\"count\": " + std::to_string(state.range(0))) ||
        !replace("\"min\": -100,", "\"min\": " + std::to_string(-half) + ",") ||
        !replace("\"max\": 100,", "\"max\": " + std::to_string(half) + ","))
        return;
    rubble::Scene scene = rubble::parseScene(json, RUBBLE_SOURCE_DIR "/scenes/s4_sparse.json");
    stepWorld(state, scene, static_cast<int>(state.range(1)), 2);
}

}  // namespace

BENCHMARK_CAPTURE(stepScene, S1_pyramid, "s1_pyramid.json")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(stepScene, S2_pyramids, "s2_pyramids.json")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(stepScene, S3_mesh_pile, "s3_mesh_pile.json")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(stepScene, S4_sparse, "s4_sparse.json")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(stepScene, S5_large_pyramid, "s5_large_pyramid.json")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(stepScene, S6_many_pyramids, "s6_many_pyramids.json")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_SparseWorldCurve)
    ->ArgNames({"spheres", "threads"})
    ->ArgsProduct({{10'000, 30'000, 100'000, 300'000, 1'000'000}, {1, 2}})
    ->Iterations(10)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
