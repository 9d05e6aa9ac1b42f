#include "narrowphase/triangle_runs.h"

#include <algorithm>

#include "narrowphase/hull_adjacencies.h"
#include "narrowphase/mesh_manifolds.h"
#include "narrowphase/triangle_reach.h"
#include "shapes/mesh_adjacency.h"

namespace rubble::detail {

void MeshSide::prepare(const Posed& a, const Posed& meshBody) {
    const Shape& shape = *meshBody.shape;
    mesh = shape.kind == ShapeKind::TriangleMesh ? shape.mesh.get() : nullptr;
    heightfield = mesh ? nullptr : shape.heightfield.get();
    const Transform& pose = meshBody.pose;
    identity = pose.rotation == Quat{} && pose.position.x == 0 && pose.position.y == 0 && pose.position.z == 0;
    position = pose.position;
    rotation = rotationMatrix(pose.rotation);
    if (a.shape->kind == ShapeKind::Box) box = triangleBox(a.pose, a.shape->halfExtents);
    if (a.shape->kind == ShapeKind::Capsule) capsule = segmentOf(a);
}

void MeshSide::triangle(std::uint32_t t, TriangleVertices& vertices, std::uint8_t& activeEdges) const {
    if (mesh) {
        const std::uint32_t* index = &mesh->indices[3 * std::size_t(t)];
        for (int k = 0; k < 3; ++k) vertices[k] = mesh->vertices[index[k]];
        activeEdges = mesh->activeEdges.empty() ? kAllEdgesActive : mesh->activeEdges[t];
    } else {
        vertices = heightfieldTriangle(*heightfield, t);
        activeEdges = heightfieldActiveEdges(*heightfield, t);
    }
    if (!identity)
        for (Vec3& v : vertices) v = rotation * v + position;
}

namespace {

/// Each triangle kernel as two steps over a run: mark the triangles that may touch (all of them, in SIMD lanes), then
/// the exact kernel on one marked triangle k.
struct SphereTriangles {
    static void markInReach(const TriangleRun& run, const TriangleLanes& lanes, TriangleScratch& s) {
        sphereTrianglesInReach(run.a.pose.position, run.a.shape->radius, run.margin, lanes, run.count, s.inReach.get());
    }
    static void collide(const TriangleRun& run, const HullAdjacencies&, const TriangleScratch&, std::size_t,
                        const TriangleVertices& tri, std::uint8_t active, Manifold& out) {
        collideSphereTriangle(run.a.pose.position, run.a.shape->radius, tri, active, run.margin, out);
    }
};

struct CapsuleTriangles {
    static void markInReach(const TriangleRun& run, const TriangleLanes& lanes, TriangleScratch& s) {
        capsuleTrianglesInReach(run.mesh.capsule, run.margin, lanes, run.count, s.inReach.get());
    }
    static void collide(const TriangleRun& run, const HullAdjacencies&, const TriangleScratch&, std::size_t,
                        const TriangleVertices& tri, std::uint8_t active, Manifold& out) {
        collideCapsuleTriangle(run.mesh.capsule, tri, active, run.margin, out, /*inReach=*/true);
    }
};

/// The box kernel's whole SAT runs in lanes (most of the triangles a box reaches touch it); the exact kernel takes
/// its answer.
struct BoxTriangles {
    static void markInReach(const TriangleRun& run, const TriangleLanes& lanes, TriangleScratch& s) {
        const std::size_t padded = triangleLanesPadded(run.count);
        if (s.boxAxes.size() < padded) s.boxAxes.resize(padded);
        boxTriangleAxes(run.mesh.box, run.margin, lanes, run.count, s.boxAxes.data());
        for (std::size_t k = 0; k < run.count; ++k) s.inReach[k] = s.boxAxes[k].kind >= 0;
    }
    static void collide(const TriangleRun& run, const HullAdjacencies&, const TriangleScratch& s, std::size_t k,
                        const TriangleVertices& tri, std::uint8_t active, Manifold& out) {
        collideBoxTriangle(run.mesh.box, tri, active, run.margin, s.boxAxes[k], out);
    }
};

/// Hulls have no reach test: every triangle goes to the kernel.
struct HullTriangles {
    static void markInReach(const TriangleRun& run, const TriangleLanes&, TriangleScratch& s) {
        std::fill(s.inReach.get(), s.inReach.get() + run.count, true);
    }
    static void collide(const TriangleRun& run, const HullAdjacencies& hulls, const TriangleScratch&, std::size_t,
                        const TriangleVertices& tri, std::uint8_t active, Manifold& out) {
        const ConvexHull& hull = *run.a.shape->hull;
        collideHullTriangle(hull, hulls.of(hull), run.a.pose, tri, active, run.margin, out);
    }
};

/// The run's triangles into the scratch's lanes, padded with copies of the last (finite values the wide tests may
/// read).
TriangleLanes gatherTriangles(const TriangleRun& run, TriangleScratch& s) {
    const std::size_t count = run.count, padded = triangleLanesPadded(count);
    for (std::vector<float>& lane : s.triangles)
        if (lane.size() < padded) lane.resize(padded);
    if (s.activeEdges.size() < count) s.activeEdges.resize(count);
    if (s.inReachCapacity < padded) {
        s.inReach = std::make_unique<bool[]>(padded);
        s.inReachCapacity = padded;
    }
    for (std::size_t k = 0; k < count; ++k) {
        TriangleVertices tri;
        run.mesh.triangle(run.triangles[k], tri, s.activeEdges[k]);
        for (int v = 0; v < 3; ++v) {
            s.triangles[3 * v][k] = tri[v].x;
            s.triangles[3 * v + 1][k] = tri[v].y;
            s.triangles[3 * v + 2][k] = tri[v].z;
        }
    }
    for (std::vector<float>& lane : s.triangles)
        std::fill(lane.begin() + count, lane.begin() + padded, lane[count - 1]);
    return {{s.triangles[0].data(), s.triangles[3].data(), s.triangles[6].data()},
            {s.triangles[1].data(), s.triangles[4].data(), s.triangles[7].data()},
            {s.triangles[2].data(), s.triangles[5].data(), s.triangles[8].data()}};
}

template <class Kernel>
void collideRun(const TriangleRun& run, const HullAdjacencies& hulls, TriangleScratch& s, NarrowChunk& chunk) {
    const TriangleLanes lanes = gatherTriangles(run, s);
    Kernel::markInReach(run, lanes, s);
    const std::size_t firstOutput = chunk.meshManifolds.size();
    Manifold out;
    for (std::size_t k = 0; k < run.count; ++k) {
        if (!s.inReach[k]) continue;
        TriangleVertices tri;
        for (int v = 0; v < 3; ++v)
            tri[v] = {s.triangles[3 * v][k], s.triangles[3 * v + 1][k], s.triangles[3 * v + 2][k]};
        out.pointCount = 0;
        Kernel::collide(run, hulls, s, k, tri, s.activeEdges[k], out);
        if (out.pointCount == 0) continue;
        ContactPair pair = run.pair;
        pair.triangle = run.triangles[k];
        chunk.meshPairs.push_back(pair);
        chunk.meshManifolds.push_back(out);
    }
    mergeTriangleManifolds(chunk.meshPairs, chunk.meshManifolds, firstOutput);
}

}  // namespace

void collideSphereTriangleRun(const TriangleRun& run, const HullAdjacencies& hulls, TriangleScratch& scratch,
                              NarrowChunk& chunk) {
    collideRun<SphereTriangles>(run, hulls, scratch, chunk);
}
void collideCapsuleTriangleRun(const TriangleRun& run, const HullAdjacencies& hulls, TriangleScratch& scratch,
                               NarrowChunk& chunk) {
    collideRun<CapsuleTriangles>(run, hulls, scratch, chunk);
}
void collideBoxTriangleRun(const TriangleRun& run, const HullAdjacencies& hulls, TriangleScratch& scratch,
                           NarrowChunk& chunk) {
    collideRun<BoxTriangles>(run, hulls, scratch, chunk);
}
void collideHullTriangleRun(const TriangleRun& run, const HullAdjacencies& hulls, TriangleScratch& scratch,
                            NarrowChunk& chunk) {
    collideRun<HullTriangles>(run, hulls, scratch, chunk);
}

}  // namespace rubble::detail
