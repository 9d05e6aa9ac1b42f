// OBJ text from anyone: parseObj either refuses it with a message naming the file, or returns a mesh whose indices
// are in range and whose vertices are finite. A mesh the World accepts must then answer rays as brute force does: a
// ray aimed at the middle of a well-shaped triangle from in front of it hits no later than that triangle, and no
// earlier than the first triangle brute force finds along it (in double, with a generous edge margin).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>

#include "fuzz_support.h"
#include "rubble/error.h"
#include "rubble/shapes.h"
#include "rubble/world.h"

namespace {

using namespace rubble;

struct D3 {
    double x, y, z;
};
D3 toD3(Vec3 v) { return {v.x, v.y, v.z}; }
D3 sub(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
double dotD(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 crossD(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

/// Distance along the ray (unit `dir`) to the triangle's plane where the ray crosses it within `margin` (barycentric)
/// of the triangle, either side; infinity otherwise.
double rayTriangle(D3 origin, D3 dir, D3 a, D3 b, D3 c, double margin) {
    const D3 e1 = sub(b, a), e2 = sub(c, a);
    const D3 p = crossD(dir, e2);
    const double det = dotD(e1, p);
    const D3 s = sub(origin, a);
    const D3 n = crossD(e1, e2);
    const double area2 = std::sqrt(dotD(n, n));
    // A ray in the triangle's plane (to rounding) may touch it anywhere along its length: brute force cannot say
    // where, so it allows a hit from the origin on.
    if (std::abs(det) <= 1e-6 * area2 && std::abs(dotD(s, n)) <= 1e-6 * area2 * (1 + std::sqrt(dotD(s, s)))) return 0;
    if (std::abs(det) < 1e-300) return std::numeric_limits<double>::infinity();
    const double u = dotD(s, p) / det;
    const D3 q = crossD(s, e1);
    const double v = dotD(dir, q) / det;
    const double t = dotD(e2, q) / det;
    // A ray that starts on the triangle crosses it at 0, which rounding may put a hair behind the origin.
    if (u < -margin || v < -margin || u + v > 1 + margin || t < -1e-9) return std::numeric_limits<double>::infinity();
    return std::max(t, 0.0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string source = "fuzz/mesh.obj";
    TriangleMeshDef mesh;
    try {
        mesh = parseObj(std::string_view(reinterpret_cast<const char*>(data), size), source);
    } catch (const Error& e) {
        fuzz::check(std::string_view(e.what()).find(source) != std::string_view::npos,
                    "the OBJ reader's message does not name the file: " + std::string(e.what()));
        return 0;
    }
    fuzz::check(!mesh.indices.empty() && mesh.indices.size() % 3 == 0, "a mesh of whole triangles");
    for (std::uint32_t index : mesh.indices) fuzz::check(index < mesh.vertices.size(), "an index out of range");
    for (const Vec3& v : mesh.vertices)
        fuzz::check(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z), "a non-finite vertex");

    WorldSettings settings;
    settings.threads = 1;
    World world(settings);
    ShapeId shape;
    try {
        shape = world.createShape(mesh);  // sizes and coordinates beyond the limits are refused here
    } catch (const Error&) {
        return 0;
    }
    BodyDef def;
    def.type = BodyType::Static;
    def.shape = shape;
    world.createBody(def);

    double extent = 0;
    for (const Vec3& v : mesh.vertices)
        extent = std::max({extent, std::abs(double{v.x}), std::abs(double{v.y}), std::abs(double{v.z})});
    const double tolerance = 1e-4 * (1 + extent);
    QueryFilter filter;
    filter.hitBackFaces = true;
    const std::size_t triangles = mesh.indices.size() / 3;
    for (std::size_t t = 0; t < std::min<std::size_t>(triangles, 8); ++t) {
        const D3 a = toD3(mesh.vertices[mesh.indices[3 * t]]), b = toD3(mesh.vertices[mesh.indices[3 * t + 1]]),
                 c = toD3(mesh.vertices[mesh.indices[3 * t + 2]]);
        const D3 n = crossD(sub(b, a), sub(c, a));
        const double area2 = std::sqrt(dotD(n, n));
        const double longest =
            std::max({dotD(sub(b, a), sub(b, a)), dotD(sub(c, b), sub(c, b)), dotD(sub(a, c), sub(a, c))});
        // Slivers and specks are left out: where float rounding decides the hit, brute force in double is no judge.
        if (!(area2 > 1e-2 * longest) || !(longest > 1e-4)) continue;
        const D3 unit{n.x / area2, n.y / area2, n.z / area2};
        const D3 centroid{(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3, (a.z + b.z + c.z) / 3};
        const double standoff = 1 + 0.1 * extent;
        const D3 origin{centroid.x + unit.x * standoff, centroid.y + unit.y * standoff, centroid.z + unit.z * standoff};
        const D3 dir{-unit.x, -unit.y, -unit.z};
        double first = std::numeric_limits<double>::infinity();
        for (std::size_t k = 0; k < triangles; ++k)
            first = std::min(first, rayTriangle(origin, dir, toD3(mesh.vertices[mesh.indices[3 * k]]),
                                                toD3(mesh.vertices[mesh.indices[3 * k + 1]]),
                                                toD3(mesh.vertices[mesh.indices[3 * k + 2]]), 1e-3));
        const Vec3 o{static_cast<float>(origin.x), static_cast<float>(origin.y), static_cast<float>(origin.z)};
        const Vec3 d{static_cast<float>(dir.x), static_cast<float>(dir.y), static_cast<float>(dir.z)};
        const std::optional<RayHit> hit = world.castRay(o, d, std::numeric_limits<float>::infinity(), filter);
        fuzz::check(hit.has_value(), "a ray at the middle of triangle " + std::to_string(t) + " hit nothing");
        fuzz::check(hit->distance <= standoff + tolerance, "a ray at the middle of triangle " + std::to_string(t) +
                                                               " hit beyond it, at " + std::to_string(hit->distance) +
                                                               " of " + std::to_string(standoff));
        fuzz::check(hit->distance >= first - tolerance,
                    "a ray from (" + std::to_string(o.x) + ", " + std::to_string(o.y) + ", " + std::to_string(o.z) +
                        ") along (" + std::to_string(d.x) + ", " + std::to_string(d.y) + ", " + std::to_string(d.z) +
                        ") hit triangle " + std::to_string(hit->triangle) + " at " + std::to_string(hit->distance) +
                        ", before the first triangle along it (" + std::to_string(first) + ")");
    }
    return 0;
}
