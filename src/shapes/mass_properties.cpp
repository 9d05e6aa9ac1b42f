// Mass properties at unit density. Everything is accumulated in double: inertia of a thin or far-off-centre
// shape is a small difference of large terms, and float loses it.
#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <variant>

#include "rubble/error.h"
#include "rubble/limits.h"
#include "shapes/shape.h"
#include "world/validation.h"

namespace rubble::detail {

namespace {

using Mat3d = Eigen::Matrix3d;
using Vec3d = Eigen::Vector3d;

Vec3d toEigen(Vec3 v) { return {v.x, v.y, v.z}; }
Vec3 toVec3(const Vec3d& v) { return {float(v.x()), float(v.y()), float(v.z())}; }

Mat3d toEigen(const Mat3& m) {
    Mat3d r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r(i, j) = m(i, j);
    return r;
}

Mat3 toMat3(const Mat3d& m) {
    Mat3 r = Mat3::zero();
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r(i, j) = float(m(i, j));
    return r;
}

MassProperties diagonalMass(double mass, double ix, double iy, double iz) {
    MassProperties mp;
    mp.mass = float(mass);
    mp.inertia = Mat3::diagonal({float(ix), float(iy), float(iz)});
    return mp;
}

MassProperties sphereMass(double r) {
    const double m = 4.0 / 3.0 * std::numbers::pi * r * r * r;
    const double i = 0.4 * m * r * r;
    return diagonalMass(m, i, i, i);
}

MassProperties boxMass(Vec3 h) {
    const double x = h.x, y = h.y, z = h.z;
    const double m = 8.0 * x * y * z;
    // m/12 (b^2 + c^2) with full lengths b = 2y, c = 2z.
    return diagonalMass(m, m / 3.0 * (y * y + z * z), m / 3.0 * (x * x + z * z), m / 3.0 * (x * x + y * y));
}

MassProperties capsuleMass(double r, double h) {
    const double pi = std::numbers::pi;
    const double mc = pi * r * r * 2.0 * h;        // cylinder of length 2h
    const double ms = 4.0 / 3.0 * pi * r * r * r;  // both hemispheres together
    const double iy = 0.5 * mc * r * r + 0.4 * ms * r * r;
    // Cylinder about a diameter through its centre: mc (r^2/4 + L^2/12).
    const double cylinderPerp = mc * (0.25 * r * r + (2.0 * h) * (2.0 * h) / 12.0);
    // A hemisphere about a diameter of its flat face has 2/5 m r^2 like the full sphere. Move that to the
    // hemisphere's centroid (3r/8 off the face), then out to the capsule centre at h + 3r/8.
    const double c = 3.0 * r / 8.0;
    const double hemiPerp = ms * (0.4 * r * r - c * c + (h + c) * (h + c));
    const double ix = cylinderPerp + hemiPerp;
    return diagonalMass(mc + ms, ix, iy, ix);
}

MassProperties compoundMass(const Shape& shape) {
    // Parallel-axis theorem: gather every child at its pose, then refer all inertias to the common centre.
    double total = 0;
    Vec3d weighted = Vec3d::Zero();
    for (const CompoundChild& c : shape.children) {
        const MassProperties& m = c.shape->unitMass;
        total += m.mass;
        weighted += double(m.mass) * toEigen(apply(c.local, m.centerOfMass));
    }
    const Vec3d com = total > 0 ? Vec3d(weighted / total) : Vec3d::Zero();
    Mat3d inertia = Mat3d::Zero();
    for (const CompoundChild& c : shape.children) {
        const MassProperties& m = c.shape->unitMass;
        const Quat q = c.local.rotation;
        const Mat3d r = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized().toRotationMatrix();
        const Vec3d d = toEigen(apply(c.local, m.centerOfMass)) - com;
        inertia += r * toEigen(m.inertia) * r.transpose() +
                   double(m.mass) * (d.squaredNorm() * Mat3d::Identity() - d * d.transpose());
    }
    MassProperties mp;
    mp.mass = float(total);
    mp.centerOfMass = toVec3(com);
    mp.inertia = toMat3(0.5 * (inertia + inertia.transpose()));
    return mp;
}

}  // namespace

MassProperties hullMassProperties(const ConvexHull& hull) {
    if (hull.vertices.empty()) return {};
    // Integrate relative to a point inside the hull (the vertex mean) so every tetrahedron has positive volume
    // and the large-offset cancellation that an origin far outside would cause never happens.
    Vec3d ref = Vec3d::Zero();
    for (Vec3 v : hull.vertices) ref += toEigen(v);
    ref /= double(hull.vertices.size());

    double volume = 0;
    Vec3d firstMoment = Vec3d::Zero();
    Mat3d secondMoment = Mat3d::Zero();  // integral of x x^T over the solid, x relative to ref
    for (std::uint32_t f = 0; f < hull.faceCount(); ++f) {
        const std::uint32_t begin = hull.faceStart[f], end = hull.faceStart[f + 1];
        const Vec3d a = toEigen(hull.vertices[hull.faceVertices[begin]]) - ref;
        for (std::uint32_t k = begin + 1; k + 1 < end; ++k) {
            const Vec3d b = toEigen(hull.vertices[hull.faceVertices[k]]) - ref;
            const Vec3d c = toEigen(hull.vertices[hull.faceVertices[k + 1]]) - ref;
            // Tetrahedron (0, a, b, c): det = 6 V; its second moment is det/120 (sum w w^T + s s^T).
            const double det = a.dot(b.cross(c));
            const Vec3d s = a + b + c;
            volume += det / 6.0;
            firstMoment += det / 24.0 * s;
            secondMoment +=
                det / 120.0 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
        }
    }
    if (!(volume > 0)) return {};
    const Vec3d com = firstMoment / volume;
    const Mat3d central = secondMoment - volume * com * com.transpose();
    const Mat3d inertia = central.trace() * Mat3d::Identity() - central;

    MassProperties mp;
    mp.mass = float(volume);
    mp.centerOfMass = toVec3(com + ref);
    mp.inertia = toMat3(0.5 * (inertia + inertia.transpose()));
    return mp;
}

MassProperties unitMassProperties(const Shape& shape) {
    switch (shape.kind) {
        case ShapeKind::Sphere:
            return sphereMass(shape.radius);
        case ShapeKind::Box:
            return boxMass(shape.halfExtents);
        case ShapeKind::Capsule:
            return capsuleMass(shape.radius, shape.halfHeight);
        case ShapeKind::ConvexHull:
            return shape.hull ? hullMassProperties(*shape.hull) : MassProperties{};
        case ShapeKind::Compound:
            return compoundMass(shape);
        case ShapeKind::TriangleMesh:
        case ShapeKind::Heightfield:
            return {};
    }
    return {};
}

MassProperties scaleMass(const MassProperties& unit, float density) {
    MassProperties mp = unit;
    mp.mass = unit.mass * density;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) mp.inertia(i, j) = unit.inertia(i, j) * density;
    return mp;
}

