// Hull-hull, box-hull, capsule-box and capsule-hull contact: SAT with Gauss-map pruning of edge pairs (Gregorius),
// reference-face clipping and reduction to four points; GJK on the cores for capsules. See hull_pairs.h.
#include "narrowphase/hull_pairs.h"

// GCC's SLP vectoriser may fuse alternating +/- lanes (the rotation matrix of a quaternion) into vfmsubadd even under
// -ffp-contract=off, and whether it does depends on what got inlined where: the kernel's results would then change
// with unrelated edits and differ between the build levels. Its wide loops are explicit SIMD.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-tree-slp-vectorize")
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "narrowphase/box_box.h"
#include "narrowphase/clip.h"
#include "narrowphase/closest_points_contact.h"
#include "narrowphase/gjk.h"
#include "shapes/shape.h"
#include "simd/simd.h"

namespace rubble::detail {
namespace {

/// Rotation matrix of a unit quaternion (rows), cheaper than quaternion rotation when applied many times.
struct Rot {
    Vec3 row[3];
    Vec3 operator*(Vec3 v) const { return {dot(row[0], v), dot(row[1], v), dot(row[2], v)}; }
};

Rot toRot(Quat q) {
    const float xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    const float xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    const float wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    return {{{1 - 2 * (yy + zz), 2 * (xy - wz), 2 * (xz + wy)},
             {2 * (xy + wz), 1 - 2 * (xx + zz), 2 * (yz - wx)},
             {2 * (xz - wy), 2 * (yz + wx), 1 - 2 * (xx + yy)}}};
}

inline float minf(float x, float y) { return x < y ? x : y; }
inline float maxf(float x, float y) { return x > y ? x : y; }
inline float clamp01(float x) { return x < 0 ? 0.0f : (x > 1 ? 1.0f : x); }

/// What the kernels read of a hull: plain pointers, so that the box can be served from stack data.
struct HullView {
    const Vec3* vertices;
    int vertexCount;
    const std::uint32_t* faceVertices;
    const std::uint32_t* faceStart;
    const Vec3* normals;
    const float* offsets;
    int faceCount;
    const HullEdge* edges;
    int edgeCount;
    const std::vector<float>* arcs;        ///< HullAdjacency::arcs
    const std::vector<float>* normalRows;  ///< HullAdjacency::normalRows
    const std::vector<float>* arcCones;    ///< HullAdjacency::arcCones
    const std::uint32_t* vertexFaceStart;  ///< HullAdjacency::vertexFaceStart
    const std::uint32_t* vertexFaces;      ///< HullAdjacency::vertexFaces
    Vec3 interior;
    float size;
    float inradius;
};

HullView viewOf(const ConvexHull& h, const HullAdjacency& adj) {
    return {h.vertices.data(),
            static_cast<int>(h.vertices.size()),
            h.faceVertices.data(),
            h.faceStart.data(),
            h.faceNormals.data(),
            h.faceOffsets.data(),
            static_cast<int>(h.faceNormals.size()),
            adj.edges.data(),
            static_cast<int>(adj.edges.size()),
            adj.arcs,
            adj.normalRows,
            adj.arcCones,
            adj.vertexFaceStart.data(),
            adj.vertexFaces.data(),
            adj.interior,
            adj.size,
            adj.inradius};
}

// ---- The unit cube, numbered like box_box.h: vertex i has sign bits x = bit 0, y = bit 1, z = bit 2 (set = +);
// face 2 * axis + (1 if -axis), counter-clockwise from outside.
struct UnitCube {
    ConvexHull hull;
    HullAdjacency adjacency;
    UnitCube() {
        for (int i = 0; i < 8; ++i)
            hull.vertices.push_back({i & 1 ? 1.0f : -1.0f, i & 2 ? 1.0f : -1.0f, i & 4 ? 1.0f : -1.0f});
        static constexpr std::uint32_t kFaces[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3},
                                                       {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
        for (int f = 0; f < 6; ++f) {
            hull.faceStart.push_back(static_cast<std::uint32_t>(hull.faceVertices.size()));
            for (std::uint32_t v : kFaces[f]) hull.faceVertices.push_back(v);
            Vec3 n{};
            n[f / 2] = f % 2 ? -1.0f : 1.0f;
            hull.faceNormals.push_back(n);
            hull.faceOffsets.push_back(1);
        }
        hull.faceStart.push_back(static_cast<std::uint32_t>(hull.faceVertices.size()));
        // The 12 edges: along axis k from the vertex with bit k clear.
        for (int k = 0; k < 3; ++k)
            for (std::uint32_t i = 0; i < 8; ++i)
                if (!(i & (1u << k))) hull.edges.push_back(i), hull.edges.push_back(i | (1u << k));
        adjacency = buildHullAdjacency(hull);
    }
};

const UnitCube& unitCube() {
    static const UnitCube cube;
    return cube;
}

/// A box of half extents `half` as a hull view over caller-provided storage for its vertices and offsets.
HullView boxView(Vec3 half, Vec3 (&vertices)[8], float (&offsets)[6]) {
    const UnitCube& c = unitCube();
    for (int i = 0; i < 8; ++i) {
        const Vec3 u = c.hull.vertices[i];
        vertices[i] = {u.x * half.x, u.y * half.y, u.z * half.z};
    }
    for (int f = 0; f < 6; ++f) offsets[f] = half[f / 2];
    HullView v = viewOf(c.hull, c.adjacency);
    v.vertices = vertices;
    v.offsets = offsets;
    v.size = length(half);
    v.inradius = minf(half.x, minf(half.y, half.z));
    return v;
}

/// n rounded up to whole rows of HullAdjacency's SoA data (kHullArcPadding).
std::size_t paddedRow(std::size_t n) { return (n + kHullArcPadding - 1) / kHullArcPadding * kHullArcPadding; }

/// Thread-local scratch (grown, never shrunk), so the kernels do not allocate in steady state.
struct Scratch {
    std::vector<Vec3> vertices;
    std::vector<std::uint32_t> faces, everyFace;  ///< faces in the cone of possible axes; 0, 1, 2, ...
    std::vector<std::uint32_t> edgesA, edgesB;    ///< the edges whose arcs reach the cone of possible axes
    /// Per edge of edgesA, packed in SoA rows: HullAdjacency::arcs (rows 0-8), then the edge's start, direction and
    /// start relative to the interior (9-17) and its squared length (18), as edgeOfA computes them.
    std::vector<float> edgeRowsA[19];
    HullAdjacency adjA, adjB;
};
Scratch& scratch() {
    thread_local Scratch s;
    return s;
}

/// Closest points of segments p1 + s d1 and p2 + t d2 (s, t in [0, 1]), Ericson 5.1.9.
void closestSegmentPoints(Vec3 p1, Vec3 d1, Vec3 p2, Vec3 d2, float& s, float& t) {
    const Vec3 r = p1 - p2;
    const float a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
    if (a <= 0 && e <= 0) {
        s = t = 0;
        return;
    }
    if (a <= 0) {
        s = 0, t = clamp01(f / e);
        return;
    }
    const float c = dot(d1, r);
    if (e <= 0) {
        t = 0, s = clamp01(-c / a);
        return;
    }
    const float b = dot(d1, d2), denom = a * e - b * b;
    s = denom > 0 ? clamp01((b * f - c * e) / denom) : 0.0f;
    t = (b * s + f) / e;
    if (t < 0) {
        t = 0, s = clamp01(-c / a);
    } else if (t > 1) {
        t = 1, s = clamp01((b - c) / a);
    }
}

/// What the SAT's edge-pair test needs of one edge of A: its faces' normals, their cross product (the edge's great
/// circle on the Gauss map), its start, direction and squared length, and its start relative to A's interior.
struct EdgeOfA {
    Vec3 a, b, bxa, pa, da, paRel;
    float da2;
};

EdgeOfA edgeOfA(const HullView& A, int i) {
    const HullEdge& e = A.edges[i];
    EdgeOfA r;
    r.a = A.normals[e.face0], r.b = A.normals[e.face1];
    r.bxa = cross(r.b, r.a);
    r.pa = A.vertices[e.v0], r.da = A.vertices[e.v1] - r.pa;
    r.da2 = dot(r.da, r.da);
    r.paRel = r.pa - A.interior;
    return r;
}

/// The SAT's test of A's edge `ea` against B's edge (start `pb`, direction `db`, `crossB` the great circle of its
/// negated face normals, `cba` and `dba` the sides of those normals against ea's circle): whether the pair is a face
/// of the Minkowski difference A - B whose axis could separate by more than `limit` (Gregorius' IsMinkowskiFace,
/// near-parallel edges skipped); if so its unnormalised axis (pointing away from A's interior) and the numerator of
/// the separation along it. The search and the hint test both go through here, so they agree bit for bit.
[[gnu::always_inline]] inline bool edgePairCandidate(const EdgeOfA& ea, Vec3 pb, Vec3 db, Vec3 crossB, float cba,
                                                     float dba, float limit, Vec3& axis, float& len2, float& num) {
    constexpr float kParallel2 = kBoxEdgeParallelEpsilon * kBoxEdgeParallelEpsilon;
    if (cba * dba >= 0) return false;
    const float adc = dot(ea.a, crossB), bdc = dot(ea.b, crossB);
    if (adc * bdc >= 0 || cba * bdc <= 0) return false;
    axis = cross(ea.da, db);
    len2 = dot(axis, axis);
    if (len2 < kParallel2 * ea.da2 * dot(db, db)) return false;
    if (dot(axis, ea.paRel) < 0) axis = -axis;
    num = dot(axis, pb - ea.pa);
    // sep = num / |axis| > limit, tested without the square root first.
    return !(limit <= 0 ? num <= limit * std::sqrt(len2) : (num <= 0 || num * num <= limit * limit * len2));
}

/// For faces [f0, f0 + lanes) of one hull (normals in SoA rows, padded), the lowest of the other hull's vertices
/// along each: min over i of dot(n, v_i), with dot's order of operations and minf's choice, lane by lane.
void lowestAlongFaces(const float* const rows[3], int f0, const Vec3* vertices, int count, float* lowest) {
    using simd::FloatW;
    const FloatW nx = simd::load<FloatW>(rows[0] + f0), ny = simd::load<FloatW>(rows[1] + f0),
                 nz = simd::load<FloatW>(rows[2] + f0);
    FloatW lo(INFINITY);
    for (int i = 0; i < count; ++i) {
        const Vec3 v = vertices[i];
        lo = simd::min(lo, nx * FloatW(v.x) + ny * FloatW(v.y) + nz * FloatW(v.z));
    }
    simd::store(lowest, lo);
}

/// Writes to `out`, in ascending order, the edges whose arcs come within the cone {n : n . u > coneCos} (u a unit
/// direction in the hull's frame) and returns their count: the arc lies within half its angle h of its midpoint m,
/// so it reaches the cone unless angle(u, m) exceeds h plus the cone's angle a, that is unless cos angle(u, m) <
/// cos(h + a) = cos h cos a - sin h sin a (for h + a < pi, else it always reaches it). The cone's sine is taken
/// once, not an angle per edge. `out` holds edgeCount + kLanes.
int edgesNearCone(const std::vector<float>* cones, int edgeCount, Vec3 u, float coneCos, std::uint32_t* out) {
    using simd::FloatW;
    if (!(coneCos > -1.0f)) {  // every axis
        for (int e = 0; e < edgeCount; ++e) out[e] = static_cast<std::uint32_t>(e);
        return edgeCount;
    }
    const float cosCone = minf(coneCos, 1.0f), sinCone = std::sqrt(maxf(1.0f - cosCone * cosCone, 0.0f));
    const FloatW ux(u.x), uy(u.y), uz(u.z), cosA(cosCone), sinA(sinCone), minusCosA(-cosCone);
    alignas(64) bool near[simd::kLanes];
    int count = 0;
    for (int e0 = 0; e0 < edgeCount; e0 += static_cast<int>(simd::kLanes)) {
        const auto row = [&](int k) { return simd::load<FloatW>(cones[k].data() + e0); };
        const FloatW c = row(0) * ux + row(1) * uy + row(2) * uz, cosH = row(3), sinH = row(4);
        simd::storeMask(near, (cosH <= minusCosA) | (c >= cosH * cosA - sinH * sinA));
        const int lanes = std::min(static_cast<int>(simd::kLanes), edgeCount - e0);
        for (int k = 0; k < lanes; ++k) {  // branch-free: the unpredictable test picks only the next slot
            out[count] = static_cast<std::uint32_t>(e0 + k);
            count += near[k];
        }
    }
    return count;
}

/// Writes to `out`, in ascending order, the faces whose normals lie in the cone {n : n . u > coneCos}, and returns
/// their count. `out` holds faceCount + kLanes.
int facesInCone(const std::vector<float>* normalRows, int faceCount, Vec3 u, float coneCos, std::uint32_t* out) {
    using simd::FloatW;
    const FloatW ux(u.x), uy(u.y), uz(u.z), threshold(coneCos);
    alignas(64) bool inside[simd::kLanes];
    int count = 0;
    for (int f0 = 0; f0 < faceCount; f0 += static_cast<int>(simd::kLanes)) {
        const auto row = [&](int k) { return simd::load<FloatW>(normalRows[k].data() + f0); };
        simd::storeMask(inside, row(0) * ux + row(1) * uy + row(2) * uz > threshold);
        const int lanes = std::min(static_cast<int>(simd::kLanes), faceCount - f0);
        for (int k = 0; k < lanes; ++k) {
            out[count] = static_cast<std::uint32_t>(f0 + k);
            count += inside[k];
        }
    }
    return count;
}

/// The vertex of H nearest p (in H's frame).
std::uint32_t nearestVertex(const HullView& H, Vec3 p) {
    int best = 0;
    float bestD = INFINITY;
    for (int i = 0; i < H.vertexCount; ++i) {
        const Vec3 d = H.vertices[i] - p;
        const float d2 = dot(d, d);
        if (d2 < bestD) bestD = d2, best = i;
    }
    return static_cast<std::uint32_t>(best);
}

/// Hull-hull kernel. B is brought into A's frame (relative to A's centre); all tests run there.
//
// Every hull holds a ball of its inradius around its interior point, so along a unit axis n the hulls are apart by
// at most n . d - inradiusA - inradiusB, d the line between the interiors: only axes in a cone around d can be
// apart by more than a given floor. The face scans and the edge pairs test only the faces and edges that can reach
// such a cone; a slack keeps every axis that rounding could lift over the floor, so the answer is that of the plain
// search bit for bit (HullPairs.AxisConesNeverChangeTheAnswer).
bool collidePolytopes(const HullView& A, const Transform& poseA, const HullView& B, const Transform& poseB,
                      float margin, Manifold& out, SatHint* hint, float featureDrift) {
    out.pointCount = 0;
    Scratch& sc = scratch();
    const Quat qInv = conjugate(poseA.rotation);
    const Rot r = toRot(qInv * poseB.rotation);
    const Vec3 t = rotate(qInv, poseB.position - poseA.position);
    if (sc.vertices.size() < static_cast<std::size_t>(B.vertexCount)) sc.vertices.resize(B.vertexCount);
    Vec3* vb = sc.vertices.data();
    for (int i = 0; i < B.vertexCount; ++i) vb[i] = r * B.vertices[i] + t;
    const Vec3* va = A.vertices;
    // B's faces in A's frame, made when needed: most pairs need only a few.
    const auto normalB = [&](int f) { return r * B.normals[f]; };
    const auto planeB = [&](int f, Vec3& normal, float& offset) {
        normal = normalB(f);
        offset = B.offsets[f] + dot(normal, t);
    };

    const Vec3 between = (r * B.interior + t) - A.interior;
    const float distance = length(between);
    const bool bounded = distance > 0 && A.inradius > 0 && B.inradius > 0;
    const float slack = 1e-3f * (A.size + B.size);
    // The cosine of the cone (around towardB, for A's normals; around -towardB for B's) of the axes along which the
    // hulls can be apart by more than `floor`; below -1 (every axis) without a bound.
    const auto coneCos = [&](float floor) {
        return bounded ? (floor + A.inradius + B.inradius - slack) / distance : -2.0f;
    };
    const Vec3 towardB = distance > 0 ? between / distance : Vec3{1, 0, 0};
    // r^T (-towardB): the cone's axis for B's normals, in B's own frame.
    const Vec3 towardAInB = -(towardB.x * r.row[0] + towardB.y * r.row[1] + towardB.z * r.row[2]);

    // The face axes of one hull against the other's vertices, kLanes faces at a time in SIMD lanes: the separation
    // along face f is the lowest vertex above its plane.
    alignas(64) float lanes[3][simd::kLanes];
    alignas(64) float lowestOnFace[simd::kLanes];
    const float* laneRows[3] = {lanes[0], lanes[1], lanes[2]};
    const auto separations = [&](bool ofB, const std::uint32_t* faces, int count, float* sep) {
        float offsets[simd::kLanes];
        for (int k = 0; k < static_cast<int>(simd::kLanes); ++k) {
            Vec3 n{};
            offsets[k] = 0;
            if (k < count) {
                const int f = static_cast<int>(faces[k]);
                if (ofB)
                    planeB(f, n, offsets[k]);
                else
                    n = A.normals[f], offsets[k] = A.offsets[f];
            }
            lanes[0][k] = n.x, lanes[1][k] = n.y, lanes[2][k] = n.z;
        }
        lowestAlongFaces(laneRows, 0, ofB ? va : vb, ofB ? A.vertexCount : B.vertexCount, lowestOnFace);
        for (int k = 0; k < count; ++k) sep[k] = lowestOnFace[k] - offsets[k];
    };
    // An edge pair's contact: one point, at the closest points of the two edges.
    const auto edgeContact = [&](int edgeA, int edgeB, Vec3 axisE) {
        const Rot ra = toRot(poseA.rotation);
        const HullEdge& ea = A.edges[edgeA];
        const HullEdge& eb = B.edges[edgeB];
        const Vec3 pa = va[ea.v0], da = va[ea.v1] - pa, pb = vb[eb.v0], db = vb[eb.v1] - pb;
        float s, w;
        closestSegmentPoints(pa, da, pb, db, s, w);
        const Vec3 ca = pa + da * s, cb = pb + db * w;
        Vec3 normal = axisE;
        float depth = dot(ca - cb, axisE);
        // Apart, the edges' closest points are the contact: their distance can exceed the axis's separation when
        // one of them is an edge's end (then the axis is not the direction between them), and the point on A must
        // be `depth` along the normal from the point on B.
        if (const float apart = length(cb - ca); depth < 0 && apart > 0) normal = (cb - ca) / apart, depth = -apart;
        if (depth < -margin) return false;
        out.normal = ra * normal;
        out.points[0].position = poseA.position + ra * cb;
        out.points[0].depth = depth;
        out.points[0].feature = (2u << 30) | ((static_cast<std::uint32_t>(edgeA) & 0x7FFFu) << 15) |
                                (static_cast<std::uint32_t>(edgeB) & 0x7FFFu);
        out.pointCount = 1;
        return true;
    };
    // Face contact. Reference face on A (or B). Incident face: among the other hull's faces through its deepest
    // vertex along the reference normal, the most anti-parallel one. (The most anti-parallel face overall can lie
    // beside the reference face for general hulls, and then clips to nothing.)
    const auto faceContact = [&](bool useB, int fr) {
        const Rot ra = toRot(poseA.rotation);
        const HullView& R = useB ? B : A;
        const HullView& I = useB ? A : B;
        const Vec3* rv = useB ? vb : va;
        const Vec3* iv = useB ? va : vb;
        Vec3 refN;
        float refOff;
        if (useB)
            planeB(fr, refN, refOff);
        else
            refN = A.normals[fr], refOff = A.offsets[fr];
        std::uint32_t deepest = 0;
        float lowest = INFINITY;
        for (int i = 0; i < I.vertexCount; ++i) {
            const float h = dot(refN, iv[i]);
            if (h < lowest) lowest = h, deepest = static_cast<std::uint32_t>(i);
        }
        int fi = 0;
        float mostAnti = INFINITY;
        for (std::uint32_t k = I.vertexFaceStart[deepest]; k < I.vertexFaceStart[deepest + 1]; ++k) {
            const int f = static_cast<int>(I.vertexFaces[k]);  // ascending: ties keep the lowest face
            const float c = dot(useB ? A.normals[f] : normalB(f), refN);
            if (c < mostAnti) mostAnti = c, fi = f;
        }
        ClipVertex bufA[kClipCapacity], bufB[kClipCapacity];
        ClipVertex* cur = bufA;
        ClipVertex* nxt = bufB;
        const std::uint32_t i0 = I.faceStart[fi], i1 = I.faceStart[fi + 1];
        int n = 0;
        for (std::uint32_t k = i0; k < i1 && n < kClipCapacity; ++k, ++n)
            cur[n] = {iv[I.faceVertices[k]], static_cast<std::uint16_t>(n), static_cast<std::uint16_t>(n)};
        const std::uint32_t r0 = R.faceStart[fr], r1 = R.faceStart[fr + 1];
        for (std::uint32_t k = r0; k < r1 && n > 0; ++k) {
            const Vec3 p0 = rv[R.faceVertices[k]], p1 = rv[R.faceVertices[k + 1 == r1 ? r0 : k + 1]];
            const Vec3 side = cross(p1 - p0, refN);
            n = clipPolygon(cur, n, nxt, side, dot(side, p0), static_cast<int>(k - r0));
            ClipVertex* tmp = cur;
            cur = nxt;
            nxt = tmp;
        }
        Vec3 pts[kClipCapacity];
        float depth[kClipCapacity];
        std::uint16_t ids[kClipCapacity];
        int m = 0;
        for (int k = 0; k < n; ++k) {
            const float d = refOff - dot(refN, cur[k].p);
            if (d >= -margin) pts[m] = cur[k].p, depth[m] = d, ids[m] = cur[k].id, ++m;
        }
        if (m == 0) {
            // Nothing of the incident face lies over the reference face (deep, lopsided overlaps where hysteresis kept
            // a face axis): report the deepest incident vertex alone, so the pair is never dropped while the SAT says
            // it overlaps. Apart, the vertex is not over the face and its height misstates the distance: the
            // closest points decide (keepDistanceExact).
            const float d = refOff - lowest;
            if (d < -minf(margin, kClosestPointsMinimumGap * maxf(A.size, B.size))) return false;
            pts[0] = iv[deepest], depth[0] = d, m = 1;
            ids[0] = 0x7FFF;
            for (std::uint32_t k = I.faceStart[fi]; k < I.faceStart[fi + 1]; ++k)
                if (I.faceVertices[k] == deepest) ids[0] = static_cast<std::uint16_t>(k - I.faceStart[fi]);
        }
        Vec3 u, v;
        planeBasis(refN, u, v);
        int chosen[4];
        const int count = reduceContactPoints(pts, depth, m, u, v, chosen);
        out.normal = ra * (useB ? -refN : refN);
        const std::uint32_t base = ((useB ? 1u : 0u) << 30) | ((static_cast<std::uint32_t>(fr) & 0xFFu) << 22) |
                                   ((static_cast<std::uint32_t>(fi) & 0x3Fu) << 16);
        for (int k = 0; k < count; ++k) {
            const int c = chosen[k];
            // With the reference face on B the clipped points lie on A's face: move them onto B's face.
            const Vec3 p = useB ? pts[c] + refN * depth[c] : pts[c];
            out.points[k].position = poseA.position + ra * p;
            out.points[k].depth = depth[c];
            out.points[k].feature = base | ids[c];
        }
        out.pointCount = count;
        return count > 0;
    };
    // Hulls apart whose clipped or edge contact misstates their distance (closest_points_contact.h) get the contact
    // at their closest points instead; `bestSeparation` is the largest separation of the axes tested.
    const auto keepDistanceExact = [&](float bestSeparation) {
        if (!misstatesDistance(out, bestSeparation, maxf(A.size, B.size))) return out.pointCount > 0;
        GjkShape ga, gb;
        ga.core = gb.core = GjkShape::Core::Points;
        ga.points = A.vertices, ga.pointCount = static_cast<std::uint32_t>(A.vertexCount), ga.pose = poseA;
        gb.points = B.vertices, gb.pointCount = static_cast<std::uint32_t>(B.vertexCount), gb.pose = poseB;
        Vec3 localA, localB;
        if (!contactAtClosestPoints(ga, gb, margin, out, localA, localB)) return out.pointCount > 0;
        out.points[0].feature = (kClosestPointsFeatureKind << 30) | ((nearestVertex(A, localA) & 0x7FFFu) << 15) |
                                (nearestVertex(B, localB) & 0x7FFFu);
        return true;
    };
    const auto separatedBy = [&](SatHint::Kind kind, int a, int b) {
        if (hint) *hint = {kind, true, 0, static_cast<std::uint16_t>(a), static_cast<std::uint16_t>(b), 0};
        return false;
    };
    // An edge pair's axis (unit, away from A) and separation, when the pair is a face of the Minkowski difference
    // whose separation exceeds `limit`.
    const auto edgeAxis = [&](int ia, int jb, float limit, Vec3& axis, float& sep) {
        const EdgeOfA ea = edgeOfA(A, ia);
        const HullEdge& eb = B.edges[jb];
        const Vec3 n0 = normalB(static_cast<int>(eb.face0)), n1 = normalB(static_cast<int>(eb.face1));
        float len2, num;
        if (!edgePairCandidate(ea, vb[eb.v0], vb[eb.v1] - vb[eb.v0], cross(n1, n0), -dot(n0, ea.bxa), -dot(n1, ea.bxa),
                               limit, axis, len2, num))
            return false;
        sep = num / std::sqrt(len2);
        axis = axis / std::sqrt(len2);
        return true;
    };

    // The separation along the hint's axis (for an edge pair, when it is still a face of the Minkowski difference
    // apart by more than `limit`, and its unit axis); false when the hint names no axis of these hulls.
    const auto hintSeparation = [&](const SatHint& h, float limit, float& sep, Vec3& axis) {
        const std::uint32_t face = h.a;
        if (h.kind == SatHint::kFaceA && h.a < A.faceCount) return separations(false, &face, 1, &sep), true;
        if (h.kind == SatHint::kFaceB && h.a < B.faceCount) return separations(true, &face, 1, &sep), true;
        return h.kind == SatHint::kEdges && h.a < A.edgeCount && h.b < B.edgeCount &&
               edgeAxis(h.a, h.b, limit, axis, sep);
    };
    float hintSep = -INFINITY;
    Vec3 hintAxis{};
    // Last call's separating axis first: one axis instead of the search, when the pair is still apart along it.
    if (hint && hint->separated && hintSeparation(*hint, margin, hintSep, hintAxis) && hintSep > margin) return false;
    // Last call's contact feature (reference face or edge pair), when the pair touched: its contact is built again
    // without the search while the feature's separation stays within featureDrift of what the search found (Box3D's
    // SAT cache keeps a feature the same way). A feature that now separates the pair is an exact answer: no contact.
    if (hint && !hint->separated && featureDrift > 0 && hintSeparation(*hint, -INFINITY, hintSep, hintAxis)) {
        const SatHint last = *hint;
        if (hintSep > margin) return separatedBy(last.kind, last.a, last.b);
        if (std::fabs(hintSep - last.separation) <= featureDrift &&
            (last.kind == SatHint::kEdges ? edgeContact(last.a, last.b, hintAxis)
                                          : faceContact(last.kind == SatHint::kFaceB, last.a))) {
            hint->reuses = static_cast<std::uint8_t>(last.reuses < 255 ? last.reuses + 1 : 255);
            return keepDistanceExact(hintSep);
        }
    }
    if (hint) *hint = {};

    // Face axes of A, then of B, each read in face order, so that the first that separates and the best are those
    // of a plain scan. First only the faces that can be apart by more than `floor` (a little overlap): none of the
    // others separates, or beats a best above the floor; when the best is below it (deep overlap), every face.
    const auto scanFaces = [&](bool ofB, const std::uint32_t* faces, int count, SatHint::Kind kind, float& best,
                               int& bestFace) {
        best = -INFINITY, bestFace = 0;
        float sep[simd::kLanes];
        for (int c0 = 0; c0 < count; c0 += static_cast<int>(simd::kLanes)) {
            const int n = std::min(static_cast<int>(simd::kLanes), count - c0);
            separations(ofB, faces + c0, n, sep);
            for (int k = 0; k < n; ++k) {
                const int f = static_cast<int>(faces[c0 + k]);
                if (sep[k] > margin) return separatedBy(kind, f, 0);  // the common exit, taken as soon as found
                if (sep[k] > best) best = sep[k], bestFace = f;
            }
        }
        return true;
    };
    const float floor = minf(margin, -kFaceConeDepth * maxf(A.size, B.size));
    const float faceCos = coneCos(floor);
    const int mostFaces = std::max(A.faceCount, B.faceCount);
    if (sc.faces.size() < static_cast<std::size_t>(mostFaces) + simd::kLanes) {
        sc.faces.resize(static_cast<std::size_t>(mostFaces) + simd::kLanes);
        sc.everyFace.resize(static_cast<std::size_t>(mostFaces));
        for (std::size_t f = 0; f < sc.everyFace.size(); ++f) sc.everyFace[f] = static_cast<std::uint32_t>(f);
    }
    const auto bestFace = [&](bool ofB, SatHint::Kind kind, float& best, int& face) {
        const HullView& H = ofB ? B : A;
        const int near = facesInCone(H.normalRows, H.faceCount, ofB ? towardAInB : towardB, faceCos, sc.faces.data());
        if (!scanFaces(ofB, sc.faces.data(), near, kind, best, face)) return false;
        return best >= floor || scanFaces(ofB, sc.everyFace.data(), H.faceCount, kind, best, face);
    };
    float sepA, sepB;
    int faceA, faceB;
    if (!bestFace(false, SatHint::kFaceA, sepA, faceA) || !bestFace(true, SatHint::kFaceB, sepB, faceB)) return false;

    const float absTol = kBoxAxisAbsoluteTolerance * maxf(A.size, B.size);
    auto clearlyBetter = [&](float candidate, float current) {
        return candidate > current + kBoxAxisRelativeTolerance * std::fabs(current) + absTol;
    };
    const bool useB = clearlyBetter(sepB, sepA);
    const float sepFace = useB ? sepB : sepA;

    // Edge pairs whose Gauss-map arcs cross (Gregorius' IsMinkowskiFace, with B's normals negated for the
    // Minkowski difference A - B). Only a separation above `limit` matters: it separates or beats the face axis; so
    // only the edges whose arcs reach the cone of that limit are paired.
    const float limit = minf(margin, sepFace + kBoxAxisRelativeTolerance * std::fabs(sepFace) + absTol);
    const float edgeCos = coneCos(limit);
    const int mostEdges = std::max(A.edgeCount, B.edgeCount);
    if (sc.edgesA.size() < static_cast<std::size_t>(mostEdges) + simd::kLanes) {
        sc.edgesA.resize(static_cast<std::size_t>(mostEdges) + simd::kLanes);
        sc.edgesB.resize(static_cast<std::size_t>(mostEdges) + simd::kLanes);
    }
    const int countA = edgesNearCone(A.arcCones, A.edgeCount, towardB, edgeCos, sc.edgesA.data());
    const int countB = edgesNearCone(B.arcCones, B.edgeCount, towardAInB, edgeCos, sc.edgesB.data());
    const int padded = static_cast<int>(paddedRow(countA));
    for (std::vector<float>& row : sc.edgeRowsA)
        if (row.size() < static_cast<std::size_t>(padded)) row.resize(static_cast<std::size_t>(padded));
    for (int i = 0; i < countA; ++i) {
        const int e = static_cast<int>(sc.edgesA[i]);
        const EdgeOfA ea = edgeOfA(A, e);
        const float edge[10] = {ea.pa.x, ea.pa.y,    ea.pa.z,    ea.da.x,    ea.da.y,
                                ea.da.z, ea.paRel.x, ea.paRel.y, ea.paRel.z, ea.da2};
        for (int k = 0; k < 9; ++k) sc.edgeRowsA[k][i] = A.arcs[k][e];
        for (int k = 0; k < 10; ++k) sc.edgeRowsA[9 + k][i] = edge[k];
    }
    // Padding lanes are zeros: they fail the sign tests.
    for (std::vector<float>& row : sc.edgeRowsA) std::fill(row.begin() + countA, row.begin() + padded, 0.0f);
    // Each of B's edges against all of A's at once, A's in SIMD lanes: the three sign tests of the Minkowski-face test
    // branch-free over A's arcs (most pairs fail them), then the axis and the separation along it, and only the lanes
    // that may beat `limit` go on, one at a time, through edgePairCandidate, which decides with its own arithmetic
    // and finds the axis. The lanes' separation is only a filter: it drops a lane when it lies below the limit by a
    // slack far above its rounding (or the edges are clearly parallel), so every pair the scalar test would take
    // still reaches it, and the answer is the plain search's bit for bit. (On the hull pile ~17 lanes a call pass the
    // sign tests and ~0.5 the separation.) The best pair is the one a scan over A's edges, then B's, would keep
    // first: the largest separation, ties to the lowest (i, j).
    using simd::FloatW;
    const float* rowsA[19];
    for (int k = 0; k < 19; ++k) rowsA[k] = sc.edgeRowsA[k].data();
    const FloatW filterLimit(limit - 1e-4f * (A.size + B.size));
    const FloatW clearlyParallel(0.5f * kBoxEdgeParallelEpsilon * kBoxEdgeParallelEpsilon);
    const FloatW orientationFloor(1e-3f * (A.size + B.size));
    float sepE = -INFINITY;
    int edgeA = -1, edgeB = -1;
    Vec3 axisE{};
    alignas(64) bool skip[simd::kLanes];
    for (int jb = 0; jb < countB; ++jb) {
        const int j = static_cast<int>(sc.edgesB[static_cast<std::size_t>(jb)]);
        const HullEdge& eb = B.edges[j];
        const Vec3 n0 = normalB(static_cast<int>(eb.face0)), n1 = normalB(static_cast<int>(eb.face1));
        const Vec3 c = cross(n1, n0);  // (-n1) x (-n0)
        const Vec3 dirB = vb[eb.v1] - vb[eb.v0];
        const FloatW n0x(n0.x), n0y(n0.y), n0z(n0.z), n1x(n1.x), n1y(n1.y), n1z(n1.z), cx(c.x), cy(c.y), cz(c.z);
        const FloatW zero(0.0f);
        const Vec3 pb = vb[eb.v0];
        const FloatW dbx(dirB.x), dby(dirB.y), dbz(dirB.z), pbx(pb.x), pby(pb.y), pbz(pb.z);
        const float db2 = dot(dirB, dirB);
        for (int i0 = 0; i0 < countA; i0 += static_cast<int>(simd::kLanes)) {
            const auto row = [&](int k) { return simd::load<FloatW>(rowsA[k] + i0); };
            const FloatW bxaX = row(6), bxaY = row(7), bxaZ = row(8);
            const FloatW cba = -(n0x * bxaX + n0y * bxaY + n0z * bxaZ);
            const FloatW dba = -(n1x * bxaX + n1y * bxaY + n1z * bxaZ);
            const FloatW adc = row(0) * cx + row(1) * cy + row(2) * cz;
            const FloatW bdc = row(3) * cx + row(4) * cy + row(5) * cz;
            simd::MaskW fail = (cba * dba >= zero) | (adc * bdc >= zero) | (cba * bdc <= zero);
            if (simd::all(fail)) continue;
            {
                const FloatW daX = row(12), daY = row(13), daZ = row(14);
                const FloatW ax = daY * dbz - daZ * dby, ay = daZ * dbx - daX * dbz, az = daX * dby - daY * dbx;
                const FloatW len2 = ax * ax + ay * ay + az * az;
                const FloatW outward = ax * row(15) + ay * row(16) + az * row(17);
                const FloatW num = ax * (pbx - row(9)) + ay * (pby - row(10)) + az * (pbz - row(11));
                const FloatW length = simd::sqrt(len2);
                const FloatW oriented = simd::select(outward < zero, -num, num);
                // A lane whose orientation is unsure (an axis at right angles to the edge's offset from the interior)
                // is left to the scalar test.
                const simd::MaskW sure = simd::abs(outward) > orientationFloor * length;
                fail = fail | (len2 < clearlyParallel * row(18) * FloatW(db2)) |
                       (sure & (oriented < filterLimit * length));
                if (simd::all(fail)) continue;
            }
            simd::storeMask(skip, fail);
            for (int k = 0; k < static_cast<int>(simd::kLanes) && i0 + k < countA; ++k) {
                if (skip[k]) continue;
                const int i = static_cast<int>(sc.edgesA[static_cast<std::size_t>(i0 + k)]);
                const EdgeOfA ea = edgeOfA(A, i);
                Vec3 axis;
                float len2, num;
                if (!edgePairCandidate(ea, vb[eb.v0], dirB, c, -dot(n0, ea.bxa), -dot(n1, ea.bxa), limit, axis, len2,
                                       num))
                    continue;
                const float sep = num / std::sqrt(len2);
                if (sep > margin) return separatedBy(SatHint::kEdges, i, j);
                if (sep > sepE || (sep == sepE && i < edgeA))
                    sepE = sep, edgeA = i, edgeB = j, axisE = axis / std::sqrt(len2);
            }
        }
    }

    const float bestSeparation = maxf(maxf(sepA, sepB), sepE);
    if (edgeA >= 0 && clearlyBetter(sepE, sepFace)) {
        edgeContact(edgeA, edgeB, axisE);
        if (hint)
            *hint = {
                SatHint::kEdges, false, 0, static_cast<std::uint16_t>(edgeA), static_cast<std::uint16_t>(edgeB), sepE};
        return keepDistanceExact(bestSeparation);
    }
    const int fr = useB ? faceB : faceA;
    faceContact(useB, fr);
    if (hint) *hint = {useB ? SatHint::kFaceB : SatHint::kFaceA, false, 0, static_cast<std::uint16_t>(fr), 0, sepFace};
    return keepDistanceExact(bestSeparation);
}

/// Segment feature of parameter t in [0, 1]: 1 at the start, 2 at the end, 0 between.
std::uint32_t segmentCode(float t) { return t <= 0 ? 1u : (t >= 1 ? 2u : 0u); }

/// Clips segment p0 + t (p1 - p0) to the prism over face f and reports its ends within the margin.
int capsuleFaceContact(const HullView& H, int f, Vec3 p0, Vec3 p1, float radius, float margin, Vec3 out[2],
                       float depth[2], std::uint32_t feature[2]) {
    const Vec3 n = H.normals[f], d = p1 - p0;
    float t0 = 0, t1 = 1;
    int plane0 = -1, plane1 = -1;
    const std::uint32_t s0 = H.faceStart[f], s1 = H.faceStart[f + 1];
    for (std::uint32_t k = s0; k < s1; ++k) {
        const Vec3 a = H.vertices[H.faceVertices[k]], b = H.vertices[H.faceVertices[k + 1 == s1 ? s0 : k + 1]];
        const Vec3 side = cross(b - a, n);
        const float h = dot(side, a);
        const float e0 = dot(side, p0) - h, e1 = dot(side, p1) - h;
        if (e0 > 0 && e1 > 0) return 0;
        const int plane = static_cast<int>(k - s0);
        if (e0 > 0) {
            const float t = e0 / (e0 - e1);
            if (t > t0) t0 = t, plane0 = plane;
        } else if (e1 > 0) {
            const float t = e0 / (e0 - e1);
            if (t < t1) t1 = t, plane1 = plane;
        }
    }
    if (t0 > t1) return 0;
    const int ends = dot(d, d) > 0 ? 2 : 1;
    int count = 0;
    for (int e = 0; e < ends; ++e) {
        const Vec3 q = p0 + d * (e == 0 ? t0 : t1);
        const float gap = dot(n, q) - H.offsets[f];
        if (radius - gap < -margin) continue;
        const int plane = e == 0 ? plane0 : plane1;
        out[count] = q - n * gap;
        depth[count] = radius - gap;
        feature[count] = (1u << 30) | ((static_cast<std::uint32_t>(f) & 0xFFu) << 8) | static_cast<std::uint32_t>(e) |
                         (plane >= 0 ? 0x40u | ((static_cast<std::uint32_t>(plane) & 0x1Fu) << 1) : 0u);
        ++count;
    }
    return count;
}

/// Exact distance between segment seg (swept by radius) and the box of half extents h, both in the box frame, in
/// closed form. The squared distance of the segment point s(t) = seg0 + t d from the box is the sum over the axes of
/// the squared excess of |s_i(t)| over h_i: convex, piecewise quadratic in t, continuously differentiable, with a
/// break where s(t) crosses a face plane (at most six). Its derivative is therefore monotone and piecewise linear:
/// the interval where it changes sign is found by walking the sorted breaks, and on that interval (a fixed set of
/// axes in excess) the minimum is one division. The closest points are s(t) and s(t) clamped to the box. The face
/// axes, tested first, give the common early exit (a lower bound on the distance). Same result layout as GJK
/// (normal from the capsule to the box); cores closer than 1e-6 count as overlapping.
GjkResult segmentBoxDistance(const Vec3 seg[2], float radius, Vec3 h, float margin) {
    const Vec3 d = seg[1] - seg[0];
    GjkResult r;
    // Face axes: the larger gap of the two ends' lower bound beyond each face.
    float faceGap = -INFINITY;
    for (int k = 0; k < 3; ++k) {
        const float a = seg[0][k], b = seg[1][k], hk = h[k];
        faceGap = maxf(faceGap, maxf(minf(a, b) - hk, -maxf(a, b) - hk));
    }
    if (faceGap - radius > margin) {  // a face axis already separates beyond the margin: the common early exit
        r.status = GjkStatus::Separated;
        r.distance = faceGap - radius;
        return r;
    }
    const float s0[3] = {seg[0].x, seg[0].y, seg[0].z}, dv[3] = {d.x, d.y, d.z}, hv[3] = {h.x, h.y, h.z};
    // Half the derivative of the squared distance at t: sum over the axes of excess * d_i.
    auto slope = [&](float t) {
        float sum = 0;
        for (int k = 0; k < 3; ++k) {
            const float x = s0[k] + t * dv[k];
            sum += (x - maxf(-hv[k], minf(x, hv[k]))) * dv[k];
        }
        return sum;
    };
    float t = 0;
    if (dot(d, d) > 0 && slope(0) < 0) {
        if (slope(1) <= 0) {
            t = 1;
        } else {
            float breaks[6];
            int count = 0;
            for (int k = 0; k < 3; ++k) {
                if (dv[k] == 0) continue;
                const float inv = 1.0f / dv[k];
                for (const float plane : {hv[k], -hv[k]}) {
                    const float b = (plane - s0[k]) * inv;
                    if (!(b > 0 && b < 1)) continue;
                    int i = count++;  // insertion keeps them sorted (at most six)
                    for (; i > 0 && breaks[i - 1] > b; --i) breaks[i] = breaks[i - 1];
                    breaks[i] = b;
                }
            }
            float lo = 0, hi = 1;
            for (int i = 0; i < count; ++i) {
                if (slope(breaks[i]) >= 0) {
                    hi = breaks[i];
                    break;
                }
                lo = breaks[i];
            }
            // On (lo, hi) the axes in excess are fixed: those of its midpoint. The slope there is
            // sum (s0_i + t d_i - side_i h_i) d_i, zero at t = sum (side_i h_i - s0_i) d_i / sum d_i^2.
            const float mid = 0.5f * (lo + hi);
            float num = 0, den = 0;
            for (int k = 0; k < 3; ++k) {
                const float x = s0[k] + mid * dv[k];
                if (x > hv[k] || x < -hv[k]) {
                    num += ((x > 0 ? hv[k] : -hv[k]) - s0[k]) * dv[k];
                    den += dv[k] * dv[k];
                }
            }
            t = den > 0 ? maxf(lo, minf(num / den, hi)) : lo;
        }
    }
    const Vec3 p = seg[0] + d * t;
    const Vec3 q{maxf(-h.x, minf(p.x, h.x)), maxf(-h.y, minf(p.y, h.y)), maxf(-h.z, minf(p.z, h.z))};
    const Vec3 a = p - q;  // from the box to the segment
    // Over a face (one axis in excess) the distance is that excess exactly, as the face axis gives it.
    const int excess = (a.x != 0) + (a.y != 0) + (a.z != 0);
    const float dist = excess == 1 ? std::fabs(a.x + a.y + a.z) : length(a);
    // Cores that overlap or touch (within the rounding of a surface point at this scale) have no usable direction:
    // the caller's SAT decides.
    if (!(dist > 1e-6f * maxf(1.0f, length(h) + length(d)))) return r;
    const Vec3 axis = excess == 1
                          ? Vec3{a.x > 0 ? 1.0f : (a.x < 0 ? -1.0f : 0.0f), a.y > 0 ? 1.0f : (a.y < 0 ? -1.0f : 0.0f),
                                 a.z > 0 ? 1.0f : (a.z < 0 ? -1.0f : 0.0f)}
                          : a * (1.0f / dist);
    r.status = dist > radius ? GjkStatus::Separated : GjkStatus::RadiiOverlap;
    r.distance = dist - radius;
    r.normal = -axis;
    r.pointA = p - axis * radius;
    r.pointB = q;
    return r;
}

/// Capsule A against polytope B, in B's frame relative to its centre. `boxHalf` is set when B is a box: its exact
/// segment-box distance replaces GJK.
/// Where the line through `point` along unit `n` leaves the capsule (segment p0-p1 swept by `radius`) on its far side
/// along n: the largest lambda with point + n lambda in the capsule, the capsule's surface point facing along n on
/// that line. False when the line misses the capsule. Roots of the cylinder's quadratic (within the segment) and of
/// both end spheres'.
bool capsuleExitAlong(Vec3 p0, Vec3 p1, float radius, Vec3 point, Vec3 n, float& lambda) {
    const Vec3 d = p1 - p0, m = point - p0;
    const float dd = dot(d, d), r2 = radius * radius;
    float best = -INFINITY;
    const auto sphere = [&](Vec3 c) {
        const Vec3 mc = point - c;
        const float b = dot(mc, n), disc = b * b - (dot(mc, mc) - r2);
        if (disc >= 0) best = maxf(best, -b + std::sqrt(disc));
    };
    sphere(p0);
    sphere(p1);
    if (dd > 0) {
        const float nd = dot(n, d), md = dot(m, d);
        const float a = 1.0f - nd * nd / dd, b = dot(m, n) - md * nd / dd, c = dot(m, m) - md * md / dd - r2;
        const float disc = b * b - a * c;
        if (a > 1e-12f && disc >= 0) {
            const float lam = (-b + std::sqrt(disc)) / a;
            const float t = (md + nd * lam) / dd;
            if (t >= 0 && t <= 1) best = maxf(best, lam);
        }
    }
    if (!(best > -INFINITY)) return false;
    lambda = best;
    return true;
}

bool collideCapsulePolytope(const CapsuleSegment& capsule, const HullView& H, const Transform& poseH, float margin,
                            Manifold& out, const Vec3* boxHalf = nullptr) {
    out.pointCount = 0;
    const Quat qInv = conjugate(poseH.rotation);
    const Vec3 c = rotate(qInv, capsule.center - poseH.position), h = rotate(qInv, capsule.halfAxis);
    const Vec3 seg[2] = {c - h, c + h};
    const float radius = capsule.radius;
    const Rot rh = toRot(poseH.rotation);

    GjkShape sa, sb;
    sa.core = GjkShape::Core::Points, sa.points = seg, sa.pointCount = 2, sa.radius = radius;
    sb.core = GjkShape::Core::Points, sb.points = H.vertices, sb.pointCount = static_cast<std::uint32_t>(H.vertexCount);
    const GjkResult g = boxHalf ? segmentBoxDistance(seg, radius, *boxHalf, margin) : gjkDistance(sa, sb);

    Vec3 pts[2];
    float depth[2];
    std::uint32_t feature[2];
    int count = 0;
    Vec3 normal;  // from the capsule to the polytope, in B's frame
    if (g.status != GjkStatus::CoresOverlap) {
        if (g.distance > margin) return false;
        normal = g.normal;
        int best = 0;
        float bestCos = -INFINITY;
        for (int f = 0; f < H.faceCount; ++f) {
            const float cs = -dot(H.normals[f], normal);
            if (cs > bestCos) bestCos = cs, best = f;
        }
        if (bestCos >= kCapsuleFaceAlignCos) {
            // The points come from the face; the normal stays GJK's (the exact direction of least separation: the
            // face normal, up to the alignment tolerance, would under-report how far a tilted capsule must move).
            count = capsuleFaceContact(H, best, seg[0], seg[1], radius, margin, pts, depth, feature);
            // Keep the face points only if they carry GJK's depth: when GJK's closest point is on the face's
            // boundary and the capsule hangs over it, the clipped segment misses the deepest part.
            const float tol = kBoxAxisAbsoluteTolerance * maxf(H.size, length(h) + radius);
            if (count > 0 && maxf(depth[0], count > 1 ? depth[1] : -INFINITY) < -g.distance - tol) count = 0;
        }
        if (count == 0) {
            const Vec3 d = seg[1] - seg[0];
            const float dd = dot(d, d);
            const float tSeg = dd > 0 ? dot(g.pointA - normal * radius - seg[0], d) / dd : 0.0f;
            pts[0] = g.pointB, depth[0] = -g.distance;
            feature[0] = (2u << 30) | ((nearestVertex(H, g.pointB) & 0xFFFFu) << 2) | segmentCode(tSeg);
            count = 1;
        }
    } else {
        // Cores overlap: SAT over the faces and the admissible segment x edge axes.
        float sepF = -INFINITY;
        int faceF = 0;
        for (int f = 0; f < H.faceCount; ++f) {
            const Vec3 n = H.normals[f];
            const float sep = minf(dot(n, seg[0]), dot(n, seg[1])) - H.offsets[f] - radius;
            if (sep > sepF) sepF = sep, faceF = f;
        }
        if (sepF > margin) return false;
        const Vec3 d = seg[1] - seg[0];
        const float dd = dot(d, d);
        float sepE = -INFINITY;
        int edgeE = -1;
        Vec3 axisE{};
        constexpr float kParallel2 = kBoxEdgeParallelEpsilon * kBoxEdgeParallelEpsilon;
        for (int i = 0; i < H.edgeCount && dd > 0; ++i) {
            const HullEdge& e = H.edges[i];
            // The segment's Gauss map is the great circle orthogonal to d; the edge's arc must cross it.
            if (dot(H.normals[e.face0], d) * dot(H.normals[e.face1], d) >= 0) continue;
            const Vec3 v0 = H.vertices[e.v0], ed = H.vertices[e.v1] - v0;
            Vec3 axis = cross(d, ed);
            const float len2 = dot(axis, axis);
            if (len2 < kParallel2 * dd * dot(ed, ed)) continue;
            if (dot(axis, v0 - H.interior) < 0) axis = -axis;  // outward from the polytope
            const float sep = dot(axis, seg[0] - v0) / std::sqrt(len2) - radius;
            if (sep > sepE) sepE = sep, edgeE = i, axisE = axis / std::sqrt(len2);
        }
        if (sepE > margin) return false;
        const float absTol = kBoxAxisAbsoluteTolerance * maxf(H.size, std::sqrt(dd));
        if (edgeE >= 0 && sepE > sepF + kBoxAxisRelativeTolerance * std::fabs(sepF) + absTol) {
            const HullEdge& e = H.edges[edgeE];
            const Vec3 v0 = H.vertices[e.v0], ed = H.vertices[e.v1] - v0;
            float s, w;
            closestSegmentPoints(seg[0], d, v0, ed, s, w);
            const Vec3 ca = seg[0] + d * s, cb = v0 + ed * w;
            normal = -axisE;
            pts[0] = cb, depth[0] = radius - dot(axisE, ca - cb);
            const Vec3 dv0 = cb - v0, dv1 = cb - H.vertices[e.v1];
            const std::uint32_t vtx = dot(dv0, dv0) <= dot(dv1, dv1) ? e.v0 : e.v1;
            feature[0] = (2u << 30) | ((vtx & 0xFFFFu) << 2) | segmentCode(s);
            count = 1;
        } else {
            normal = -H.normals[faceF];
            count = capsuleFaceContact(H, faceF, seg[0], seg[1], radius, margin, pts, depth, feature);
            if (count == 0) {
                // The segment lies beside the face's prism (possible only for odd shapes): its deepest end.
                const Vec3 n = H.normals[faceF];
                const int e = dot(n, seg[0]) <= dot(n, seg[1]) ? 0 : 1;
                const float gap = dot(n, seg[e]) - H.offsets[faceF];
                pts[0] = seg[e] - n * gap, depth[0] = radius - gap;
                feature[0] = (1u << 30) | ((static_cast<std::uint32_t>(faceF) & 0xFFu) << 8) | e;
                count = 1;
            }
        }
    }
    // Each point on the polytope names its partner on the capsule, `depth` further along the normal: where the line
    // along the normal through it leaves the capsule. A face's clipped segment gives depths measured from the segment
    // point straight above the face, which name a point inside a tilted capsule, or one off a normal that is GJK's
    // rather than the face's.
    for (int k = 0; k < count; ++k) {
        float lambda = 0;
        if (capsuleExitAlong(seg[0], seg[1], radius, pts[k], normal, lambda)) depth[k] = lambda;
    }
    out.normal = rh * normal;
    for (int k = 0; k < count; ++k) {
        out.points[k].position = poseH.position + rh * pts[k];
        out.points[k].depth = depth[k];
        out.points[k].feature = feature[k];
    }
    out.pointCount = count;
    return count > 0;
}

}  // namespace

HullAdjacency buildHullAdjacency(const ConvexHull& hull) {
    HullAdjacency adj;
    const std::size_t nv = hull.vertices.size();
    // Directed face edges u -> v grouped by u (compressed rows): value v and the face that holds the edge.
    std::vector<std::uint32_t> start(nv + 1, 0), to, face;
    const std::uint32_t faces = hull.faceCount();
    for (std::uint32_t f = 0; f < faces; ++f)
        for (std::uint32_t k = hull.faceStart[f]; k < hull.faceStart[f + 1]; ++k) ++start[hull.faceVertices[k] + 1];
    for (std::size_t i = 0; i < nv; ++i) start[i + 1] += start[i];
    to.resize(start[nv]);
    face.resize(start[nv]);
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::uint32_t f = 0; f < faces; ++f) {
        const std::uint32_t s0 = hull.faceStart[f], s1 = hull.faceStart[f + 1];
        for (std::uint32_t k = s0; k < s1; ++k) {
            const std::uint32_t u = hull.faceVertices[k], v = hull.faceVertices[k + 1 == s1 ? s0 : k + 1];
            to[fill[u]] = v;
            face[fill[u]++] = f;
        }
    }
    auto faceOf = [&](std::uint32_t u, std::uint32_t v) {
        for (std::uint32_t k = start[u]; k < start[u + 1]; ++k)
            if (to[k] == v) return face[k];
        return 0u;  // not an edge of any face: only for malformed hulls
    };
    adj.edges.resize(hull.edges.size() / 2);
    for (std::size_t e = 0; e < adj.edges.size(); ++e) {
        const std::uint32_t u = hull.edges[2 * e], v = hull.edges[2 * e + 1];
        adj.edges[e] = {u, v, faceOf(u, v), faceOf(v, u)};
    }
    Vec3 sum{};
    for (const Vec3& p : hull.vertices) sum += p;
    adj.interior = nv > 0 ? sum / static_cast<float>(nv) : Vec3{};
    for (const Vec3& p : hull.vertices) adj.size = maxf(adj.size, length(p - adj.interior));
    for (std::vector<float>& row : adj.normalRows) row.assign(paddedRow(faces), 0.0f);
    for (std::uint32_t f = 0; f < faces; ++f) {
        adj.normalRows[0][f] = hull.faceNormals[f].x;
        adj.normalRows[1][f] = hull.faceNormals[f].y;
        adj.normalRows[2][f] = hull.faceNormals[f].z;
    }
    for (std::vector<float>& row : adj.arcs) row.assign(paddedRow(adj.edges.size()), 0.0f);
    for (std::size_t e = 0; e < adj.edges.size(); ++e) {
        const Vec3 a = hull.faceNormals[adj.edges[e].face0], b = hull.faceNormals[adj.edges[e].face1];
        const Vec3 c = cross(b, a);
        const float values[9] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z};
        for (int r = 0; r < 9; ++r) adj.arcs[r][e] = values[r];
    }
    for (std::vector<float>& row : adj.arcCones) row.assign(paddedRow(adj.edges.size()), 0.0f);
    for (std::size_t e = 0; e < adj.edges.size(); ++e) {
        const Vec3 a = hull.faceNormals[adj.edges[e].face0], b = hull.faceNormals[adj.edges[e].face1];
        const float half = 0.5f * std::acos(std::fmax(-1.0f, std::fmin(1.0f, dot(a, b))));
        const Vec3 sum2 = a + b;
        const float len = length(sum2);
        // Opposite normals (only on degenerate hulls): no midpoint, and a cone of the whole sphere.
        const Vec3 mid = len > 1e-6f ? sum2 / len : Vec3{1, 0, 0};
        const float values[5] = {mid.x, mid.y, mid.z, len > 1e-6f ? std::cos(half) : -1.0f,
                                 len > 1e-6f ? std::sin(half) : 0.0f};
        for (int r = 0; r < 5; ++r) adj.arcCones[r][e] = values[r];
    }
    adj.vertexFaceStart.assign(nv + 1, 0);
    for (std::uint32_t k = 0; k < hull.faceStart[faces]; ++k) ++adj.vertexFaceStart[hull.faceVertices[k] + 1];
    for (std::size_t i = 0; i < nv; ++i) adj.vertexFaceStart[i + 1] += adj.vertexFaceStart[i];
    adj.vertexFaces.resize(adj.vertexFaceStart[nv]);
    std::vector<std::uint32_t> next(adj.vertexFaceStart.begin(), adj.vertexFaceStart.end() - 1);
    for (std::uint32_t f = 0; f < faces; ++f)  // in face order, so each vertex's faces ascend
        for (std::uint32_t k = hull.faceStart[f]; k < hull.faceStart[f + 1]; ++k)
            adj.vertexFaces[next[hull.faceVertices[k]]++] = f;
    adj.inradius = faces > 0 ? INFINITY : 0.0f;
    for (std::uint32_t f = 0; f < faces; ++f)
        adj.inradius = minf(adj.inradius, hull.faceOffsets[f] - dot(hull.faceNormals[f], adj.interior));
    adj.inradius = maxf(adj.inradius, 0.0f);
    return adj;
}

