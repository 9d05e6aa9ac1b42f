#pragma once
// Triangle adjacency and edge convexity of static triangle meshes and heightfields, for the narrow phase's ghost
// contact suppression ("active edges", see narrowphase/triangle_pairs.h).
//
// Edge e of a triangle runs from its vertex e to vertex (e + 1) % 3 (for a mesh: indices[3t + e] to
// indices[3t + (e + 1) % 3]; for a heightfield: the vertices heightfieldTriangle() returns). An edge is
//  - Boundary: no neighbour (or shared by more than two triangles, or next to a zero-area triangle);
//  - Convex:   the neighbour falls away below this triangle's plane (a ridge);
//  - Flat:     the neighbour is within kFlatEdgeSine (sine of the dihedral angle) of this triangle's plane;
//  - Concave:  the neighbour rises above this triangle's plane (a valley).
// Boundary and convex edges are "active": a contact there may take an edge or vertex normal. Flat and concave
// edges are inactive: the neighbouring surface covers them, so a normal there must be the face normal.
//
// Meshes link triangles through shared vertex indices (weld duplicate vertices before building), so a mesh with
// split vertices reports those edges as boundary, i.e. active: conservative (bumps possible), never wrong-sided.
#include <array>
#include <cstdint>
#include <vector>

#include "rubble/math.h"
#include "shapes/shape.h"

namespace rubble::detail {

enum class EdgeKind : std::uint8_t { Boundary, Convex, Flat, Concave };

inline constexpr std::uint32_t kNoNeighbour = ~0u;
/// Dihedral angles whose sine is below this count as flat: 5 degrees, the threshold Jolt uses for its active edges.
/// A kink this small is the tessellation of a smooth surface (a terrain of 1 m cells bends by a few degrees an edge),
/// where the face normal is the surface's; taken as an edge, it throws a rolling ball up as it passes (speculative
/// contacts extrapolate the approach to a vertex or edge linearly, and stop what would not have touched).
inline constexpr float kFlatEdgeSine = 0.0872f;
/// All three edges active: the flags of a lone triangle (no ghost suppression at all).
inline constexpr std::uint8_t kAllEdgesActive = 7;

/// Per triangle of a mesh: neighbour across each edge (kNoNeighbour when none), edge kind, active-edge bits.
struct MeshAdjacency {
    std::vector<std::uint32_t> neighbours;  ///< 3 per triangle
    std::vector<EdgeKind> kinds;            ///< 3 per triangle
    std::vector<std::uint8_t> activeEdges;  ///< 1 per triangle: bit e set when edge e is boundary or convex

    std::uint32_t neighbour(std::uint32_t t, int e) const { return neighbours[3 * std::size_t(t) + e]; }
    EdgeKind kind(std::uint32_t t, int e) const { return kinds[3 * std::size_t(t) + e]; }
};

/// Kind of edge (a, b) of triangle (a, b, c) whose neighbour's third vertex is `far`. Degenerate input gives Flat
/// for a degenerate neighbour and Boundary for a degenerate triangle (callers skip those).
EdgeKind classifyEdge(Vec3 a, Vec3 b, Vec3 c, Vec3 far, float flatSine = kFlatEdgeSine);

/// Bit e set when kinds[e] is Boundary or Convex.
std::uint8_t activeEdgeMask(const std::array<EdgeKind, 3>& kinds);

/// Built once per mesh: O(n log n) in the triangle count.
MeshAdjacency buildMeshAdjacency(const TriangleMesh& mesh, float flatSine = kFlatEdgeSine);

/// Neighbours of heightfield triangle t (numbering of broadphase/static_bvh.h), kNoNeighbour at the border.
std::array<std::uint32_t, 3> heightfieldNeighbours(const Heightfield& field, std::uint32_t t);
/// Edge kinds of heightfield triangle t, from the grid numbering (no table needed).
std::array<EdgeKind, 3> heightfieldEdgeKinds(const Heightfield& field, std::uint32_t t, float flatSine = kFlatEdgeSine);
inline std::uint8_t heightfieldActiveEdges(const Heightfield& field, std::uint32_t t, float flatSine = kFlatEdgeSine) {
    return activeEdgeMask(heightfieldEdgeKinds(field, t, flatSine));
}

}  // namespace rubble::detail
