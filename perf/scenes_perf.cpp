// Whole-step benchmarks of the standard scenes (../shared/SCENES.md), at 1 and 2 threads. Each iteration is one
// step of the scene's own time step; the counters carry each stage's mean time per step under the profile's names.
#include <benchmark/benchmark.h>

#include <string>

#include "rubble/scene.h"
#include "rubble/world.h"

namespace {

void stepScene(benchmark::State& state, const char* file) {
    rubble::Scene scene = rubble::loadScene(std::string(RUBBLE_SOURCE_DIR "/scenes/") + file);
    scene.settings.threads = static_cast<int>(state.range(0));
    rubble::World world(scene.settings);
    rubble::instantiate(scene, world);

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
    state.SetItemsProcessed(state.iterations() * world.bodyCount());
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
