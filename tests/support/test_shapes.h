#pragma once
// Shape inputs the narrow-phase tests share: random convex point clouds, box corners and flat grid meshes.
#include <cstdint>
#include <random>
#include <vector>

#include "rubble/shapes.h"

namespace rubble::test {

/// `points` points drawn uniformly inside an ellipsoid whose semi-axes are `scale` times [0.4, 1) each (drawn
/// first), for random convex hulls.
inline std::vector<Vec3> randomHullCloud(std::mt19937& rng, int points, float scale) {
    std::uniform_real_distribution<float> u(-1, 1), s(0.4f, 1.0f);
    const Vec3 axes{scale * s(rng), scale * s(rng), scale * s(rng)};
    std::vector<Vec3> cloud;
    while (static_cast<int>(cloud.size()) < points) {
        const Vec3 p{u(rng), u(rng), u(rng)};
        if (dot(p, p) > 1) continue;
        cloud.push_back({p.x * axes.x, p.y * axes.y, p.z * axes.z});
    }
    return cloud;
}

/// The eight corners of a box with half extents h, centred at the origin.
inline std::vector<Vec3> boxCorners(Vec3 h) {
    std::vector<Vec3> corners;
    for (int i = 0; i < 8; ++i) corners.push_back({i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z});
    return corners;
}

/// A grid of 1 m cells, `columns` along x by `rows` along z from (x0, z0), each cell split into two triangles along
/// its (x0, z0)-(x1, z1) diagonal, counter-clockwise seen from +y; vertex (x, z) at height(x, z).
template <class Height>
TriangleMeshDef gridMesh(int columns, int rows, float x0, float z0, Height&& height) {
    TriangleMeshDef grid;
    for (int r = 0; r <= rows; ++r)
        for (int c = 0; c <= columns; ++c) {
            const float x = x0 + static_cast<float>(c), z = z0 + static_cast<float>(r);
            grid.vertices.push_back({x, height(x, z), z});
        }
    const auto row = static_cast<std::uint32_t>(columns + 1);
    for (std::uint32_t r = 0; r < static_cast<std::uint32_t>(rows); ++r)
        for (std::uint32_t c = 0; c < static_cast<std::uint32_t>(columns); ++c) {
            const std::uint32_t a = r * row + c, b = a + 1, d = a + row, e = d + 1;
            grid.indices.insert(grid.indices.end(), {a, d, e, a, e, b});
        }
    return grid;
}

/// A flat n x n grid of 1 m cells in the plane y = 0, centred at the origin, two triangles per cell.
inline TriangleMeshDef flatGridMesh(int n) {
    const float half = static_cast<float>(n) / 2;
    return gridMesh(n, n, -half, -half, [](float, float) { return 0.0f; });
}

}  // namespace rubble::test
