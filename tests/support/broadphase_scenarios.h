#pragma once
// Box sets for broad-phase tests and benchmarks, and the brute-force O(n^2) answer they are checked against.
// Header-only so that tests/ and perf/ share one definition of each scenario.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string_view>
#include <vector>

#include "broadphase/broadphase.h"

namespace rubble::test {

using detail::BodyPair;
using detail::Bounds;
using detail::overlaps;
using detail::PairFilter;

enum class Scenario { Uniform, Clustered, Flat, MixedSizes, AllOverlapping };

inline std::string_view scenarioName(Scenario s) {
    switch (s) {
        case Scenario::Uniform:
            return "uniform";
        case Scenario::Clustered:
            return "clustered";
        case Scenario::Flat:
            return "flat";
        case Scenario::MixedSizes:
            return "mixed_sizes";
        case Scenario::AllOverlapping:
            return "all_overlapping";
    }
    return "?";
}

/// n boxes at S4's density (100k spheres of radius 0.5 in a cube of side 200 m, so the side grows as n^(1/3)):
/// - Uniform: centres uniform in the cube, half extent 0.5;
/// - Clustered: 20 Gaussian clusters (sigma = side / 40), half extent 0.5;
/// - Flat: the cube squashed to a 2 m thick slab of the same area density per volume (a 2D world in 3D);
/// - MixedSizes: half extents log-uniform over 1:1000 (0.05 .. 50), more small ones than large;
/// - AllOverlapping: every box contains the origin.
/// A fixed seed makes each scenario reproducible.
inline Bounds makeScenario(Scenario s, std::uint32_t n, std::uint32_t seed = 42) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const float side = 200.0f * std::cbrt(static_cast<float>(n) / 100000.0f);
    Bounds b;
    b.resize(n);
    std::vector<float> cx(20), cy(20), cz(20);
    for (int c = 0; c < 20; ++c)
        cx[c] = (unit(rng) - 0.5f) * side, cy[c] = (unit(rng) - 0.5f) * side, cz[c] = (unit(rng) - 0.5f) * side;
    std::normal_distribution<float> gauss(0.0f, side / 40.0f);
    for (std::uint32_t i = 0; i < n; ++i) {
        float x = (unit(rng) - 0.5f) * side, y = (unit(rng) - 0.5f) * side, z = (unit(rng) - 0.5f) * side;
        float h = 0.5f;
        switch (s) {
            case Scenario::Uniform:
                break;
            case Scenario::Clustered: {
                const int c = static_cast<int>(rng() % 20);
                x = cx[c] + gauss(rng), y = cy[c] + gauss(rng), z = cz[c] + gauss(rng);
                break;
            }
            case Scenario::Flat: {
                const float wide = side * std::sqrt(side / 2.0f);
                x = (unit(rng) - 0.5f) * wide, z = (unit(rng) - 0.5f) * wide, y = unit(rng) * 1.0f;
                break;
            }
            case Scenario::MixedSizes:
                h = 0.05f * std::pow(1000.0f, unit(rng) * unit(rng));
                break;
            case Scenario::AllOverlapping:
                h = 1.0f + unit(rng);
                x = y = z = 0;
                x += (unit(rng) - 0.5f) * 0.5f;
                break;
        }
        b.minX[i] = x - h, b.maxX[i] = x + h;
        b.minY[i] = y - h, b.maxY[i] = y + h;
        b.minZ[i] = z - h, b.maxZ[i] = z + h;
    }
    return b;
}

/// Bodies piled onto one point (a `grid` generator with spacing 0): `small` boxes of half extent 0.5, then `large`
/// ones of half extent 10, all centred on the origin, so every pair overlaps.
inline Bounds pileAtOnePoint(std::uint32_t small, std::uint32_t large = 0) {
    Bounds b;
    b.resize(small + large);
    for (std::uint32_t i = 0; i < small + large; ++i) {
        const float h = i < small ? 0.5f : 10.0f;
        b.minX[i] = b.minY[i] = b.minZ[i] = -h;
        b.maxX[i] = b.maxY[i] = b.maxZ[i] = h;
    }
    return b;
}

/// Every overlapping pair (a < b) accepted by the filter, sorted: the reference answer.
inline std::vector<BodyPair> bruteForcePairs(const Bounds& b, const PairFilter& filter = {}) {
    std::vector<BodyPair> out;
    for (std::uint32_t i = 0; i < b.size(); ++i)
        for (std::uint32_t j = i + 1; j < b.size(); ++j)
            if (overlaps(b, i, b, j) && filter.accepts(i, j)) out.push_back({i, j});
    return out;
}

/// Moves every box by a random step (as a simulation step would), keeping sizes.
inline void jiggle(Bounds& b, float step, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> d(-step, step);
    for (std::uint32_t i = 0; i < b.size(); ++i) {
        const float dx = d(rng), dy = d(rng), dz = d(rng);
        b.minX[i] += dx, b.maxX[i] += dx, b.minY[i] += dy, b.maxY[i] += dy, b.minZ[i] += dz, b.maxZ[i] += dz;
    }
}

}  // namespace rubble::test
