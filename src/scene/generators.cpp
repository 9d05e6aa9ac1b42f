#include "scene/generators.h"

#include <cmath>
#include <random>

namespace rubble::scene_detail {
namespace {

SceneBody makeBody(const GeneratorCommon& common, std::uint64_t index, double x, double y, double z) {
    SceneBody b = common.prototype;
    b.shape = common.shapes[index % common.shapes.size()];
    b.def.position = {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)};
    return b;
}

/// Offset of item `i` of `n` evenly spaced items centred on zero.
double centred(std::uint64_t i, std::uint64_t n, double spacing) {
    return (static_cast<double>(i) - 0.5 * static_cast<double>(n - 1)) * spacing;
}

}  // namespace

double pyramidBodyCount(const PyramidParams& p) {
    double perPyramid = 0;
    for (std::uint32_t k = 0; k < p.layers; ++k) {
        const double n = static_cast<double>(p.base - k);
        perPyramid += p.wall ? n : n * n;
    }
    return perPyramid * static_cast<double>(p.repeatCount[0]) * static_cast<double>(p.repeatCount[1]);
}

void generatePyramids(const PyramidParams& p, const GeneratorCommon& common, std::vector<SceneBody>& out) {
    std::uint64_t index = 0;
    for (std::uint32_t a = 0; a < p.repeatCount[0]; ++a) {
        for (std::uint32_t b = 0; b < p.repeatCount[1]; ++b) {
            const double cx = p.center[0] + centred(a, p.repeatCount[0], p.repeatSpacing[0]);
            const double cz = p.center[2] + centred(b, p.repeatCount[1], p.repeatSpacing[1]);
            for (std::uint32_t k = 0; k < p.layers; ++k) {
                const std::uint32_t n = p.base - k;
                const double y = p.center[1] + static_cast<double>(k) * p.spacing[1];
                for (std::uint32_t i = 0; i < n; ++i) {
                    const double x = cx + centred(i, n, p.spacing[0]);
                    if (p.wall) {
                        out.push_back(makeBody(common, index++, x, y, cz));
                        continue;
                    }
                    for (std::uint32_t j = 0; j < n; ++j)
                        out.push_back(makeBody(common, index++, x, y, cz + centred(j, n, p.spacing[2])));
                }
            }
        }
    }
}

Quat randomRotation(std::mt19937& rng) {
    // Shoemake (Graphics Gems III): three uniform numbers give a unit quaternion uniform on the 3-sphere, so every
    // orientation is as likely as any other.
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const double u1 = unit(rng), u2 = unit(rng), u3 = unit(rng);
    const double a = std::sqrt(1.0 - u1), c = std::sqrt(u1), turn = 2.0 * 3.14159265358979323846;
    return {static_cast<float>(a * std::sin(turn * u2)), static_cast<float>(a * std::cos(turn * u2)),
            static_cast<float>(c * std::sin(turn * u3)), static_cast<float>(c * std::cos(turn * u3))};
}

double gridBodyCount(const GridParams& p) {
    return static_cast<double>(p.count[0]) * static_cast<double>(p.count[1]) * static_cast<double>(p.count[2]);
}

void generateGrid(const GridParams& p, const GeneratorCommon& common, std::vector<SceneBody>& out) {
    std::uint64_t index = 0;
    std::mt19937 rng(p.seed);
    for (std::uint32_t l = 0; l < p.count[1]; ++l) {
        const double y = p.origin[1] + static_cast<double>(l) * p.spacing[1];
        for (std::uint32_t i = 0; i < p.count[0]; ++i) {
            const double x = p.origin[0] + static_cast<double>(i) * p.spacing[0];
            for (std::uint32_t j = 0; j < p.count[2]; ++j) {
                out.push_back(makeBody(common, index++, x, y, p.origin[2] + static_cast<double>(j) * p.spacing[2]));
                if (p.drawRotation) out.back().def.orientation = randomRotation(rng);
            }
        }
    }
}

void generateRandom(const RandomParams& p, const GeneratorCommon& common, std::vector<SceneBody>& out) {
    std::mt19937 rng(p.seed);
    // One distribution per axis; libstdc++'s uniform_real_distribution keeps no state between draws, so this
    // draws the same numbers as one shared distribution when the ranges agree (SCENES.md S4).
    using Uniform = std::uniform_real_distribution<float>;
    Uniform pos[3] = {Uniform(p.min[0], p.max[0]), Uniform(p.min[1], p.max[1]), Uniform(p.min[2], p.max[2])};
    Uniform vel[3] = {Uniform(p.velocityMin[0], p.velocityMax[0]), Uniform(p.velocityMin[1], p.velocityMax[1]),
                      Uniform(p.velocityMin[2], p.velocityMax[2])};
    for (std::uint64_t n = 0; n < p.count; ++n) {
        SceneBody b = common.prototype;
        b.shape = common.shapes[n % common.shapes.size()];
        // Sequenced statements, not one braced initializer, so the draw order is x, y, z by construction.
        b.def.position.x = pos[0](rng);
        b.def.position.y = pos[1](rng);
        b.def.position.z = pos[2](rng);
        if (p.drawVelocity) {
            b.def.linearVelocity.x = vel[0](rng);
            b.def.linearVelocity.y = vel[1](rng);
            b.def.linearVelocity.z = vel[2](rng);
        }
        if (p.drawRotation) b.def.orientation = randomRotation(rng);
        out.push_back(b);
    }
}

TriangleMeshDef generateTerrain(const TerrainParams& p) {
    TriangleMeshDef mesh;
    const std::uint32_t nx = p.cells[0], nz = p.cells[1];
    const std::uint32_t stride = nx + 1;
    mesh.vertices.reserve(static_cast<std::size_t>(nx + 1) * (nz + 1));
    for (std::uint32_t r = 0; r <= nz; ++r) {
        const double z = p.min[1] + (p.max[1] - p.min[1]) * static_cast<double>(r) / static_cast<double>(nz);
        for (std::uint32_t c = 0; c <= nx; ++c) {
            const double x = p.min[0] + (p.max[0] - p.min[0]) * static_cast<double>(c) / static_cast<double>(nx);
            const double y = p.amplitude * std::sin(x / p.wavelength[0]) * std::cos(z / p.wavelength[1]);
            mesh.vertices.push_back({static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
        }
    }
    mesh.indices.reserve(static_cast<std::size_t>(nx) * nz * 6);
    for (std::uint32_t r = 0; r < nz; ++r) {
        for (std::uint32_t c = 0; c < nx; ++c) {
            const std::uint32_t v00 = r * stride + c;  // (x0, z0)
            const std::uint32_t v10 = v00 + 1;         // (x1, z0)
            const std::uint32_t v01 = v00 + stride;    // (x0, z1)
            const std::uint32_t v11 = v01 + 1;         // (x1, z1)
            // With x right and z towards the viewer below +y, (v00, v01, v11) and (v00, v11, v10) have +y normals.
            mesh.indices.insert(mesh.indices.end(), {v00, v01, v11, v00, v11, v10});
        }
    }
    return mesh;
}

}  // namespace rubble::scene_detail