bool collideHulls(const ConvexHull& a, const HullAdjacency& adjA, const Transform& poseA, const ConvexHull& b,
                  const HullAdjacency& adjB, const Transform& poseB, float margin, Manifold& out, SatHint* hint,
                  float featureDrift) {
    return collidePolytopes(viewOf(a, adjA), poseA, viewOf(b, adjB), poseB, margin, out, hint, featureDrift);
}

bool collideHulls(const ConvexHull& a, const Transform& poseA, const ConvexHull& b, const Transform& poseB,
                  float margin, Manifold& out) {
    Scratch& sc = scratch();
    sc.adjA = buildHullAdjacency(a);
    sc.adjB = buildHullAdjacency(b);
    return collideHulls(a, sc.adjA, poseA, b, sc.adjB, poseB, margin, out);
}

bool collideBoxHull(const Transform& box, Vec3 half, const ConvexHull& hull, const HullAdjacency& adj,
                    const Transform& poseHull, float margin, Manifold& out, SatHint* hint, float featureDrift) {
    Vec3 vertices[8];
    float offsets[6];
    return collidePolytopes(boxView(half, vertices, offsets), box, viewOf(hull, adj), poseHull, margin, out, hint,
                            featureDrift);
}

bool collideBoxHull(const Transform& box, Vec3 half, const ConvexHull& hull, const Transform& poseHull, float margin,
                    Manifold& out) {
    Scratch& sc = scratch();
    sc.adjB = buildHullAdjacency(hull);
    return collideBoxHull(box, half, hull, sc.adjB, poseHull, margin, out);
}

