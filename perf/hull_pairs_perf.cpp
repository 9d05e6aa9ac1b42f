// Polytope contact kernels (hull_pairs.h) on one core. items_per_second counts manifolds (pairs processed).
// Hulls are random point clouds of 12-24 points through the engine's hull builder (detail::buildShape), a few dozen
// distinct hulls shared by 4096 pairs. Pose sets: random (random rotations, offsets from half to all of the sum of
// the sizes: deep, grazing and separated pairs, as a broad phase hands them on) and resting (a hull or capsule on a
// ground box, slightly sunk and wobbled). Hull adjacency is built once per hull (the engine keeps it with the
// shape); BM_HullHullRandomNoAdjacency measures the convenience overload that rebuilds it per call.
// Rocks: the hull of scenes/hull_pile.json (32 points on a sphere of radius 2, 60 faces, 90 edges) against itself,
// both turned at random, in two pose sets: as the broad phase hands pairs on (centres anywhere in the cube where
// the two world boxes overlap: mostly apart) and touching (centres 3.2 to 4 m apart: grazing to a few cm deep).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include "narrowphase/hull_pairs.h"
#include "shapes/shape.h"

namespace {

using namespace rubble;
using namespace rubble::detail;

Quat randomRotation(std::mt19937& rng) {
    std::normal_distribution<float> g;
    const float x = g(rng), y = g(rng), z = g(rng), w = g(rng);
    const float n = std::sqrt(x * x + y * y + z * z + w * w);
    return {x / n, y / n, z / n, w / n};
}

struct HullSet {
    std::vector<ConvexHull> hulls;
    std::vector<HullAdjacency> adjacency;
    std::vector<float> size;
};

const HullSet& hullSet() {
    static const HullSet set = [] {
        HullSet s;
        std::mt19937 rng(17);
        std::uniform_real_distribution<float> u(-1, 1), axis(0.3f, 0.8f);
        std::uniform_int_distribution<int> count(12, 24);
        for (int h = 0; h < 32; ++h) {
            const Vec3 ax{axis(rng), axis(rng), axis(rng)};
            std::vector<Vec3> cloud;
            const int n = count(rng);
            while (static_cast<int>(cloud.size()) < n) {
                const Vec3 p{u(rng), u(rng), u(rng)};
                if (dot(p, p) <= 1) cloud.push_back({p.x * ax.x, p.y * ax.y, p.z * ax.z});
            }
            s.hulls.push_back(*buildShape(ConvexHullDef{cloud}).hull);
            s.adjacency.push_back(buildHullAdjacency(s.hulls.back()));
            s.size.push_back(s.adjacency.back().size);
        }
        return s;
    }();
    return set;
}

/// The pile's rock (scenes/hull_pile.json: mt19937 seed 42, the same draw as the peers' harness).
const ConvexHull& rock() {
    static const ConvexHull hull = [] {
        std::mt19937 rng(42);
        std::uniform_real_distribution<float> u(-1.0f, 1.0f);
        std::vector<Vec3> points;
        while (points.size() < 32) {
            const Vec3 p{u(rng), u(rng), u(rng)};
            const float l = length(p);
            if (l > 0.1f && l <= 1.0f) points.push_back(p * (2.0f / l));
        }
        return *buildShape(ConvexHullDef{points}).hull;
    }();
    return hull;
}

struct RockPair {
    Transform a, b;
};

/// `touching`: centres 3.2 to 4 m apart in a random direction; else anywhere in the cube of side 8 m where the
/// rocks' world boxes (half extent 2) overlap.
std::vector<RockPair> rockPairs(bool touching) {
    std::mt19937 rng(touching ? 45 : 44);
    std::uniform_real_distribution<float> u(-1, 1), distance(3.2f, 4.0f);
    std::vector<RockPair> pairs(4096);
    for (RockPair& p : pairs) {
        p.a = {{0, 0, 0}, randomRotation(rng)};
        Vec3 offset{4 * u(rng), 4 * u(rng), 4 * u(rng)};
        if (touching) offset = offset * (distance(rng) / std::fmax(length(offset), 1e-3f));
        p.b = {offset, randomRotation(rng)};
    }
    return pairs;
}

struct Pair {
    int a = 0, b = 0;
    Transform pa, pb;
    Vec3 half;
    CapsuleSegment capsule;
};

std::vector<Pair> randomPairs() {
    const HullSet& s = hullSet();
    std::mt19937 rng(42);
    std::uniform_real_distribution<float> u(-1, 1), frac(0, 1), half(0.2f, 0.7f);
    std::uniform_int_distribution<int> pick(0, static_cast<int>(s.hulls.size()) - 1);
    std::vector<Pair> pairs(4096);
    for (Pair& p : pairs) {
        p.a = pick(rng), p.b = pick(rng);
        p.half = {half(rng), half(rng), half(rng)};
        p.pa = {{u(rng), u(rng), u(rng)}, randomRotation(rng)};
        Vec3 dir{u(rng), u(rng), u(rng)};
        dir = dir / std::fmax(length(dir), 1e-3f);
        const float reach = (0.5f + 0.5f * frac(rng)) * (s.size[p.a] + s.size[p.b]);
        p.pb = {p.pa.position + dir * reach, randomRotation(rng)};
        const float hh = 0.6f * frac(rng), r = 0.1f + 0.3f * frac(rng);
        const Vec3 at = p.pa.position + dir * ((0.5f + 0.5f * frac(rng)) * (length(p.half) + hh + r));
        p.capsule = {at, rotate(randomRotation(rng), {0, hh, 0}), r};
    }
    return pairs;
}

std::vector<Pair> restingPairs() {
    const HullSet& s = hullSet();
    std::mt19937 rng(43);
    std::uniform_real_distribution<float> u(-1, 1);
    std::uniform_int_distribution<int> pick(0, static_cast<int>(s.hulls.size()) - 1);
    std::vector<Pair> pairs(4096);
    for (Pair& p : pairs) {
        p.b = pick(rng);
        const ConvexHull& h = s.hulls[p.b];
        // Face 0 down, sunk by up to 1 cm, wobbled by up to 1 mrad.
        const Vec3 n = h.faceNormals[0];
        const Vec3 ax = cross(n, {0, -1, 0});
        const Quat down = length(ax) > 1e-6f ? Quat::fromAxisAngle(ax, std::atan2(length(ax), -n.y)) : Quat{};
        const Quat rot = Quat::fromAxisAngle({u(rng), u(rng), u(rng)}, 1e-3f * u(rng)) * down;
        p.pa = {{0, 0, 0}, {}};
        p.half = {20, 0.5f, 20};
        p.pb = {{10 * u(rng), 0.5f + h.faceOffsets[0] - 0.005f * (1 + u(rng)), 10 * u(rng)}, rot};
        // Capsule lying on the ground box (2 points).
        const Vec3 axis = rotate(Quat::fromAxisAngle({0, 1, 0}, 3.14159f * u(rng)), {0.4f, 0, 0});
        p.capsule = {{10 * u(rng), 0.5f + 0.2f - 0.005f * (1 + u(rng)), 10 * u(rng)}, axis, 0.2f};
    }
    return pairs;
}

template <typename F>
void run(benchmark::State& state, const std::vector<Pair>& pairs, F collide) {
    Manifold m;
    std::size_t points = 0;
    for (auto _ : state) {
        for (const Pair& p : pairs) {
            collide(p, m);
            points += static_cast<std::size_t>(m.pointCount);
            benchmark::DoNotOptimize(m);
        }
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(pairs.size()));
    state.counters["points_per_manifold"] =
        static_cast<double>(points) / static_cast<double>(state.iterations() * pairs.size());
}

void BM_HullHullRandom(benchmark::State& state) {
    const HullSet& s = hullSet();
    run(state, randomPairs(), [&](const Pair& p, Manifold& m) {
        collideHulls(s.hulls[p.a], s.adjacency[p.a], p.pa, s.hulls[p.b], s.adjacency[p.b], p.pb, 0.02f, m);
    });
}
void BM_HullHullRandomNoAdjacency(benchmark::State& state) {
    const HullSet& s = hullSet();
    run(state, randomPairs(),
        [&](const Pair& p, Manifold& m) { collideHulls(s.hulls[p.a], p.pa, s.hulls[p.b], p.pb, 0.02f, m); });
}
void BM_HullOnBoxResting(benchmark::State& state) {
    const HullSet& s = hullSet();
    run(state, restingPairs(), [&](const Pair& p, Manifold& m) {
        collideBoxHull(p.pa, p.half, s.hulls[p.b], s.adjacency[p.b], p.pb, 0.02f, m);
    });
}
void BM_BoxHullRandom(benchmark::State& state) {
    const HullSet& s = hullSet();
    run(state, randomPairs(), [&](const Pair& p, Manifold& m) {
        collideBoxHull(p.pa, p.half, s.hulls[p.b], s.adjacency[p.b], p.pb, 0.02f, m);
    });
}
void BM_CapsuleBoxRandom(benchmark::State& state) {
    run(state, randomPairs(),
        [&](const Pair& p, Manifold& m) { collideCapsuleBox(p.capsule, p.pa, p.half, 0.02f, m); });
}
void BM_CapsuleBoxResting(benchmark::State& state) {
    run(state, restingPairs(),
        [&](const Pair& p, Manifold& m) { collideCapsuleBox(p.capsule, p.pa, p.half, 0.02f, m); });
}
void BM_CapsuleHullRandom(benchmark::State& state) {
    const HullSet& s = hullSet();
    run(state, randomPairs(), [&](const Pair& p, Manifold& m) {
        collideCapsuleHull(p.capsule, s.hulls[p.a], s.adjacency[p.a], p.pa, 0.02f, m);
    });
}

/// `hinted`: each pair keeps its SatHint from call to call while body B moves back and forth by 5 mm and 5 mrad,
/// as a pair does from step to step.
void rockRock(benchmark::State& state, bool touching, bool hinted) {
    static const HullAdjacency adjacency = buildHullAdjacency(rock());
    const std::vector<RockPair> pairs = rockPairs(touching);
    std::vector<Transform> moved(pairs.size());
    const Quat turn = Quat::fromAxisAngle({0.3f, 1.0f, -0.5f}, 0.005f);
    for (std::size_t k = 0; k < pairs.size(); ++k)
        moved[k] = {pairs[k].b.position + Vec3{0.003f, -0.004f, 0.0f}, turn * pairs[k].b.rotation};
    std::vector<SatHint> hints(pairs.size());
    Manifold m;
    std::size_t points = 0, manifolds = 0, calls = 0;
    for (auto _ : state) {
        for (std::size_t k = 0; k < pairs.size(); ++k) {
            const RockPair& p = pairs[k];
            const Transform& b = calls % 2 ? moved[k] : p.b;
            collideHulls(rock(), adjacency, p.a, rock(), adjacency, b, 0.02f, m, hinted ? &hints[k] : nullptr);
            points += static_cast<std::size_t>(m.pointCount);
            manifolds += m.pointCount > 0 ? 1 : 0;
            benchmark::DoNotOptimize(m);
        }
        ++calls;
    }
    const auto pairCount = static_cast<double>(state.iterations() * pairs.size());
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(pairs.size()));
    state.counters["touching"] = static_cast<double>(manifolds) / pairCount;
    state.counters["points_per_pair"] = static_cast<double>(points) / pairCount;
}
void BM_RockRockCandidates(benchmark::State& state) { rockRock(state, false, false); }
void BM_RockRockCandidatesHinted(benchmark::State& state) { rockRock(state, false, true); }
void BM_RockRockTouching(benchmark::State& state) { rockRock(state, true, false); }
void BM_RockRockTouchingHinted(benchmark::State& state) { rockRock(state, true, true); }

BENCHMARK(BM_RockRockCandidates);
BENCHMARK(BM_RockRockCandidatesHinted);
BENCHMARK(BM_RockRockTouching);
BENCHMARK(BM_RockRockTouchingHinted);
BENCHMARK(BM_HullHullRandom);
BENCHMARK(BM_HullHullRandomNoAdjacency);
BENCHMARK(BM_HullOnBoxResting);
BENCHMARK(BM_BoxHullRandom);
BENCHMARK(BM_CapsuleBoxRandom);
BENCHMARK(BM_CapsuleBoxResting);
BENCHMARK(BM_CapsuleHullRandom);

}  // namespace
