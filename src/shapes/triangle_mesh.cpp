// Static triangle meshes: validation, the xz grid behind height look-ups, and the OBJ reader.
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "core/file_reading.h"
#include "rubble/error.h"
#include "rubble/limits.h"
#include "shapes/shape.h"
#include "world/validation.h"

namespace rubble::detail {

namespace {

constexpr const char* kDef = "TriangleMeshDef";

}  // namespace

std::optional<float> triangleHeightAt(Vec3 a, Vec3 b, Vec3 c, float x, float z) {
    // Double precision so that a mesh and a heightfield holding the same samples give the same answer.
    const double abx = double(b.x) - a.x, abz = double(b.z) - a.z;
    const double acx = double(c.x) - a.x, acz = double(c.z) - a.z;
    const double area2 = abx * acz - acx * abz;
    const double scale = std::max({std::abs(abx), std::abs(abz), std::abs(acx), std::abs(acz)});
    // Vertical or degenerate in xz: no single height exists, and the neighbours cover the point anyway.
    if (!(std::abs(area2) > 1e-12 * scale * scale)) return std::nullopt;
    const double px = double(x) - a.x, pz = double(z) - a.z;
    const double v = (px * acz - acx * pz) / area2;
    const double w = (abx * pz - px * abz) / area2;
    const double u = 1.0 - v - w;
    // A tiny tolerance closes the hairline gaps rounding would open along shared edges.
    constexpr double tol = 1e-6;
    if (u < -tol || v < -tol || w < -tol) return std::nullopt;
    return float(u * a.y + v * b.y + w * c.y);
}

TriangleMesh buildTriangleMesh(const TriangleMeshDef& def) {
    for (std::size_t i = 0; i < def.vertices.size(); ++i)
        if (!isFinite(def.vertices[i]))
            fail(kDef, "vertices[" + std::to_string(i) + "] is not finite " + describe(def.vertices[i]));
    if (def.indices.empty()) fail(kDef, "needs at least one triangle (indices is empty)");
    if (def.indices.size() % 3 != 0)
        fail(kDef, "indices has " + std::to_string(def.indices.size()) + " values, not a multiple of 3");
    for (std::size_t i = 0; i < def.indices.size(); ++i)
        if (def.indices[i] >= def.vertices.size())
            fail(kDef, "indices[" + std::to_string(i) + "] = " + std::to_string(def.indices[i]) + " is out of range (" +
                           std::to_string(def.vertices.size()) + " vertices)");

    TriangleMesh mesh;
    mesh.vertices = def.vertices;
    mesh.indices = def.indices;
    const std::uint32_t triangles = mesh.triangleCount();

    // Bounds over referenced vertices only: stray unused vertices must not stretch the grid or the AABB.
    Vec3 lo = mesh.vertices[mesh.indices[0]], hi = lo;
    double extentSum = 0;
    for (std::uint32_t t = 0; t < triangles; ++t) {
        Vec3 tlo = mesh.vertices[mesh.indices[3 * t]], thi = tlo;
        for (int k = 0; k < 3; ++k) {
            const Vec3 p = mesh.vertices[mesh.indices[3 * t + k]];
            tlo = {std::min(tlo.x, p.x), std::min(tlo.y, p.y), std::min(tlo.z, p.z)};
            thi = {std::max(thi.x, p.x), std::max(thi.y, p.y), std::max(thi.z, p.z)};
        }
        lo = {std::min(lo.x, tlo.x), std::min(lo.y, tlo.y), std::min(lo.z, tlo.z)};
        hi = {std::max(hi.x, thi.x), std::max(hi.y, thi.y), std::max(hi.z, thi.z)};
        extentSum += std::max(double(thi.x) - tlo.x, double(thi.z) - tlo.z);
    }
    mesh.bounds = {lo, hi};

    // Cells about one triangle across keep each look-up to a handful of triangles; the cap bounds memory for
    // meshes of a few huge triangles next to many tiny ones.
    const double width = double(hi.x) - lo.x, depth = double(hi.z) - lo.z;
    double cell = extentSum / triangles;
    if (!(cell > 0)) cell = std::max({width, depth, 1.0});
    const double maxCells = 4.0 * triangles;
    auto counts = [&](double size) {
        const double cx = std::max(1.0, std::ceil(width / size)), cz = std::max(1.0, std::ceil(depth / size));
        return std::pair{cx, cz};
    };
    while (counts(cell).first * counts(cell).second > maxCells) cell *= 1.25;
    const auto [cx, cz] = counts(cell);
    mesh.cellSize = float(cell);
    mesh.cellsX = std::uint32_t(cx);
    mesh.cellsZ = std::uint32_t(cz);

    auto cellRange = [&](std::uint32_t t, std::uint32_t range[4]) {
        float minX = HUGE_VALF, maxX = -HUGE_VALF, minZ = HUGE_VALF, maxZ = -HUGE_VALF;
        for (int k = 0; k < 3; ++k) {
            const Vec3 p = mesh.vertices[mesh.indices[3 * t + k]];
            minX = std::min(minX, p.x), maxX = std::max(maxX, p.x);
            minZ = std::min(minZ, p.z), maxZ = std::max(maxZ, p.z);
        }
        auto index = [&](double v, double origin, std::uint32_t n) {
            const double i = std::floor((v - origin) / cell);
            return std::uint32_t(std::clamp(i, 0.0, double(n - 1)));
        };
        range[0] = index(minX, lo.x, mesh.cellsX), range[1] = index(maxX, lo.x, mesh.cellsX);
        range[2] = index(minZ, lo.z, mesh.cellsZ), range[3] = index(maxZ, lo.z, mesh.cellsZ);
    };
    const std::size_t cellCount = std::size_t(mesh.cellsX) * mesh.cellsZ;
    mesh.cellStart.assign(cellCount + 1, 0);
    std::uint32_t r[4];
    for (std::uint32_t t = 0; t < triangles; ++t) {
        cellRange(t, r);
        for (std::uint32_t iz = r[2]; iz <= r[3]; ++iz)
            for (std::uint32_t ix = r[0]; ix <= r[1]; ++ix) ++mesh.cellStart[std::size_t(iz) * mesh.cellsX + ix + 1];
    }
    for (std::size_t i = 0; i < cellCount; ++i) mesh.cellStart[i + 1] += mesh.cellStart[i];
    mesh.cellTriangles.resize(mesh.cellStart[cellCount]);
    std::vector<std::uint32_t> fill(mesh.cellStart.begin(), mesh.cellStart.end() - 1);
    for (std::uint32_t t = 0; t < triangles; ++t) {
        cellRange(t, r);
        for (std::uint32_t iz = r[2]; iz <= r[3]; ++iz)
            for (std::uint32_t ix = r[0]; ix <= r[1]; ++ix)
                mesh.cellTriangles[fill[std::size_t(iz) * mesh.cellsX + ix]++] = t;
    }
    return mesh;
}

std::optional<float> meshHeightAt(const TriangleMesh& mesh, float x, float z) {
    if (mesh.cellsX == 0 || mesh.cellsZ == 0) return std::nullopt;
    const double slack = 1e-6 * std::max(1.0, double(mesh.cellSize));
    const double fx = (double(x) - mesh.bounds.min.x) / mesh.cellSize;
    const double fz = (double(z) - mesh.bounds.min.z) / mesh.cellSize;
    if (!(double(x) >= mesh.bounds.min.x - slack && double(x) <= mesh.bounds.max.x + slack &&
          double(z) >= mesh.bounds.min.z - slack && double(z) <= mesh.bounds.max.z + slack))
        return std::nullopt;  // also refuses NaN
    const auto ix = std::uint32_t(std::clamp(std::floor(fx), 0.0, double(mesh.cellsX - 1)));
    const auto iz = std::uint32_t(std::clamp(std::floor(fz), 0.0, double(mesh.cellsZ - 1)));
    const std::size_t cell = std::size_t(iz) * mesh.cellsX + ix;
    std::optional<float> best;
    for (std::uint32_t k = mesh.cellStart[cell]; k < mesh.cellStart[cell + 1]; ++k) {
        const std::uint32_t t = mesh.cellTriangles[k];
        const auto h = triangleHeightAt(mesh.vertices[mesh.indices[3 * t]], mesh.vertices[mesh.indices[3 * t + 1]],
                                        mesh.vertices[mesh.indices[3 * t + 2]], x, z);
        if (h && (!best || *h > *best)) best = h;
    }
    return best;
}

}  // namespace rubble::detail

