// What contact and sensor events cost (issue 22), on whole steps of standard scenes:
// - contactEvents: a scene with no body listening (the events stage does not run) and with every body listening,
//   at 1 and 2 threads: the events stage's own time and the step's. S6's 10,780 boxes are built at rest, so after
//   the first steps its pairs hardly change (the cost of listening to 56,000 steady contacts); S1 dropped (hard/)
//   lands 20,100 boxes during the measured steps, every landing a begin and a hit.
// - SensorsS4: S4's 100,000 spheres alone and with 1,000 kinematic sensor spheres of radius 2 m drifting among them
//   (scenes/s4_sensors.json): what the sensors add to the broad and narrow phases and the events stage.
#include <benchmark/benchmark.h>

#include <string>

#include "rubble/scene.h"
#include "rubble/world.h"

namespace {

void stepAndCount(benchmark::State& state, rubble::Scene& scene, int threads, int warmUpSteps) {
    scene.settings.threads = threads;
    rubble::World world(scene.settings);
    rubble::instantiate(scene, world);
    for (int k = 0; k < warmUpSteps; ++k) world.step(scene.settings.timeStep);
    double eventsMs = 0, broadMs = 0, narrowMs = 0, events = 0;
    for (auto _ : state) {
        world.step(scene.settings.timeStep);
        const rubble::Profile& p = world.lastProfile();
        eventsMs += p[rubble::Stage::Events].ms;
        broadMs += p[rubble::Stage::BroadPhase].ms;
        narrowMs += p[rubble::Stage::NarrowPhase].ms;
        events += p.events;
    }
    const auto perStep = [&](double total) {
        return benchmark::Counter(total / static_cast<double>(state.iterations()));
    };
    state.counters["events_ms"] = perStep(eventsMs);
    state.counters["broad_phase_ms"] = perStep(broadMs);
    state.counters["narrow_phase_ms"] = perStep(narrowMs);
    state.counters["events_per_step"] = perStep(events);
    state.counters["sensor_pairs"] = world.lastProfile().sensorPairs;
    state.counters["manifolds"] = world.lastProfile().manifolds;
}

/// range(0): 0 = nobody listens, 1 = every body listens; range(1): threads.
void contactEvents(benchmark::State& state, const char* file, int warmUpSteps) {
    rubble::Scene scene = rubble::loadScene(std::string(RUBBLE_SOURCE_DIR "/scenes/") + file);
    for (rubble::SceneBody& body : scene.bodies) body.def.contactEvents = state.range(0) != 0;
    stepAndCount(state, scene, static_cast<int>(state.range(1)), warmUpSteps);
}

/// range(0): 0 = S4, 1 = S4 with 1,000 sensors; range(1): threads.
void BM_SensorsS4(benchmark::State& state) {
    rubble::Scene scene = rubble::loadScene(std::string(RUBBLE_SOURCE_DIR "/scenes/") +
                                            (state.range(0) ? "s4_sensors.json" : "s4_sparse.json"));
    stepAndCount(state, scene, static_cast<int>(state.range(1)), 2);
}

}  // namespace

BENCHMARK_CAPTURE(contactEvents, S6_many_pyramids, "s6_many_pyramids.json", 5)
    ->ArgNames({"listening", "threads"})
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(contactEvents, S1d_pyramid_dropped, "hard/s1d_pyramid_dropped.json", 10)
    ->ArgNames({"listening", "threads"})
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->Iterations(40)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_SensorsS4)
    ->ArgNames({"sensors", "threads"})
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->Iterations(30)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
