// Convex hulls: topology of the merged faces, robustness to messy clouds, and mass properties against answers
// computed without the hull's own integration (closed forms, and a grid estimate from the face planes).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>

#include "rubble/error.h"
#include "shapes/shape.h"

namespace rubble::detail {
namespace {

struct Moments {
    double volume = 0;
    Eigen::Vector3d com = Eigen::Vector3d::Zero();
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
};

Eigen::Matrix3d toEigen(const Mat3& m) {
    Eigen::Matrix3d r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r(i, j) = m(i, j);
    return r;
}

// Independent estimate of a hull's mass properties: an n x n grid of columns over the xz bounds, each column cut
// exactly along y by the face half-spaces (midpoint rule in x and z, exact in y).
Moments gridEstimate(const ConvexHull& hull, int n) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(HUGE_VAL), hi = -lo;
    for (Vec3 v : hull.vertices) {
        lo = lo.cwiseMin(Eigen::Vector3d(v.x, v.y, v.z));
        hi = hi.cwiseMax(Eigen::Vector3d(v.x, v.y, v.z));
    }
    const double dx = (hi.x() - lo.x()) / n, dz = (hi.z() - lo.z()) / n, area = dx * dz;
    double m0 = 0;
    Eigen::Vector3d m1 = Eigen::Vector3d::Zero();
    Eigen::Matrix3d m2 = Eigen::Matrix3d::Zero();
    for (int i = 0; i < n; ++i) {
        const double x = lo.x() + (i + 0.5) * dx;
        for (int k = 0; k < n; ++k) {
            const double z = lo.z() + (k + 0.5) * dz;
            double ylo = -HUGE_VAL, yhi = HUGE_VAL;
            bool empty = false;
            for (std::uint32_t f = 0; f < hull.faceCount() && !empty; ++f) {
                const Vec3 nrm = hull.faceNormals[f];
                const double rhs = double(hull.faceOffsets[f]) - nrm.x * x - nrm.z * z;
                if (nrm.y > 1e-12)
                    yhi = std::min(yhi, rhs / nrm.y);
                else if (nrm.y < -1e-12)
                    ylo = std::max(ylo, rhs / nrm.y);
                else if (rhs < 0)
                    empty = true;
            }
            if (empty || !(yhi > ylo)) continue;
            const double len = yhi - ylo, iy = 0.5 * (yhi * yhi - ylo * ylo),
                         iyy = (yhi * yhi * yhi - ylo * ylo * ylo) / 3;
            m0 += len * area;
            m1 += area * Eigen::Vector3d(x * len, iy, z * len);
            Eigen::Matrix3d s;
            s << x * x * len, x * iy, x * z * len, x * iy, iyy, z * iy, x * z * len, z * iy, z * z * len;
            m2 += area * s;
        }
    }
    Moments r;
    r.volume = m0;
    r.com = m1 / m0;
    const Eigen::Matrix3d central = m2 - m0 * r.com * r.com.transpose();
    r.inertia = central.trace() * Eigen::Matrix3d::Identity() - central;
    return r;
}

// Structural invariants every hull must satisfy whatever the input.
void expectWellFormed(const ConvexHull& hull, const std::vector<Vec3>& input) {
    ASSERT_EQ(hull.faceStart.size(), hull.faceCount() + 1);
    ASSERT_EQ(hull.faceOffsets.size(), hull.faceCount());
    ASSERT_EQ(hull.faceStart.back(), hull.faceVertices.size());
    double size = 0, magnitude = 0;
    for (Vec3 p : input) {
        size = std::max(size, double(length(p - input[0])));
        magnitude = std::max(magnitude, double(length(p)));
    }
    // Float planes through float points: relative to the hull's size, plus float rounding of its position.
    const double tol = 1e-5 * size + 1e-6 * magnitude;
    // Euler characteristic of a convex polyhedron.
    EXPECT_EQ(int(hull.vertices.size()) - int(hull.edges.size() / 2) + int(hull.faceCount()), 2);
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
    for (std::uint32_t f = 0; f < hull.faceCount(); ++f) {
        const Vec3 n = hull.faceNormals[f];
        EXPECT_NEAR(length(n), 1.0, 1e-5);
        const std::uint32_t b = hull.faceStart[f], e = hull.faceStart[f + 1];
        ASSERT_GE(e - b, 3u);
        for (std::uint32_t k = b; k < e; ++k) {
            const Vec3 p0 = hull.vertices[hull.faceVertices[k]];
            const Vec3 p1 = hull.vertices[hull.faceVertices[k + 1 < e ? k + 1 : b]];
            const Vec3 p2 = hull.vertices[hull.faceVertices[k + 2 < e ? k + 2 : b + (k + 2 - e)]];
            EXPECT_NEAR(dot(n, p0), hull.faceOffsets[f], tol);  // on its plane
            EXPECT_GT(dot(cross(p1 - p0, p2 - p1), n), 0) << "face " << f << " is not convex counter-clockwise";
            ++directed[{hull.faceVertices[k], hull.faceVertices[k + 1 < e ? k + 1 : b]}];
        }
        for (Vec3 p : input) EXPECT_LE(dot(n, p), hull.faceOffsets[f] + tol);
    }
    // Closed and consistently oriented: each directed edge once, its reverse once, and matching the edge list.
    for (const auto& [edge, count] : directed) {
        EXPECT_EQ(count, 1);
        EXPECT_EQ(directed.count({edge.second, edge.first}), 1u);
    }
    EXPECT_EQ(directed.size(), hull.edges.size());
}

std::vector<Vec3> boxCorners(Vec3 h) {
    std::vector<Vec3> p;
    for (int i = 0; i < 8; ++i) p.push_back({i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z});
    return p;
}

TEST(ConvexHull, BoxWithDuplicateInteriorAndCoplanarPoints) {
    const Vec3 h{1.0f, 0.5f, 2.0f};
    std::vector<Vec3> pts = boxCorners(h);
    const std::vector<Vec3> corners = pts;
    for (Vec3 c : corners) pts.push_back(c);  // duplicates
    pts.push_back({0.1f, 0.2f, -0.3f});       // interior
    pts.push_back({0, 0, 0});
    for (int a = 0; a < 3; ++a)  // face centres
        for (float s : {-1.0f, 1.0f}) {
            Vec3 p{};
            p[a] = s * h[a];
            pts.push_back(p);
        }
    for (std::size_t i = 0; i < corners.size(); ++i)  // edge midpoints (and face diagonals' midpoints)
        for (std::size_t j = i + 1; j < corners.size(); ++j) pts.push_back((corners[i] + corners[j]) * 0.5f);
    std::shuffle(pts.begin(), pts.end(), std::mt19937(7));

    const ConvexHull hull = buildConvexHull(pts);
    EXPECT_EQ(hull.vertices.size(), 8u);
    EXPECT_EQ(hull.faceCount(), 6u);
    EXPECT_EQ(hull.edges.size(), 24u);  // 12 edges, two indices each
    for (std::uint32_t f = 0; f < 6; ++f) {
        EXPECT_EQ(hull.faceStart[f + 1] - hull.faceStart[f], 4u);
        const Vec3 n = hull.faceNormals[f];
        const int axis = std::abs(n.x) > 0.5f ? 0 : std::abs(n.y) > 0.5f ? 1 : 2;
        EXPECT_NEAR(std::abs(n[axis]), 1.0f, 1e-6f);
        EXPECT_NEAR(hull.faceOffsets[f], h[axis], 1e-6f);
    }
    for (Vec3 v : hull.vertices) {
        EXPECT_EQ(std::abs(v.x), h.x);
        EXPECT_EQ(std::abs(v.y), h.y);
        EXPECT_EQ(std::abs(v.z), h.z);
    }
    expectWellFormed(hull, pts);

    // Same solid as the box primitive: mass properties to 1e-5 relative.
    const MassProperties hm = hullMassProperties(hull);
    const MassProperties bm = buildShape(BoxDef{h}).unitMass;
    EXPECT_NEAR(hm.mass, bm.mass, 1e-5 * bm.mass);
    EXPECT_NEAR(length(hm.centerOfMass), 0, 1e-5);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) EXPECT_NEAR(hm.inertia(i, j), bm.inertia(i, j), 1e-5 * bm.inertia(2, 2));
}

