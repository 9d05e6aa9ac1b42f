// The resting-load guess for new contacts (src/contacts/resting_loads.cpp), on the contacts of real steps:
// - S5 first step: every one of the wall's manifolds is new, so all 5,050 cubes are balanced top down (the cost a
//   stack pays once, when it appears);
// - S3 after 300 steps: bodies still meet new triangles as they roll, and the guess visits only those bodies
//   (the cost of a typical step), at 1 and 2 threads (the scan for supports is parallel).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <string>
#include <vector>

#include "contacts/resting_loads.h"
#include "core/parallel.h"
#include "rubble/scene.h"
#include "rubble/world.h"
#include "world/world_access.h"

namespace {

using namespace rubble;
using namespace rubble::detail;

struct Captured {
    Contacts contacts;
    std::vector<std::uint8_t> carried;
    MovingBodies bodies;
    std::vector<PointImpulse> impulses;
    RestingLoadParams params;
};

/// The contacts, carried flags and impulses of `scene`'s step `steps` (the impulses the step ended with; none where
/// everything is new).
Captured capture(const std::string& scene, int steps, bool everythingNew) {
    const Scene s = loadScene(std::string(RUBBLE_SOURCE_DIR) + "/scenes/" + scene);
    WorldSettings settings = s.settings;
    settings.threads = 1;
    World world(settings);
    instantiate(s, world);
    for (int i = 0; i < steps; ++i) world.step(settings.timeStep);
    const World::Impl& w = WorldAccess::of(world);
    Captured c;
    c.contacts = w.contacts;
    c.bodies = w.bodies.moving;
    const std::span<const std::uint8_t> carried = w.contactCache.carried();
    c.carried.assign(carried.begin(), carried.end());
    if (everythingNew) std::fill(c.carried.begin(), c.carried.end(), std::uint8_t{0});
    c.impulses = w.impulses;
    if (everythingNew) std::fill(c.impulses.begin(), c.impulses.end(), PointImpulse{});
    c.params = {settings.gravity, settings.timeStep / static_cast<float>(settings.substeps),
                settings.solver.linearSlop};
    return c;
}

void restingLoads(benchmark::State& state, const char* scene, int steps, bool everythingNew, int threads) {
    const Captured c = capture(scene, steps, everythingNew);
    TaskPool pool(threads);
    RestingLoads loads;
    // Copied once: a seed writes only the manifolds that carried nothing, and reads those only after writing them,
    // so every iteration sees the same inputs.
    std::vector<PointImpulse> impulses = c.impulses;
    std::uint32_t written = 0;
    for (auto _ : state) {
        written = loads.seed(c.contacts, c.carried, c.bodies, c.params, pool, impulses);
        benchmark::DoNotOptimize(impulses.data());
    }
    state.counters["manifolds"] = static_cast<double>(c.contacts.manifolds.size());
    state.counters["written"] = written;
}

}  // namespace

BENCHMARK_CAPTURE(restingLoads, S5_first_step, "s5_large_pyramid.json", 1, true, 1)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(restingLoads, S1_first_step, "s1_pyramid.json", 1, true, 1)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(restingLoads, S3_step_300, "s3_mesh_pile.json", 300, false, 1)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(restingLoads, S3_step_300_2threads, "s3_mesh_pile.json", 300, false, 2)
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();
