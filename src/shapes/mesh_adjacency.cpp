// Mesh adjacency: edges keyed by their sorted vertex pair, sorted, and matched in pairs.
#include "shapes/mesh_adjacency.h"

#include <algorithm>

#include "broadphase/static_bvh.h"

namespace rubble::detail {
namespace {

/// Triangles whose squared doubled area is below this fraction of (longest edge^2)^2 are degenerate (a sine
/// of about 1e-5 between their edges): no usable normal.
constexpr float kDegenerateAreaSq = 1e-10f;

bool degenerate(Vec3 a, Vec3 b, Vec3 c) {
    const Vec3 ab = b - a, ac = c - a, bc = c - b;
    const Vec3 n = cross(ab, ac);
    const float longest = std::max({dot(ab, ab), dot(ac, ac), dot(bc, bc)});
    const float n2 = dot(n, n);
    return !(n2 > kDegenerateAreaSq * longest * longest) || !std::isfinite(n2);
}

}  // namespace

EdgeKind classifyEdge(Vec3 a, Vec3 b, Vec3 c, Vec3 far, float flatSine) {
    if (degenerate(a, b, c)) return EdgeKind::Boundary;
    const Vec3 n = cross(b - a, c - a);
    const Vec3 edge = b - a, off = far - a;
    // Height of `far` above this plane and its distance from the edge line, both scaled by |n| |edge|.
    const float height = dot(n, off) * length(edge);
    const float fromLine = length(cross(edge, off)) * length(n);
    if (!(fromLine > 0)) return EdgeKind::Flat;
    if (height < -flatSine * fromLine) return EdgeKind::Convex;
    if (height > flatSine * fromLine) return EdgeKind::Concave;
    return EdgeKind::Flat;
}

std::uint8_t activeEdgeMask(const std::array<EdgeKind, 3>& kinds) {
    std::uint8_t mask = 0;
    for (int e = 0; e < 3; ++e)
        if (kinds[e] == EdgeKind::Boundary || kinds[e] == EdgeKind::Convex) mask |= std::uint8_t(1u << e);
    return mask;
}

MeshAdjacency buildMeshAdjacency(const TriangleMesh& mesh, float flatSine) {
    const std::uint32_t n = mesh.triangleCount();
    MeshAdjacency adj;
    adj.neighbours.assign(3 * std::size_t(n), kNoNeighbour);
    adj.kinds.assign(3 * std::size_t(n), EdgeKind::Boundary);
    adj.activeEdges.assign(n, kAllEdgesActive);

    struct EdgeRef {
        std::uint64_t key;     // min vertex << 32 | max vertex
        std::uint32_t corner;  // 3 * triangle + edge
    };
    std::vector<EdgeRef> edges;
    edges.reserve(3 * std::size_t(n));
    auto vertex = [&](std::uint32_t t, int k) { return mesh.vertices[mesh.indices[3 * std::size_t(t) + k]]; };
    for (std::uint32_t t = 0; t < n; ++t) {
        if (degenerate(vertex(t, 0), vertex(t, 1), vertex(t, 2))) continue;
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t i = mesh.indices[3 * std::size_t(t) + e];
            const std::uint32_t j = mesh.indices[3 * std::size_t(t) + (e + 1) % 3];
            if (i == j) continue;
            edges.push_back({std::uint64_t(std::min(i, j)) << 32 | std::max(i, j), 3 * t + std::uint32_t(e)});
        }
    }
    // Sorting by (key, corner) makes the result independent of any hashing or thread order.
    std::sort(edges.begin(), edges.end(),
              [](const EdgeRef& x, const EdgeRef& y) { return x.key != y.key ? x.key < y.key : x.corner < y.corner; });
    for (std::size_t s = 0; s < edges.size();) {
        std::size_t e = s + 1;
        while (e < edges.size() && edges[e].key == edges[s].key) ++e;
        if (e - s == 2) {  // manifold edge; more than two triangles on one edge stay boundary (active)
            const std::uint32_t c0 = edges[s].corner, c1 = edges[s + 1].corner;
            adj.neighbours[c0] = c1 / 3;
            adj.neighbours[c1] = c0 / 3;
        }
        s = e;
    }
    for (std::uint32_t t = 0; t < n; ++t) {
        std::array<EdgeKind, 3> kinds{EdgeKind::Boundary, EdgeKind::Boundary, EdgeKind::Boundary};
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t u = adj.neighbours[3 * std::size_t(t) + e];
            if (u == kNoNeighbour) continue;
            const std::uint32_t i = mesh.indices[3 * std::size_t(t) + e];
            const std::uint32_t j = mesh.indices[3 * std::size_t(t) + (e + 1) % 3];
            std::uint32_t far = mesh.indices[3 * std::size_t(u)];
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t v = mesh.indices[3 * std::size_t(u) + k];
                if (v != i && v != j) far = v;
            }
            kinds[e] = classifyEdge(vertex(t, e), vertex(t, (e + 1) % 3), vertex(t, (e + 2) % 3), mesh.vertices[far],
                                    flatSine);
        }
        for (int e = 0; e < 3; ++e) adj.kinds[3 * std::size_t(t) + e] = kinds[e];
        adj.activeEdges[t] = activeEdgeMask(kinds);
    }
    return adj;
}

std::array<std::uint32_t, 3> heightfieldNeighbours(const Heightfield& field, std::uint32_t t) {
    std::array<std::uint32_t, 3> out{kNoNeighbour, kNoNeighbour, kNoNeighbour};
    if (t >= heightfieldTriangleCount(field)) return out;
    const std::uint32_t cellsX = field.columns - 1, cellsZ = field.rows - 1;
    const std::uint32_t cell = t / 2, r = cell / cellsX, c = cell % cellsX;
    auto tri = [&](std::uint32_t row, std::uint32_t col, std::uint32_t k) { return 2 * (row * cellsX + col) + k; };
    if ((t & 1) == 0) {  // (p00, p01, p11): left edge x = c, top edge z = r + 1, diagonal
        if (c > 0) out[0] = tri(r, c - 1, 1);
        if (r + 1 < cellsZ) out[1] = tri(r + 1, c, 1);
        out[2] = tri(r, c, 1);
    } else {  // (p00, p11, p10): diagonal, right edge x = c + 1, bottom edge z = r
        out[0] = tri(r, c, 0);
        if (c + 1 < cellsX) out[1] = tri(r, c + 1, 0);
        if (r > 0) out[2] = tri(r - 1, c, 0);
    }
    return out;
}

std::array<EdgeKind, 3> heightfieldEdgeKinds(const Heightfield& field, std::uint32_t t, float flatSine) {
    std::array<EdgeKind, 3> kinds{EdgeKind::Boundary, EdgeKind::Boundary, EdgeKind::Boundary};
    if (t >= heightfieldTriangleCount(field)) return kinds;
    const std::array<Vec3, 3> v = heightfieldTriangle(field, t);
    const std::array<std::uint32_t, 3> nb = heightfieldNeighbours(field, t);
    for (int e = 0; e < 3; ++e) {
        if (nb[e] == kNoNeighbour) continue;
        const std::array<Vec3, 3> w = heightfieldTriangle(field, nb[e]);
        const Vec3 a = v[e], b = v[(e + 1) % 3];
        Vec3 far = w[0];
        for (const Vec3& p : w)  // samples are computed identically for both triangles: exact comparison is safe
            if (!(p == a) && !(p == b)) far = p;
        kinds[e] = classifyEdge(a, b, v[(e + 2) % 3], far, flatSine);
    }
    return kinds;
}

}  // namespace rubble::detail