PrincipalInertia principalAxes(const Mat3& inertia) {
    Mat3d m = toEigen(inertia);
    m = 0.5 * (m + m.transpose());
    const Eigen::SelfAdjointEigenSolver<Mat3d> solver(m);
    if (solver.info() != Eigen::Success || !m.allFinite())
        return {{inertia(0, 0), inertia(1, 1), inertia(2, 2)}, Quat{}};
    Mat3d r = solver.eigenvectors();
    // Eigenvectors come with arbitrary signs; a reflection would flip handedness, so turn it into a rotation.
    if (r.determinant() < 0) r.col(2) = -r.col(2);
    Eigen::Quaterniond q(r);
    q.normalize();
    const Vec3d moments = solver.eigenvalues();
    return {toVec3(moments), Quat{float(q.x()), float(q.y()), float(q.z()), float(q.w())}};
}

}  // namespace rubble::detail

namespace rubble {

MassProperties computeMassProperties(const ShapeDef& shape, float density) {
    if (std::holds_alternative<TriangleMeshDef>(shape) || std::holds_alternative<HeightfieldDef>(shape))
        throw Error(std::string("computeMassProperties: ") +
                    (std::holds_alternative<TriangleMeshDef>(shape) ? "TriangleMeshDef" : "HeightfieldDef") +
                    " is static-only and has no mass properties");
    detail::requireWithin("computeMassProperties", "density", density, limits::kMinDensity, limits::kMaxDensity,
                          "kg/m^3");
    return detail::scaleMass(detail::buildShape(shape).unitMass, density);
}

}  // namespace rubble
