// Heightfields: a regular grid of samples, each cell split along its (x0, z0)-(x1, z1) diagonal. The split and the
// triangle test are the mesh's own, so a heightfield and a mesh built from the same samples agree.
#include <algorithm>
#include <cmath>
#include <string>

#include "rubble/error.h"
#include "rubble/limits.h"
#include "shapes/shape.h"
#include "world/validation.h"

namespace rubble::detail {

namespace {

constexpr const char* kDef = "HeightfieldDef";

}  // namespace

Heightfield buildHeightfield(const HeightfieldDef& def) {
    if (def.rows < 2) fail(kDef, "rows must be >= 2 (got " + std::to_string(def.rows) + ")");
    if (def.columns < 2) fail(kDef, "columns must be >= 2 (got " + std::to_string(def.columns) + ")");
    const char* axes[] = {"spacing.x", "spacing.y", "spacing.z"};
    const float spacing[] = {def.spacing.x, def.spacing.y, def.spacing.z};
    for (int i = 0; i < 3; ++i) {
        if (!std::isfinite(spacing[i]))
            fail(kDef, std::string(axes[i]) + " is not finite (" + formatNumber(spacing[i]) + ")");
        if (!(spacing[i] > 0)) fail(kDef, std::string(axes[i]) + " must be > 0 (got " + formatNumber(spacing[i]) + ")");
    }
    // Counted in 64 bits: rows * columns of two 32-bit numbers overflows 32.
    const std::uint64_t triangles = 2 * (std::uint64_t(def.rows) - 1) * (std::uint64_t(def.columns) - 1);
    if (triangles > limits::kMaxMeshTriangles)
        fail(kDef, "rows and columns make " + std::to_string(triangles) + " triangles, more than " +
                       std::to_string(limits::kMaxMeshTriangles) + " (docs/limits.md)");
    const std::uint64_t expected = std::uint64_t(def.rows) * def.columns;
    if (def.heights.size() != expected)
        fail(kDef, "heights has " + std::to_string(def.heights.size()) +
                       " values but rows * columns = " + std::to_string(expected));
    Heightfield field;
    field.rows = def.rows;
    field.columns = def.columns;
    field.spacingX = def.spacing.x;
    field.spacingZ = def.spacing.z;
    field.heights.resize(def.heights.size());
    for (std::size_t i = 0; i < def.heights.size(); ++i) {
        if (!std::isfinite(def.heights[i]))
            fail(kDef, "heights[" + std::to_string(i) + "] is not finite (" + formatNumber(def.heights[i]) + ")");
        field.heights[i] = def.heights[i] * def.spacing.y;
        if (!std::isfinite(field.heights[i]))
            fail(kDef,
                 "heights[" + std::to_string(i) + "] * spacing.y overflows (" + formatNumber(def.heights[i]) + ")");
    }
    return field;
}

std::optional<float> heightfieldHeightAt(const Heightfield& field, float x, float z) {
    if (field.rows < 2 || field.columns < 2) return std::nullopt;
    const double fx = double(x) / field.spacingX, fz = double(z) / field.spacingZ;
    constexpr double slack = 1e-6;  // matches the triangle test's tolerance on the outer edges
    if (!(fx >= -slack && fx <= double(field.columns - 1) + slack && fz >= -slack &&
          fz <= double(field.rows - 1) + slack))
        return std::nullopt;  // also refuses NaN
    const auto c = std::uint32_t(std::clamp(std::floor(fx), 0.0, double(field.columns - 2)));
    const auto r = std::uint32_t(std::clamp(std::floor(fz), 0.0, double(field.rows - 2)));
    const Vec3 p00 = heightfieldSample(field, r, c), p10 = heightfieldSample(field, r, c + 1);
    const Vec3 p01 = heightfieldSample(field, r + 1, c), p11 = heightfieldSample(field, r + 1, c + 1);
    // Counter-clockwise seen from above, like a mesh exported from the same grid.
    std::optional<float> best = triangleHeightAt(p00, p01, p11, x, z);
    const std::optional<float> other = triangleHeightAt(p00, p11, p10, x, z);
    if (other && (!best || *other > *best)) best = other;
    return best;
}

std::uint32_t heightfieldTriangleCount(const Heightfield& field) {
    if (field.rows < 2 || field.columns < 2) return 0;
    return 2 * (field.rows - 1) * (field.columns - 1);
}

std::array<Vec3, 3> heightfieldTriangle(const Heightfield& field, std::uint32_t triangle) {
    const std::uint32_t cell = triangle / 2, cellsPerRow = field.columns - 1;
    const std::uint32_t r = cell / cellsPerRow, c = cell % cellsPerRow;
    const Vec3 p00 = heightfieldSample(field, r, c), p10 = heightfieldSample(field, r, c + 1);
    const Vec3 p01 = heightfieldSample(field, r + 1, c), p11 = heightfieldSample(field, r + 1, c + 1);
    if ((triangle & 1) == 0) return {p00, p01, p11};
    return {p00, p11, p10};
}

}  // namespace rubble::detail