TEST(ConvexHull, SurfaceGridsMergeIntoPolygons) {
    // A 9x9 grid of points on every face of a box: many coplanar and edge points, still 6 quads.
    std::vector<Vec3> box;
    for (int a = 0; a < 3; ++a)
        for (float s : {-1.0f, 1.0f})
            for (int i = 0; i <= 8; ++i)
                for (int j = 0; j <= 8; ++j) {
                    float p[3];
                    p[a] = s;
                    p[(a + 1) % 3] = -1 + float(i) * 0.25f;
                    p[(a + 2) % 3] = -1 + float(j) * 0.25f;
                    box.push_back({p[0], p[1], p[2]});
                }
    const ConvexHull b = buildConvexHull(box);
    EXPECT_EQ(b.vertices.size(), 8u);
    EXPECT_EQ(b.faceCount(), 6u);
    EXPECT_EQ(b.edges.size(), 24u);
    expectWellFormed(b, box);

    // A 32-sided prism: two 32-gon caps and 32 quads, 64 vertices, 96 edges.
    std::vector<Vec3> prism;
    for (int i = 0; i < 32; ++i) {
        const double t = 2 * std::numbers::pi * i / 32;
        for (float y : {-0.5f, 0.5f}) prism.push_back({float(std::cos(t)), y, float(std::sin(t))});
        prism.push_back({0.5f * float(std::cos(t)), 0.5f, 0.5f * float(std::sin(t))});  // inside the top cap
    }
    const ConvexHull p = buildConvexHull(prism);
    EXPECT_EQ(p.vertices.size(), 64u);
    EXPECT_EQ(p.faceCount(), 34u);
    EXPECT_EQ(p.edges.size(), 2 * 96u);
    int caps = 0;
    for (std::uint32_t f = 0; f < p.faceCount(); ++f) caps += p.faceStart[f + 1] - p.faceStart[f] == 32;
    EXPECT_EQ(caps, 2);
    expectWellFormed(p, prism);
    // Volume of the prism: 32 triangles of the regular polygon, (32/2) sin(2 pi / 32), times height 1.
    EXPECT_NEAR(hullMassProperties(p).mass, 16 * std::sin(2 * std::numbers::pi / 32), 1e-5);
}

