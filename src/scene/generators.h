#pragma once
// Body and terrain generators of scene files (internal to src/scene/). The loader validates a generator's JSON and
// fills one of these parameter structs; the functions here only compute positions, so the arithmetic that the
// standard scenes (SCENES.md) depend on lives in one place. Positions are computed in double and rounded once.
#include <cstdint>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "rubble/limits.h"
#include "rubble/scene.h"
#include "rubble/shapes.h"

namespace rubble::scene_detail {

/// Largest number of bodies one scene may hold (explicit and generated together): what a World may hold.
inline constexpr std::uint64_t kMaxBodies = limits::kMaxSceneBodies;
/// Largest number of triangles a generated terrain may have.
inline constexpr std::uint64_t kMaxTerrainTriangles = 10'000'000;

/// How much a scene may ask its generators for. Files are held to the limits above; the scene fuzzer holds its inputs
/// to a few thousand so that each runs in milliseconds, through the same checks.
struct SceneCaps {
    std::uint64_t bodies = kMaxBodies;
    std::uint64_t terrainTriangles = kMaxTerrainTriangles;
};
/// parseScene with other caps.
Scene parseSceneWithin(std::string_view text, const std::string& sourceName, const SceneCaps& caps);

/// Every generated body starts as a copy of a template (material, type, filter, velocities, ...); generators set the
/// position, the shape (cycled through `shapes` by creation index within the generator) and, for random, velocity.
struct GeneratorCommon {
    SceneBody prototype;
    std::vector<std::uint32_t> shapes;  ///< indices into Scene::shapes, at least one
};

/// Pyramids of layers. Layer k (0 = bottom) has n = base - k bodies per side: an n x n grid in x, z ("square") or a
/// row of n along x ("wall"), centred on the pyramid centre, at y = center.y + k * spacing.y.
/// Copies sit on an nx x nz grid centred on `center` (x outer, z inner), each copy complete before the next.
struct PyramidParams {
    std::uint32_t base = 1;
    std::uint32_t layers = 1;
    bool wall = false;
    double spacing[3] = {1, 1, 1};
    double center[3] = {0, 0.5, 0};
    std::uint32_t repeatCount[2] = {1, 1};
    double repeatSpacing[2] = {0, 0};
};

/// Bodies a pyramid generator creates (double, so absurd inputs cannot overflow before the cap check).
double pyramidBodyCount(const PyramidParams& p);
void generatePyramids(const PyramidParams& p, const GeneratorCommon& common, std::vector<SceneBody>& out);

/// An orientation uniform over all rotations, from three draws of std::uniform_real_distribution<float>(0, 1)
/// (Shoemake's method).
Quat randomRotation(std::mt19937& rng);

/// A box lattice: count[1] layers (y) outermost, then count[0] (x), then count[2] (z); the first body's centre is
/// `origin`, body (i, l, j) sits at origin + (i sx, l sy, j sz). With drawRotation, each body in creation order gets
/// randomRotation() from std::mt19937(seed).
struct GridParams {
    std::uint32_t count[3] = {1, 1, 1};
    double spacing[3] = {1, 1, 1};
    double origin[3] = {0, 0, 0};
    bool drawRotation = false;
    std::uint32_t seed = 42;
};

double gridBodyCount(const GridParams& p);
void generateGrid(const GridParams& p, const GeneratorCommon& common, std::vector<SceneBody>& out);

/// Uniform random bodies: std::mt19937(seed); for each body in order x, y, z from
/// std::uniform_real_distribution<float>(min[a], max[a]), then (if drawVelocity) vx, vy, vz likewise, then (if
/// drawRotation) randomRotation().
struct RandomParams {
    std::uint64_t count = 0;
    std::uint32_t seed = 42;
    float min[3] = {0, 0, 0};
    float max[3] = {0, 0, 0};
    bool drawVelocity = false;
    float velocityMin[3] = {0, 0, 0};
    float velocityMax[3] = {0, 0, 0};
    bool drawRotation = false;
};

void generateRandom(const RandomParams& p, const GeneratorCommon& common, std::vector<SceneBody>& out);

/// Wavy terrain: (cells[0] + 1) x (cells[1] + 1) vertices from min to max in x, z (vertex (c, r) has index
/// r * (cells[0] + 1) + c), y = amplitude * sin(x / wavelength[0]) * cos(z / wavelength[1]). Each cell becomes two
/// triangles split along its (x0, z0)-(x1, z1) diagonal, counter-clockwise seen from +y; cells row by row (z outer).
struct TerrainParams {
    std::uint32_t cells[2] = {1, 1};
    double min[2] = {0, 0};
    double max[2] = {1, 1};
    double amplitude = 0;
    double wavelength[2] = {1, 1};
};

TriangleMeshDef generateTerrain(const TerrainParams& p);

/// Escapes one JSON pointer reference token (RFC 6901: '~' -> "~0", '/' -> "~1").
inline std::string jsonPointerToken(std::string_view key) {
    std::string out;
    out.reserve(key.size());
    for (const char c : key) {
        if (c == '~')
            out += "~0";
        else if (c == '/')
            out += "~1";
        else
            out += c;
    }
    return out;
}

}  // namespace rubble::scene_detail
