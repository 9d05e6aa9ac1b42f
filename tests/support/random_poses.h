#pragma once
// Random orientations and directions for the tests that pose shapes at random.
#include <cmath>
#include <random>

#include "rubble/math.h"

namespace rubble::test {

/// A uniformly random rotation (a normalised 4D Gaussian).
inline Quat randomRotation(std::mt19937& rng) {
    std::normal_distribution<float> g;
    const float x = g(rng), y = g(rng), z = g(rng), w = g(rng);
    const float n = std::sqrt(x * x + y * y + z * z + w * w);
    return {x / n, y / n, z / n, w / n};
}

/// A uniformly random unit vector.
inline Vec3 randomDirection(std::mt19937& rng) {
    std::normal_distribution<float> g;
    const Vec3 v{g(rng), g(rng), g(rng)};
    return v / length(v);
}

}  // namespace rubble::test
