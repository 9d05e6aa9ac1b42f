// Viewer meshes and instances: the unit meshes are closed the right way round, and the instances made from a
// runtime frame put every part where the world says the body is (compared with World::transform and the shape's
// own geometry, composed independently here with Eigen-free scalar maths).
#include <gtest/gtest.h>

#include <cmath>

#include "rubble/runtime.h"
#include "rubble/world.h"
#include "shape_meshes.h"

using namespace rubble;
using namespace rubble::viewer;

namespace {

/// Every triangle winds counter-clockwise seen from outside a convex mesh centred on the origin, its vertex
/// normals agree, and the mesh is watertight enough that the signed volume is close to `volume`.
void expectOutwardMesh(const MeshData& mesh, float volume, float tolerance) {
    double signedVolume = 0;
    for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
        const MeshVertex& a = mesh.vertices[mesh.indices[t]];
        const MeshVertex& b = mesh.vertices[mesh.indices[t + 1]];
        const MeshVertex& c = mesh.vertices[mesh.indices[t + 2]];
        const Vec3 n = cross(b.position - a.position, c.position - a.position);
        ASSERT_GT(length(n), 0) << "degenerate triangle " << t / 3;
        EXPECT_GT(dot(n, a.position + b.position + c.position), 0) << "triangle " << t / 3 << " faces inwards";
        EXPECT_GT(dot(n, a.normal), 0) << "triangle " << t / 3 << " disagrees with its normals";
        signedVolume += dot(a.position, cross(b.position, c.position)) / 6.0;
    }
    EXPECT_NEAR(signedVolume, volume, tolerance);
}

}  // namespace

TEST(ShapeMeshes, UnitPrimitivesAreClosedAndFaceOutwards) {
    const float pi = 3.14159265f;
    // A 48 x 24 polyhedron inscribed in the unit sphere falls short of its volume by about 1 %.
    expectOutwardMesh(unitSphere(48, 24), 4.0f / 3.0f * pi, 0.02f * 4.0f / 3.0f * pi);
    expectOutwardMesh(unitBox(), 8.0f, 1e-5f);
    for (const MeshVertex& v : unitSphere(12, 8).vertices) EXPECT_NEAR(length(v.position), 1, 1e-6f);
    // The cylinder is open (capsules cap it with spheres): check orientation only, by its side normals.
    const MeshData cylinder = unitCylinder(16);
    for (const MeshVertex& v : cylinder.vertices) {
        EXPECT_NEAR(std::hypot(v.position.x, v.position.z), 1, 1e-6f);
        EXPECT_NEAR(std::fabs(v.position.y), 1, 1e-6f);
        EXPECT_NEAR(dot(v.normal, Vec3{v.position.x, 0, v.position.z}), 1, 1e-6f);
    }
}

TEST(ShapeMeshes, FlatShadingDropsDegenerateTrianglesAndUsesFaceNormals) {
    const std::vector<Vec3> vertices{{0, 0, 0}, {0, 0, 1}, {1, 0, 0}, {2, 0, 0}};
    const MeshData mesh = flatShaded(vertices, {0, 1, 2, 0, 2, 3});  // the second is a sliver of zero area
    ASSERT_EQ(mesh.indices.size(), 3u);
    for (const MeshVertex& v : mesh.vertices) EXPECT_EQ(v.normal, (Vec3{0, 1, 0}));
}

TEST(ShapeMeshes, InstancesSitWhereTheWorldPutsTheBodies) {
    World world;
    CompoundDef compound;
    compound.children.push_back({BoxDef{{0.5f, 0.25f, 0.5f}}, {{1, 0, 0}, {}}});
    compound.children.push_back({CapsuleDef{0.2f, 0.6f}, {{-1, 0, 0}, Quat::fromAxisAngle({0, 0, 1}, 1.0f)}});
    ConvexHullDef hull;
    hull.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    BodyDef def;
    def.shape = world.createShape(compound);
    def.position = {2, 3, 4};
    def.orientation = Quat::fromAxisAngle({0.3f, 1, 0.2f}, 0.7f);
    const BodyId compoundBody = world.createBody(def);
    def.shape = world.createShape(hull);
    def.position = {-5, 1, 0};
    world.createBody(def);

    ShapeLibrary library;
    for (BodyId id : world.bodies()) library.add(world.bodyShape(id).index, world.shapeGeometry(world.bodyShape(id)));
    Runtime runtime(std::move(world));
    runtime.singleStep();
    const RenderFrame& frame = runtime.latest(1);
    InstanceLists lists;
    const std::uint32_t unknown = collectInstances(
        frame, library, [](std::uint32_t, ShapeType) { return Rgba{}; }, lists);
    EXPECT_EQ(unknown, 0u);
    // Compound: one box, a capsule as a cylinder and two spheres; the hull: one mesh instance.
    ASSERT_EQ(lists.primitives[static_cast<int>(PrimitiveMesh::Box)].size(), 1u);
    ASSERT_EQ(lists.primitives[static_cast<int>(PrimitiveMesh::Cylinder)].size(), 1u);
    ASSERT_EQ(lists.primitives[static_cast<int>(PrimitiveMesh::Sphere)].size(), 2u);
    ASSERT_EQ(lists.meshes.size(), 1u);
    EXPECT_EQ(lists.meshes[0].size(), 1u);

    const Transform pose = runtime.world().transform(compoundBody);
    const Instance& box = lists.primitives[static_cast<int>(PrimitiveMesh::Box)][0];
    const Vec3 boxCentre = rotate(pose.rotation, Vec3{1, 0, 0}) + pose.position;
    EXPECT_NEAR(box.position[0], boxCentre.x, 1e-5f);
    EXPECT_NEAR(box.position[1], boxCentre.y, 1e-5f);
    EXPECT_NEAR(box.position[2], boxCentre.z, 1e-5f);
    EXPECT_EQ(box.scale[1], 0.25f);
    // The capsule's cap spheres sit at +-halfHeight along the child's turned y axis.
    const Quat capsuleTurn = pose.rotation * Quat::fromAxisAngle({0, 0, 1}, 1.0f);
    const Vec3 capsuleCentre = rotate(pose.rotation, Vec3{-1, 0, 0}) + pose.position;
    for (const Instance& cap : lists.primitives[static_cast<int>(PrimitiveMesh::Sphere)]) {
        const Vec3 offset = Vec3{cap.position[0], cap.position[1], cap.position[2]} - capsuleCentre;
        EXPECT_NEAR(length(offset), 0.6f, 1e-5f);
        EXPECT_NEAR(std::fabs(dot(offset, rotate(capsuleTurn, {0, 1, 0}))), 0.6f, 1e-5f);
        EXPECT_EQ(cap.scale[0], 0.2f);
    }
}