TEST(ConvexHull, OffsetBoxKeepsItsCentre) {
    std::vector<Vec3> pts = boxCorners({0.5f, 1.5f, 0.25f});
    for (Vec3& p : pts) p += Vec3{100, -40, 7};
    const MassProperties m = hullMassProperties(buildConvexHull(pts));
    EXPECT_NEAR(m.mass, 1.5, 1.5e-5);  // 1 * 3 * 0.5, 1e-5 relative
    EXPECT_NEAR(m.centerOfMass.x, 100, 1e-4);
    EXPECT_NEAR(m.centerOfMass.y, -40, 1e-4);
    EXPECT_NEAR(m.centerOfMass.z, 7, 1e-4);
    EXPECT_NEAR(m.inertia(0, 0), 1.5 / 12 * (9 + 0.25), 1e-5);  // m/12 (b^2 + c^2), full lengths
}

TEST(ConvexHull, TetrahedronClosedForm) {
    // Unit right tetrahedron: V = 1/6, COM = (1/4, 1/4, 1/4). From the moments of the corner tetrahedron
    // (integral x^2 dV = 1/60, integral xy dV = 1/120): central C_xx = 1/60 - V/16 = 1/160, C_xy = -1/480, so
    // I_xx = C_yy + C_zz = 1/80 and I_xy = -C_xy = 1/480. Tolerance 1e-7 (float storage of ~1e-2 values).
    const ConvexHull hull = buildConvexHull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}});
    EXPECT_EQ(hull.faceCount(), 4u);
    const MassProperties m = hullMassProperties(hull);
    const double mass = 1.0 / 6;
    EXPECT_NEAR(m.mass, mass, 1e-7);
    EXPECT_NEAR(m.centerOfMass.x, 0.25, 1e-7);
    EXPECT_NEAR(m.inertia(0, 0), 1.0 / 80, 1e-7);
    EXPECT_NEAR(m.inertia(0, 1), 1.0 / 480, 1e-7);
}

