#pragma once
// A body against a run of mesh or heightfield triangles: the triangles the broad phase found under the body, taken
// together. Their vertices are fetched once, a reach test in SIMD lanes (triangle_reach.h) drops those that surely
// do not touch, the exact kernel (triangle_pairs.h) takes the rest one at a time, and the touching triangles'
// manifolds that share a normal are merged (mesh_manifolds.h).
#include <cstdint>
#include <memory>
#include <vector>

#include "narrowphase/pair_jobs.h"
#include "narrowphase/pair_sides.h"
#include "narrowphase/triangle_pairs.h"

namespace rubble::detail {

class HullAdjacencies;

/// A body against a static mesh or heightfield: what all its triangle jobs (which come in a row) share, worked out
/// once. Terrain usually sits at the origin unrotated; its vertices are then used as stored.
struct MeshSide {
    const TriangleMesh* mesh = nullptr;  ///< else a heightfield
    const Heightfield* heightfield = nullptr;
    bool identity = false;
    Mat3 rotation;
    Vec3 position;
    TriangleBox box;         ///< body A when it is a box
    CapsuleSegment capsule;  ///< body A when it is a capsule

    void prepare(const Posed& a, const Posed& meshBody);
    /// World vertices and active-edge mask of triangle t.
    void triangle(std::uint32_t t, TriangleVertices& vertices, std::uint8_t& activeEdges) const;
};

/// A run's working memory: world vertices (SoA, x y z of vertex 0, 1, 2), active edges and the reach tests' verdicts,
/// padded to whole SIMD batches; grown, never shrunk.
struct TriangleScratch {
    std::vector<float> triangles[9];
    std::vector<std::uint8_t> activeEdges;
    std::unique_ptr<bool[]> inReach;
    std::size_t inReachCapacity = 0;
    std::vector<BoxTriangleAxis> boxAxes;  ///< a box's SAT per triangle
};

/// Body A (side A of `pair`, posed as `a`) against `count` triangles of `mesh` (prepared for A), within `margin`.
struct TriangleRun {
    const Posed& a;
    const MeshSide& mesh;
    const std::uint32_t* triangles;
    std::size_t count;
    float margin;
    const ContactPair& pair;
};

/// A run through one triangle kernel; the touching triangles are appended to the chunk's mesh pairs and manifolds.
void collideSphereTriangleRun(const TriangleRun& run, const HullAdjacencies& hulls, TriangleScratch& scratch,
                              NarrowChunk& chunk);
void collideCapsuleTriangleRun(const TriangleRun& run, const HullAdjacencies& hulls, TriangleScratch& scratch,
                               NarrowChunk& chunk);
void collideBoxTriangleRun(const TriangleRun& run, const HullAdjacencies& hulls, TriangleScratch& scratch,
                           NarrowChunk& chunk);
void collideHullTriangleRun(const TriangleRun& run, const HullAdjacencies& hulls, TriangleScratch& scratch,
                            NarrowChunk& chunk);

/// Memory of the triangle runs after job j while job j runs (its kernels take microseconds): the vertices of job
/// j + 1's triangles, whose indices the previous call fetched, and the indices of job j + 2's. Terrain is read in no
/// particular order, so these are mostly cache misses otherwise. Only for the same mesh as job j (the usual case).
/// Always inlined: GCC judges a function that only prefetches free of effects and may delete calls to it.
[[gnu::always_inline]] inline void prefetchTriangles(const NarrowChunk& chunk, std::size_t j,
                                                     const std::vector<std::uint32_t>& meshTriangles,
                                                     const MeshSide& mesh) {
    if (mesh.mesh == nullptr) return;
    const std::uint32_t* indices = mesh.mesh->indices.data();
    const Vec3* vertices = mesh.mesh->vertices.data();
    const ContactPair& pair = chunk.jobs[j].pair;
    for (std::size_t ahead = 1; ahead <= 2 && j + ahead < chunk.jobs.size(); ++ahead) {
        const PairJob& next = chunk.jobs[j + ahead];
        if (next.triangles == 0 || next.reuse != kNoReuse || next.pair.b != pair.b || !next.pair.bStatic) return;
        for (std::uint32_t k = 0; k < next.triangles; ++k) {
            const std::uint32_t* triangle = indices + 3 * std::size_t(meshTriangles[next.firstTriangle + k]);
            if (ahead == 2) {
                __builtin_prefetch(triangle);
                continue;
            }
            for (int v = 0; v < 3; ++v) __builtin_prefetch(vertices + triangle[v]);
        }
    }
}

}  // namespace rubble::detail
