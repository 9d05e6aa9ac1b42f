// The islands stage: the parallel union-find against the serial one on the contact graphs of S1 (one island of
// 2,870 boxes), S2 (100 islands of 91 boxes) and 100k bodies (1,100 pyramids, and one block), at 1 and 2 threads;
// and whole steps of a settled pile asleep against the same pile awake.
//
// The graphs are the scenes' resting contacts: each cube touches its neighbours in its layer and the four cubes
// below it (the bottom layer the static ground), one manifold per touching pair, in the canonical (a, b) order.
#include <benchmark/benchmark.h>

#include <string>

#include "core/parallel.h"
#include "islands/islands.h"
#include "rubble/scene.h"
#include "rubble/world.h"

namespace {

using namespace rubble::detail;

struct Graph {
    MovingBodies bodies;
    Contacts contacts;
};

/// Appends `count` pyramids of `layers` layers (layer k an (layers - k)^2 grid) with their resting contacts.
void addPyramids(Graph& g, int count, int layers) {
    for (int p = 0; p < count; ++p) {
        std::vector<std::uint32_t> below;
        for (int k = 0; k < layers; ++k) {
            const int n = layers - k;
            std::vector<std::uint32_t> layer(static_cast<std::size_t>(n * n));
            for (auto& i : layer) i = g.bodies.pushBack();
            const auto at = [&](const std::vector<std::uint32_t>& l, int w, int i, int j) {
                return l[static_cast<std::size_t>(i * w + j)];
            };
            const auto touch = [&](std::uint32_t a, std::uint32_t b, bool bStatic) {
                ContactPair pair;
                pair.a = a, pair.b = b, pair.bStatic = bStatic;
                g.contacts.pairs.push_back(pair);
            };
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < n; ++j) {
                    const std::uint32_t self = at(layer, n, i, j);
                    if (k == 0) touch(self, 0, true);
                    if (i + 1 < n) touch(self, at(layer, n, i + 1, j), false);
                    if (j + 1 < n) touch(self, at(layer, n, i, j + 1), false);
                    if (k > 0)
                        for (int di = 0; di < 2; ++di)
                            for (int dj = 0; dj < 2; ++dj) touch(at(below, n + 1, i + di, j + dj), self, false);
                }
            below = std::move(layer);
        }
    }
    g.contacts.manifolds.resize(g.contacts.pairs.size());
}

/// n bodies in one block (a 3D grid) touching their six neighbours.
void addBlock(Graph& g, int side) {
    const auto index = [&](int x, int y, int z) { return static_cast<std::uint32_t>((x * side + y) * side + z); };
    for (int i = 0; i < side * side * side; ++i) g.bodies.pushBack();
    for (int x = 0; x < side; ++x)
        for (int y = 0; y < side; ++y)
            for (int z = 0; z < side; ++z) {
                const auto touch = [&](std::uint32_t b) {
                    ContactPair pair;
                    pair.a = index(x, y, z), pair.b = b;
                    g.contacts.pairs.push_back(pair);
                };
                if (x + 1 < side) touch(index(x + 1, y, z));
                if (y + 1 < side) touch(index(x, y + 1, z));
                if (z + 1 < side) touch(index(x, y, z + 1));
            }
    g.contacts.manifolds.resize(g.contacts.pairs.size());
}

const Graph& graph(int which) {
    static const Graph graphs[] = {
        [] {
            Graph g;
            addPyramids(g, 1, 20);
            return g;
        }(),  // S1: 2,870 boxes
        [] {
            Graph g;
            addPyramids(g, 100, 6);
            return g;
        }(),  // S2: 9,100 boxes
        [] {
            Graph g;
            addPyramids(g, 1100, 6);
            return g;
        }(),  // 100,100 boxes in 1,100 islands
        [] {
            Graph g;
            addBlock(g, 47);
            return g;
        }(),  // 103,823 boxes in one island
    };
    return graphs[which];
}

void counters(benchmark::State& state, const Graph& g, const Islands& islands) {
    state.counters["bodies"] = g.bodies.size();
    state.counters["manifolds"] = static_cast<double>(g.contacts.pairs.size());
    state.counters["islands"] = islands.count();
    state.counters["largest"] = islands.largest;
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(g.contacts.pairs.size()));
}

void islandsSerial(benchmark::State& state, int which) {
    const Graph& g = graph(which);
    Islands out;
    for (auto _ : state) {
        IslandBuilder::buildSerial(g.contacts, {}, g.bodies, out);
        benchmark::DoNotOptimize(out.bodies.data());
    }
    counters(state, g, out);
}

void islandsParallel(benchmark::State& state, int which) {
    const Graph& g = graph(which);
    TaskPool pool(static_cast<int>(state.range(0)));
    IslandBuilder builder;
    Islands out;
    for (auto _ : state) {
        builder.build(g.contacts, {}, g.bodies, pool, out);
        benchmark::DoNotOptimize(out.bodies.data());
    }
    counters(state, g, out);
}

}  // namespace

#define RUBBLE_ISLANDS_BENCHMARKS(name, which)                                                   \
    BENCHMARK_CAPTURE(islandsSerial, name, which)->Unit(benchmark::kMicrosecond)->UseRealTime(); \
    BENCHMARK_CAPTURE(islandsParallel, name, which)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond)->UseRealTime();

RUBBLE_ISLANDS_BENCHMARKS(S1_pyramid, 0)
RUBBLE_ISLANDS_BENCHMARKS(S2_pyramids, 1)
RUBBLE_ISLANDS_BENCHMARKS(pyramids_100k, 2)
RUBBLE_ISLANDS_BENCHMARKS(block_100k, 3)

namespace {

/// S2 with the Sleeping effect declared (asleep) or not (awake), stepped until the pyramids have settled (and, with
/// sleeping, fallen asleep); each iteration is then one step of the settled pile.
void settledPile(benchmark::State& state, bool sleeping) {
    rubble::Scene scene = rubble::loadScene(RUBBLE_SOURCE_DIR "/scenes/s2_pyramids.json");
    scene.settings.threads = static_cast<int>(state.range(0));
    if (sleeping) scene.settings.effects = scene.settings.effects.with(rubble::Effect::Sleeping);
    rubble::World world(scene.settings);
    rubble::instantiate(scene, world);
    for (int i = 0; i < 90; ++i) world.step(scene.settings.timeStep);
    double islandsMs = 0;
    for (auto _ : state) {
        world.step(scene.settings.timeStep);
        islandsMs += world.lastProfile()[rubble::Stage::Islands].ms;
    }
    state.counters["asleep"] = world.lastProfile().sleepingBodies;
    state.counters["bodies"] = world.bodyCount();
    state.counters["islands_ms"] = benchmark::Counter(islandsMs / static_cast<double>(state.iterations()));
}

}  // namespace

BENCHMARK_CAPTURE(settledPile, S2_awake, false)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(settledPile, S2_asleep, true)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