struct Cloud {
    const char* name;
    unsigned seed;
    Vec3 scale;
    int count;
};

class ConvexHullCloud : public ::testing::TestWithParam<Cloud> {};

TEST_P(ConvexHullCloud, MatchesGridEstimate) {
    const Cloud c = GetParam();
    std::mt19937 rng(c.seed);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<Vec3> pts;
    while (int(pts.size()) < c.count) {
        const Vec3 p{u(rng), u(rng), u(rng)};
        if (dot(p, p) > 1) continue;  // a ball's cloud gives many faces and vertices of every valence
        pts.push_back({p.x * c.scale.x + 3, p.y * c.scale.y - 1, p.z * c.scale.z + 0.5f});
    }
    const ConvexHull hull = buildConvexHull(pts);
    expectWellFormed(hull, pts);

    const MassProperties m = hullMassProperties(hull);
    // 400 x 400 columns, each exact along y. Observed differences are below 4e-6 relative (2e-4 for the "tiny"
    // cloud, whose float coordinates carry 1e-4 rounding relative to its 2e-3 size), so the tolerances are 0.1%:
    // volume within 0.1%, COM within 0.1% of the cloud's size, each inertia entry within 0.1% of the largest moment.
    const Moments ref = gridEstimate(hull, 400);
    const double size = std::max({c.scale.x, c.scale.y, c.scale.z}) * 2;
    EXPECT_NEAR(m.mass, ref.volume, 1e-3 * ref.volume) << c.name;
    EXPECT_NEAR(m.centerOfMass.x, ref.com.x(), 1e-3 * size) << c.name;
    EXPECT_NEAR(m.centerOfMass.y, ref.com.y(), 1e-3 * size) << c.name;
    EXPECT_NEAR(m.centerOfMass.z, ref.com.z(), 1e-3 * size) << c.name;
    const double largest = ref.inertia.diagonal().maxCoeff();
    const Eigen::Matrix3d mine = toEigen(m.inertia);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) EXPECT_NEAR(mine(i, j), ref.inertia(i, j), 1e-3 * largest) << c.name << i << j;
    // The smallest moment of a thin or long hull is tiny next to the others; hold it to 1% of itself too.
    const double smallest = ref.inertia.selfadjointView<Eigen::Upper>().eigenvalues().minCoeff();
    EXPECT_NEAR(mine.selfadjointView<Eigen::Upper>().eigenvalues().minCoeff(), smallest, 1e-2 * smallest) << c.name;
}

INSTANTIATE_TEST_SUITE_P(ConvexHullSeeds, ConvexHullCloud,
                         ::testing::Values(Cloud{"ball1", 1, {1, 1, 1}, 200}, Cloud{"ball2", 2, {1, 1, 1}, 60},
                                           Cloud{"ball3", 3, {2, 0.5f, 1}, 500}, Cloud{"flat", 4, {1, 0.01f, 1}, 300},
                                           Cloud{"long", 5, {100, 1, 1}, 300},
                                           Cloud{"tiny", 6, {1e-3f, 1e-3f, 1e-3f}, 100}),
                         [](const ::testing::TestParamInfo<Cloud>& p) { return std::string(p.param.name); });

