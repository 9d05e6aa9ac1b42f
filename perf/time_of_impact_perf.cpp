// Time-of-impact queries (ccd/time_of_impact.h) on one core: a sphere, box, capsule and 24-point hull, each swept over
// one step against the triangles of S3's terrain under its path, as the ccd stage sweeps a fast body. Each sweep
// falls 1.65 m (99 m/s, a body dropped from 500 m) at a random point and turns by up to a radian; items_per_second
// counts queries (one body against one triangle), hits_per_second those that found a time of impact.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "ccd/time_of_impact.h"
#include "narrowphase/gjk.h"
#include "shapes/shape.h"

namespace {

using namespace rubble;
using namespace rubble::detail;

float terrain(float x, float z) { return 2.0f * std::sin(x / 8.0f) * std::cos(z / 8.0f); }

struct Query {
    BodySweep sweep;
    Vec3 triangle[3];
};

std::vector<Query> makeQueries() {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<Query> queries;
    while (queries.size() < 4096) {
        const float x = -40 + 80 * u(rng), z = -40 + 80 * u(rng);
        // The two triangles of the 1 m cell under the path, as S3's grid splits it.
        const float x0 = std::floor(x), z0 = std::floor(z);
        const Vec3 p00{x0, terrain(x0, z0), z0}, p10{x0 + 1, terrain(x0 + 1, z0), z0};
        const Vec3 p01{x0, terrain(x0, z0 + 1), z0 + 1}, p11{x0 + 1, terrain(x0 + 1, z0 + 1), z0 + 1};
        const float ground = terrain(x, z);
        const Quat q0 = Quat::fromAxisAngle({u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f}, 3 * u(rng));
        const Quat q1 = Quat::fromAxisAngle({u(rng) - 0.5f, 1, u(rng) - 0.5f}, u(rng)) * q0;
        const BodySweep sweep({x, ground + 0.6f + 1.2f * u(rng), z}, q0, {x, ground - 0.6f, z}, q1, {});
        queries.push_back({sweep, {p00, p11, p10}});
        queries.push_back({sweep, {p00, p01, p11}});
    }
    return queries;
}

void sweepShape(benchmark::State& state, const GjkShape& part, float reach) {
    const std::vector<Query> queries = makeQueries();
    std::size_t i = 0;
    std::int64_t hits = 0;
    for (auto _ : state) {
        const Query& q = queries[i++ & (queries.size() - 1)];
        GjkShape triangle;
        triangle.core = GjkShape::Core::Points;
        triangle.points = q.triangle;
        triangle.pointCount = 3;
        const TimeOfImpact toi = timeOfImpact(part, q.sweep, reach, triangle, 0.005f, 0.00125f);
        hits += toi.state == TimeOfImpact::State::Hit;
        benchmark::DoNotOptimize(toi);
    }
    state.SetItemsProcessed(state.iterations());
    state.counters["hits_per_second"] = benchmark::Counter(static_cast<double>(hits), benchmark::Counter::kIsRate);
}

void BM_TimeOfImpactSphere(benchmark::State& state) {
    GjkShape s;
    s.core = GjkShape::Core::Point;
    s.radius = 0.5f;
    sweepShape(state, s, 0);
}
void BM_TimeOfImpactBox(benchmark::State& state) {
    GjkShape s;
    s.core = GjkShape::Core::Box;
    s.halfExtents = {0.5f, 0.3f, 0.4f};
    sweepShape(state, s, length(Vec3{0.5f, 0.3f, 0.4f}));
}
void BM_TimeOfImpactCapsule(benchmark::State& state) {
    GjkShape s;
    s.core = GjkShape::Core::Segment;
    s.radius = 0.3f;
    s.halfHeight = 0.4f;
    sweepShape(state, s, 0.4f);
}
void BM_TimeOfImpactHull(benchmark::State& state) {
    // A 24-point rock of radius about 0.5 m.
    static std::vector<Vec3> points = [] {
        std::mt19937 rng(3);
        std::normal_distribution<float> g;
        std::vector<Vec3> p;
        for (int k = 0; k < 24; ++k) {
            const Vec3 d{g(rng), g(rng), g(rng)};
            const Vec3 onSphere = d * (0.5f / length(d));
            p.push_back({onSphere.x, 0.7f * onSphere.y, 0.85f * onSphere.z});
        }
        return p;
    }();
    GjkShape s;
    s.core = GjkShape::Core::Points;
    s.points = points.data();
    s.pointCount = static_cast<std::uint32_t>(points.size());
    sweepShape(state, s, 0.5f);
}
BENCHMARK(BM_TimeOfImpactSphere);
BENCHMARK(BM_TimeOfImpactBox);
BENCHMARK(BM_TimeOfImpactCapsule);
BENCHMARK(BM_TimeOfImpactHull);

}  // namespace
