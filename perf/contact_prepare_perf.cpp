// The contact solver's prepare() alone on the standard scenes' contacts: partition into blocks and slabs, colouring,
// lane placement and the constraint rows, at 1 and 2 threads (items_per_second = manifolds). The scene runs `steps`
// steps in a World first; prepare() then runs again and again on that step's contacts and islands (a second solver
// each time, so the slab choice sees the previous step as in the world). S2: 50 pyramids in blocks, whose rows are
// built later in the blocks' own tasks, so what is timed here is the serial colouring and lane placement; S3: the
// heap on the terrain, one large island cut in slabs, whose rows are built here in parallel.
#include <benchmark/benchmark.h>

#include <memory>
#include <string>

#include "rubble/scene.h"
#include "rubble/world.h"
#include "solver/contact_solver.h"
#include "thread_counts.h"
#include "world/world_access.h"
#include "world/world_impl.h"

namespace {

using namespace rubble;

void prepareContacts(benchmark::State& state, const char* file, int steps) {
    Scene scene = loadScene(std::string(RUBBLE_SOURCE_DIR "/scenes/") + file);
    scene.settings.threads = static_cast<int>(state.range(0));
    World world(scene.settings);
    instantiate(scene, world);
    for (int k = 0; k < steps; ++k) world.step(scene.settings.timeStep);
    World::Impl& w = detail::WorldAccess::of(world);
    detail::ContactSolver solver;
    const auto prepare = [&] {
        solver.prepare(w.contacts, w.impulses, w.bodies, w.settings, w.effects, w.settings.timeStep, *w.pool, nullptr,
                       &w.islands);
    };
    prepare();  // as the world's own solver did last step: the slab choice looks at it
    for (auto _ : state) {
        prepare();
        benchmark::DoNotOptimize(solver.stats().batches);
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * w.contacts.manifolds.size()));
    state.counters["manifolds"] = static_cast<double>(w.contacts.manifolds.size());
    state.counters["slabs"] = static_cast<double>(solver.slabs().size());
    state.counters["blocks"] = static_cast<double>(solver.blocks().size());
}

}  // namespace

BENCHMARK_CAPTURE(prepareContacts, S2_step60, "s2_pyramids.json", 60)->Apply(atOneAndTwoThreads);
BENCHMARK_CAPTURE(prepareContacts, S3_step300, "s3_mesh_pile.json", 300)->Apply(atOneAndTwoThreads);
