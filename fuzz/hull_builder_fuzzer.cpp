// Point clouds from anyone: World::createShape(ConvexHullDef) either refuses the cloud with a message naming
// ConvexHullDef, or builds its convex hull. What it builds is checked against the definition of a convex hull, not
// against the builder's own steps: every corner is one of the given points, no given point lies outside any face,
// every face is planar and the corners lie behind every face (convex), and the mass properties are finite with a
// positive volume and a positive definite inertia.
//
// The first byte picks how the rest becomes points: raw float bit patterns (NaN, infinities and extremes included),
// a coarse integer grid (duplicates, coplanar faces and collinear edges everywhere), or points on a sphere nudged by
// a few units in the last place (the nearly coplanar faces that trouble hull builders).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_support.h"
#include "rubble/error.h"
#include "rubble/shape_geometry.h"
#include "rubble/shapes.h"
#include "rubble/world.h"

namespace {

using namespace rubble;

std::vector<Vec3> pointsFrom(fuzz::FuzzInput& in) {
    std::vector<Vec3> points;
    const std::uint8_t mode = in.byte() % 3;
    const float scale = std::ldexp(1.0f, static_cast<int>(in.byte() % 24) - 12);  // 2^-12 .. 2^11 m
    while (!in.empty() && points.size() < 6000) {
        if (mode == 0) {
            points.push_back({in.bits(), in.bits(), in.bits()});
        } else if (mode == 1) {
            auto coordinate = [&] { return static_cast<float>(static_cast<int>(in.byte() % 9) - 4) * scale; };
            points.push_back({coordinate(), coordinate(), coordinate()});
        } else {
            const float theta = in.in(0, 3.14159265f), phi = in.in(0, 6.2831853f);
            Vec3 p{std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)};
            const int ulps = static_cast<int>(in.byte() % 9) - 4;
            p = p * (scale * (1 + static_cast<float>(ulps) * 1.2e-7f));
            points.push_back(p);
        }
    }
    return points;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::FuzzInput in(data, size);
    ConvexHullDef def;
    def.points = pointsFrom(in);

    WorldSettings settings;
    settings.threads = 1;
    World world(settings);
    ShapeId shape;
    try {
        shape = world.createShape(def);
    } catch (const Error& e) {
        fuzz::check(std::string_view(e.what()).find("ConvexHullDef") != std::string_view::npos,
                    "the refusal does not name ConvexHullDef: " + std::string(e.what()));
        return 0;
    }
    const ShapeGeometry hull = world.shapeGeometry(shape);
    fuzz::check(hull.vertices.size() >= 4 && hull.indices.size() >= 12 && hull.indices.size() % 3 == 0,
                "a hull of fewer than four corners or faces");

    double extent = 0;
    for (const Vec3& p : def.points)
        extent = std::max({extent, std::abs(double{p.x}), std::abs(double{p.y}), std::abs(double{p.z})});
    // The points are floats (relative rounding 6e-8) and qhull merges faces that are flat to a few of those; a
    // thousand times that is far below any feature a point cloud of this extent can show.
    const double tolerance = 1e-4 * extent;

    for (const Vec3& corner : hull.vertices) {
        const bool given = std::any_of(def.points.begin(), def.points.end(), [&](const Vec3& p) {
            return std::abs(p.x - corner.x) <= tolerance && std::abs(p.y - corner.y) <= tolerance &&
                   std::abs(p.z - corner.z) <= tolerance;
        });
        fuzz::check(given, "a hull corner that is none of the given points");
    }
    for (std::size_t t = 0; t < hull.indices.size(); t += 3) {
        const Vec3 a = hull.vertices[hull.indices[t]], b = hull.vertices[hull.indices[t + 1]],
                   c = hull.vertices[hull.indices[t + 2]];
        const double nx = (double{b.y} - a.y) * (double{c.z} - a.z) - (double{b.z} - a.z) * (double{c.y} - a.y);
        const double ny = (double{b.z} - a.z) * (double{c.x} - a.x) - (double{b.x} - a.x) * (double{c.z} - a.z);
        const double nz = (double{b.x} - a.x) * (double{c.y} - a.y) - (double{b.y} - a.y) * (double{c.x} - a.x);
        const double length = std::sqrt(nx * nx + ny * ny + nz * nz);
        if (!(length > 1e-12 * extent * extent)) continue;  // a fan's sliver: its face's other triangles judge it
        auto outside = [&](const Vec3& p) {
            return ((double{p.x} - a.x) * nx + (double{p.y} - a.y) * ny + (double{p.z} - a.z) * nz) / length;
        };
        for (const Vec3& p : def.points)
            fuzz::check(outside(p) <= tolerance, "a given point lies " + std::to_string(outside(p)) +
                                                     " m outside hull triangle " + std::to_string(t / 3));
        for (const Vec3& corner : hull.vertices)
            fuzz::check(outside(corner) <= tolerance, "the hull is not convex at triangle " + std::to_string(t / 3));
    }

    const MassProperties mass = world.shapeMassProperties(shape);
    fuzz::check(std::isfinite(mass.mass) && mass.mass > 0, "a hull without a positive finite volume");
    const Mat3& I = mass.inertia;
    const double d0 = I(0, 0), d1 = I(1, 1), d2 = I(2, 2);
    const double m01 = d0 * d1 - double{I(0, 1)} * I(1, 0);
    const double det = d0 * (d1 * d2 - double{I(1, 2)} * I(2, 1)) -
                       I(0, 1) * (I(1, 0) * d2 - double{I(1, 2)} * I(2, 0)) +
                       I(0, 2) * (double{I(1, 0)} * I(2, 1) - d1 * I(2, 0));
    // Sylvester's criterion, loosened by rounding: a flat sliver of a hull may have one principal moment near zero.
    const double scale = std::max({d0, d1, d2});
    fuzz::check(std::isfinite(det) && d0 > 0 && d1 > 0 && d2 > 0 && m01 >= -1e-6 * scale * scale &&
                    det >= -1e-6 * scale * scale * scale,
                "a hull whose inertia is not positive definite");
    return 0;
}