bool collideCapsuleBox(const CapsuleSegment& capsule, const Transform& box, Vec3 half, float margin, Manifold& out) {
    // Most candidate pairs are apart along a box face axis: that test first, before the box is made a hull view.
    // (segmentBoxDistance repeats it, so the pairs that pass get the same answer as ever.)
    const Quat qInv = conjugate(box.rotation);
    const Vec3 c = rotate(qInv, capsule.center - box.position), h = rotate(qInv, capsule.halfAxis);
    const Vec3 seg0 = c - h, seg1 = c + h;
    float faceGap = -INFINITY;
    for (int k = 0; k < 3; ++k) {
        const float a = seg0[k], b = seg1[k], hk = half[k];
        faceGap = maxf(faceGap, maxf(minf(a, b) - hk, -maxf(a, b) - hk));
    }
    if (faceGap - capsule.radius > margin) {
        out.pointCount = 0;
        return false;
    }
    Vec3 vertices[8];
    float offsets[6];
    return collideCapsulePolytope(capsule, boxView(half, vertices, offsets), box, margin, out, &half);
}

bool collideCapsuleHull(const CapsuleSegment& capsule, const ConvexHull& hull, const HullAdjacency& adj,
                        const Transform& poseHull, float margin, Manifold& out) {
    return collideCapsulePolytope(capsule, viewOf(hull, adj), poseHull, margin, out);
}

bool collideCapsuleHull(const CapsuleSegment& capsule, const ConvexHull& hull, const Transform& poseHull, float margin,
                        Manifold& out) {
    Scratch& sc = scratch();
    sc.adjB = buildHullAdjacency(hull);
    return collideCapsuleHull(capsule, hull, sc.adjB, poseHull, margin, out);
}

}  // namespace rubble::detail
