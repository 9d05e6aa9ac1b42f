// Shape building costs: these run when shapes are created (scene load, spawning), not per step, but a scene with
// many unique hulls pays them up front.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "shapes/shape.h"

namespace {

using namespace rubble;

std::vector<Vec3> ballCloud(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<Vec3> p;
    while (int(p.size()) < n) {
        const Vec3 v{u(rng), u(rng), u(rng)};
        if (dot(v, v) <= 1) p.push_back(v);
    }
    return p;
}

void BM_ShapesHullBuild(benchmark::State& state) {
    const std::vector<Vec3> points = ballCloud(int(state.range(0)), 42);
    std::size_t faces = 0;
    for (auto _ : state) {
        const detail::ConvexHull hull = detail::buildConvexHull(points);
        faces = hull.faceCount();
        benchmark::DoNotOptimize(hull.vertices.data());
    }
    state.counters["faces"] = double(faces);
    state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_ShapesHullBuild)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond);

void BM_ShapesHullMassProperties(benchmark::State& state) {
    const detail::ConvexHull hull = detail::buildConvexHull(ballCloud(int(state.range(0)), 7));
    for (auto _ : state) {
        MassProperties m = detail::hullMassProperties(hull);
        benchmark::DoNotOptimize(m);
    }
    state.counters["faces"] = double(hull.faceCount());
}
BENCHMARK(BM_ShapesHullMassProperties)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond);

void BM_ShapesCompoundMassProperties(benchmark::State& state) {
    CompoundDef def;
    for (int i = 0; i < 16; ++i)
        def.children.push_back(
            {BoxDef{{0.5f, 0.25f, 0.1f}}, {{float(i), 0, 0}, Quat::fromAxisAngle({0, 1, 0}, 0.3f * float(i))}});
    for (auto _ : state) {
        detail::Shape s = detail::buildShape(def);
        benchmark::DoNotOptimize(s.unitMass);
    }
}
BENCHMARK(BM_ShapesCompoundMassProperties)->Unit(benchmark::kMicrosecond);

void BM_ShapesMeshHeightLookup(benchmark::State& state) {
    TriangleMeshDef def;
    const int n = 256;
    for (int r = 0; r <= n; ++r)
        for (int c = 0; c <= n; ++c) def.vertices.push_back({float(c), float((r * 7 + c * 3) % 5), float(r)});
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) {
            const std::uint32_t a = r * (n + 1) + c, d = a + (n + 1);
            def.indices.insert(def.indices.end(), {a, d, d + 1, a, d + 1, a + 1});
        }
    const detail::Shape shape = detail::buildShape(def);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0, float(n));
    std::vector<float> xs(4096);
    for (float& x : xs) x = u(rng);
    std::size_t i = 0;
    for (auto _ : state) {
        auto h = detail::surfaceHeightAt(shape, xs[i & 4095], xs[(i + 1) & 4095]);
        benchmark::DoNotOptimize(h);
        ++i;
    }
}
BENCHMARK(BM_ShapesMeshHeightLookup);

}  // namespace