TEST(ConvexHull, PointsOnSphereApproachSphere) {
    // Fibonacci points on the unit sphere. The inscribed polyhedron's volume deficit shrinks like 1/n; with 4000
    // points it is under 0.2%, so volume and moment within 0.5% of 4/3 pi and 2/5 m r^2.
    auto sphere = [](int n) {
        std::vector<Vec3> p;
        const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
        for (int i = 0; i < n; ++i) {
            const double y = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - y * y);
            p.push_back({float(r * std::cos(golden * i)), float(y), float(r * std::sin(golden * i))});
        }
        return p;
    };
    const double volume = 4.0 / 3.0 * std::numbers::pi;
    const MassProperties coarse = hullMassProperties(buildConvexHull(sphere(200)));
    const std::vector<Vec3> finePoints = sphere(4000);
    const ConvexHull fine = buildConvexHull(finePoints);
    EXPECT_EQ(fine.vertices.size(), 4000u);  // every point is a corner
    const MassProperties m = hullMassProperties(fine);
    EXPECT_LT(m.mass, volume);  // inscribed
    EXPECT_NEAR(m.mass, volume, 5e-3 * volume);
    EXPECT_LT(volume - m.mass, volume - coarse.mass);
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(m.inertia(i, i), 0.4 * volume, 5e-3 * 0.4 * volume);
        EXPECT_NEAR(m.inertia(i, (i + 1) % 3), 0, 1e-3 * 0.4 * volume);
    }
    EXPECT_NEAR(length(m.centerOfMass), 0, 1e-4);
}

TEST(ConvexHull, DegenerateCloudsAreClearErrors) {
    auto message = [](const std::vector<Vec3>& p) {
        try {
            buildConvexHull(p);
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    ::testing::internal::CaptureStderr();
    EXPECT_EQ(message({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}), "ConvexHullDef: needs at least 4 points (got 3)");
    EXPECT_EQ(message({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 3, 0}, {0.5f, 0.5f, 0}}),
              "ConvexHullDef: the 6 points are coplanar: a hull needs volume");
    EXPECT_EQ(message({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {-1, -1, -1}, {0.5f, 0.5f, 0.5f}}),
              "ConvexHullDef: the 5 points are collinear: a hull needs volume");
    EXPECT_EQ(message({{1, 2, 3}, {1, 2, 3}, {1, 2, 3}, {1, 2, 3}}),
              "ConvexHullDef: the 4 points are all the same point: a hull needs volume");
    EXPECT_EQ(message({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {NAN, 0, 1}}),
              "ConvexHullDef: points[3] is not finite (nan, 0, 1)");
    // A tilted plane with float rounding noise is still a plane.
    std::vector<Vec3> tilted;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-5, 5);
    for (int i = 0; i < 50; ++i) {
        const float x = u(rng), z = u(rng);
        tilted.push_back({x, 0.3f * x - 0.7f * z + 2, z});
    }
    EXPECT_EQ(message(tilted), "ConvexHullDef: the 50 points are coplanar: a hull needs volume");
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");  // qhull never writes to the console
}

TEST(ConvexHull, ThinButSolidSlabIsAccepted) {
    // 1e-3 thick is far above the flatness threshold (1e-5 of the size): a real, if thin, solid.
    std::vector<Vec3> pts = boxCorners({1, 5e-4f, 1});
    const ConvexHull hull = buildConvexHull(pts);
    EXPECT_EQ(hull.faceCount(), 6u);
    EXPECT_NEAR(hullMassProperties(hull).mass, 4e-3, 4e-8);
}

}  // namespace
}  // namespace rubble::detail