namespace rubble {

namespace {

struct ObjReader {
    const std::string& path;
    std::size_t line = 0;

    [[noreturn]] void fail(const std::string& what) const {
        throw Error(path + ":" + std::to_string(line) + ": " + what);
    }

    // Shows a token in a message without letting binary junk or huge tokens through.
    static std::string quote(std::string_view token) {
        std::string out = "'";
        for (char c : token.substr(0, 32)) out += (c >= 32 && c < 127) ? c : '?';
        if (token.size() > 32) out += "...";
        return out + "'";
    }

    float number(std::string_view token) const {
        std::string_view t = token;
        if (!t.empty() && t.front() == '+') t.remove_prefix(1);  // from_chars refuses a leading '+'
        float value = 0;
        const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
        if (ec != std::errc() || end != t.data() + t.size()) fail("bad number " + quote(token) + " in a 'v' line");
        if (!std::isfinite(value)) fail("vertex coordinate " + quote(token) + " is not finite");
        return value;
    }

    std::uint32_t faceIndex(std::string_view token, std::size_t vertexCount) const {
        // "a", "a/b", "a//c", "a/b/c": only the position index matters to a collision mesh.
        const std::string_view first = token.substr(0, token.find('/'));
        std::size_t slashes = std::count(token.begin(), token.end(), '/');
        if (first.empty() || slashes > 2) fail("bad face vertex " + quote(token));
        long long index = 0;
        const auto [end, ec] = std::from_chars(first.data(), first.data() + first.size(), index);
        if (ec != std::errc() || end != first.data() + first.size()) fail("bad face vertex " + quote(token));
        if (index == 0) fail("face index 0 is invalid (OBJ indices start at 1)");
        // Negative indices count back from the latest vertex.
        const long long resolved = index > 0 ? index - 1 : static_cast<long long>(vertexCount) + index;
        if (resolved < 0 || resolved >= static_cast<long long>(vertexCount))
            fail("face index " + std::to_string(index) + " is out of range (" + std::to_string(vertexCount) +
                 " vertices)");
        return static_cast<std::uint32_t>(resolved);
    }
};

std::vector<std::string_view> tokens(std::string_view line) {
    std::vector<std::string_view> out;
    std::size_t i = 0;
    auto space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; };
    while (i < line.size()) {
        while (i < line.size() && space(line[i])) ++i;
        const std::size_t start = i;
        while (i < line.size() && !space(line[i])) ++i;
        if (i > start) out.push_back(line.substr(start, i - start));
    }
    return out;
}

}  // namespace

