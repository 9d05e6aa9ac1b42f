// Runtime: the cost of publishing a snapshot (the physics thread pays it every step) and of interpolating one frame
// (the render thread pays it every frame), at game-world sizes. Bodies are spread out and spinning so that every
// pose differs between the two snapshots.
#include <benchmark/benchmark.h>

#include <cmath>

#include "rubble/runtime.h"
#include "rubble/world.h"
#include "runtime/snapshot.h"

namespace {

/// `count` bodies, a tenth of them static (a game world's scenery), the rest dynamic boxes with velocities.
rubble::World spreadBodies(int count) {
    rubble::WorldSettings settings;
    settings.threads = 2;
    rubble::World world(settings);
    const rubble::ShapeId box = world.createShape(rubble::BoxDef{});
    rubble::BodyDef def;
    def.shape = box;
    for (int i = 0; i < count; ++i) {
        def.type = i % 10 == 0 ? rubble::BodyType::Static : rubble::BodyType::Dynamic;
        def.position = {2.0f * float(i % 100), 2.0f * float(i / 100 % 100), 2.0f * float(i / 10000)};
        def.linearVelocity = def.type == rubble::BodyType::Static ? rubble::Vec3{} : rubble::Vec3{0, 1, 0};
        def.angularVelocity = def.type == rubble::BodyType::Static ? rubble::Vec3{} : rubble::Vec3{0.3f, 1, 0};
        world.createBody(def);
    }
    return world;
}

/// Steady state: the same bodies as last time, so only the moving bodies' poses are written (in parallel on the
/// world's two threads).
void publishSnapshot(benchmark::State& state) {
    const auto count = static_cast<int>(state.range(0));
    const rubble::World world = spreadBodies(count);
    rubble::Snapshot snapshot;
    rubble::detail::writeSnapshot(world, true, snapshot);
    for (auto _ : state) {
        rubble::detail::writeSnapshot(world, false, snapshot);
        benchmark::DoNotOptimize(snapshot.px.data());
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(state.iterations() * count);
}

/// After bodies came or went: every slot is rewritten.
void publishSnapshotAfterLayoutChange(benchmark::State& state) {
    const auto count = static_cast<int>(state.range(0));
    const rubble::World world = spreadBodies(count);
    rubble::Snapshot snapshot;
    for (auto _ : state) {
        rubble::detail::writeSnapshot(world, true, snapshot);
        benchmark::DoNotOptimize(snapshot.px.data());
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(state.iterations() * count);
}

/// One render frame: blend the two newest snapshots (one step apart) into the frame the renderer reads.
void interpolateFrame(benchmark::State& state) {
    const auto count = static_cast<int>(state.range(0));
    rubble::World world = spreadBodies(count);
    rubble::Snapshot older, newer;
    rubble::detail::writeSnapshot(world, true, older);
    world.step(1.0f / 120.0f);
    rubble::detail::writeSnapshot(world, true, newer);
    rubble::RenderFrame frame;
    float alpha = 0;
    for (auto _ : state) {
        alpha = alpha >= 1.0f ? 0.0f : alpha + 0.0625f;
        rubble::interpolateSnapshots(older, newer, alpha, frame);
        benchmark::DoNotOptimize(frame.qw.data());
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(state.iterations() * count);
}

}  // namespace

BENCHMARK(publishSnapshot)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(publishSnapshotAfterLayoutChange)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(interpolateFrame)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond)->UseRealTime();