TriangleMeshDef loadObj(const std::string& path) {
    return parseObj(detail::readRegularFile(path, limits::kMaxObjFileBytes, "an OBJ file"), path);
}

TriangleMeshDef parseObj(std::string_view text, const std::string& sourceName) {
    if (text.size() > limits::kMaxObjFileBytes)
        throw Error(sourceName + ": larger than " + std::to_string(limits::kMaxObjFileBytes >> 20) +
                    " MiB, the most an OBJ file may be (docs/limits.md)");
    TriangleMeshDef mesh;
    ObjReader reader{sourceName};
    std::string_view rest = text;
    std::vector<std::uint32_t> polygon;
    while (!rest.empty()) {
        const std::size_t newline = rest.find('\n');
        std::string_view line = rest.substr(0, newline);
        rest = newline == std::string_view::npos ? std::string_view{} : rest.substr(newline + 1);
        ++reader.line;
        line = line.substr(0, line.find('#'));
        const std::vector<std::string_view> t = tokens(line);
        if (t.empty()) continue;
        if (t[0] == "v") {
            // x y z, optionally w or an r g b colour some exporters append; only the position is used.
            if (t.size() < 4) reader.fail("'v' needs 3 coordinates (got " + std::to_string(t.size() - 1) + ")");
            if (t.size() > 8) reader.fail("'v' has too many values (" + std::to_string(t.size() - 1) + ")");
            for (std::size_t k = 4; k < t.size(); ++k) reader.number(t[k]);
            mesh.vertices.push_back({reader.number(t[1]), reader.number(t[2]), reader.number(t[3])});
        } else if (t[0] == "f") {
            if (t.size() < 4) reader.fail("face needs at least 3 vertices (got " + std::to_string(t.size() - 1) + ")");
            polygon.clear();
            for (std::size_t k = 1; k < t.size(); ++k) polygon.push_back(reader.faceIndex(t[k], mesh.vertices.size()));
            for (std::size_t k = 1; k + 1 < polygon.size(); ++k)
                mesh.indices.insert(mesh.indices.end(), {polygon[0], polygon[k], polygon[k + 1]});
            if (mesh.indices.size() / 3 > limits::kMaxMeshTriangles)
                reader.fail("more than " + std::to_string(limits::kMaxMeshTriangles) + " triangles (docs/limits.md)");
        }
        // Everything else (vt, vn, o, g, s, usemtl, mtllib, l, p, unknown) does not shape a collision mesh.
    }
    if (mesh.indices.empty()) throw Error(sourceName + ": no faces (a triangle mesh needs at least one 'f' line)");
    return mesh;
}

}  // namespace rubble
