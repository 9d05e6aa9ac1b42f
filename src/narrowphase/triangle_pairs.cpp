// Sphere-, capsule-, box- and hull-triangle contact kernels; the rules and feature ids are documented in the header.
#include "narrowphase/triangle_pairs.h"

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <vector>

#include "narrowphase/clip.h"
#include "narrowphase/closest_points_contact.h"
#include "narrowphase/gjk.h"
#include "narrowphase/hull_pairs.h"
#include "shapes/shape.h"
#include "simd/simd.h"
#include "simd/vec.h"

namespace rubble::detail {
namespace {

/// Triangles whose squared doubled area is below this fraction of (longest edge^2)^2 are skipped (the sine between
/// their edges is below about 1e-5: the normal would be rounding noise). Same threshold as mesh_adjacency.cpp.
constexpr float kDegenerateAreaSq = 1e-10f;
/// Squared distances below this (1 micrometre squared) have no usable direction: the face normal is taken.
constexpr float kMinDistanceSq = 1e-12f;
/// Squared segment lengths below this count as points.
constexpr float kMinSegmentSq = 1e-12f;
/// SAT hysteresis, as in box_box.h: a later axis must beat the current one by this fraction of |separation| ...
constexpr float kAxisRelativeTolerance = 0.05f;
/// ... plus this fraction of the size (the larger of the body's -- largest box half extent, or largest hull vertex
/// distance from its centroid -- and the longest triangle edge).
constexpr float kAxisAbsoluteTolerance = 1e-4f;
/// Triangle vertices within this fraction of the size of the deepest one along the normal share its feature.
constexpr float kFeatureTolerance = 1e-4f;
/// The hull kernel's clipping planes are pushed out by this fraction of the size (a few times the rounding of its
/// inputs): a vertex on a shared boundary (a hull face coplanar with the triangle, parallel edges over each other)
/// then stays a vertex instead of rounding into crossing points, which would also make its feature id flicker.
constexpr float kClipSlack = 1e-6f;
/// Hull contact candidates closer than this fraction of the size to a deeper one are dropped: an incident edge
/// lying on a side plane crosses it right next to its own vertices, and such twins only add solver work.
constexpr float kMergeDistance = 1e-4f;

constexpr int kFeatureFace = 0;
constexpr int featureEdge(int e) { return 1 + e; }
constexpr int featureVertex(int v) { return 4 + v; }

/// Unit normal of triangle (0, ab, ac), counter-clockwise; false for (nearly) zero-area or non-finite triangles.
[[gnu::always_inline]] inline bool faceNormal(Vec3 ab, Vec3 ac, Vec3& normal) {
    const Vec3 n = cross(ab, ac);
    const Vec3 bc = ac - ab;
    const float longest = std::max({dot(ab, ab), dot(ac, ac), dot(bc, bc)});
    const float n2 = dot(n, n);
    if (!(n2 > kDegenerateAreaSq * longest * longest) || !std::isfinite(n2) || !std::isfinite(longest)) return false;
    normal = n * (1.0f / std::sqrt(n2));  // one division, not three: this runs for every triangle job
    return true;
}

/// The ghost rule: may a contact on `feature` keep a normal other than the face normal?
bool featureActive(int feature, std::uint8_t activeEdges) {
    if (feature == kFeatureFace) return true;
    if (feature < 4) return ((activeEdges >> (feature - 1)) & 1u) != 0;
    const int v = feature - 4;  // vertex v ends edge v - 1 and starts edge v
    return ((activeEdges >> v) & 1u) != 0 || ((activeEdges >> ((v + 2) % 3)) & 1u) != 0;
}

/// Rejection before the closest-point search of the sphere and capsule kernels, for the many triangles that a
/// body's bounds overlap but that lie out of its reach: a segment whose two ends (signed distances d0, d1 from a plane
/// of normal length sqrt(normal2) that has the whole triangle on its other side) are both beyond `reach` from it
/// cannot come within reach of the triangle. The plane is the triangle's own (either side) or an edge's side plane.
/// The slack (1e-4 of the reach) leaves every borderline case to the exact test, so rounding here never drops a
/// contact that the exact test keeps.
bool beyondReach(float d0, float d1, float reach, float normal2) {
    float nearer;
    if (d0 > 0 && d1 > 0)
        nearer = std::min(d0, d1);
    else if (d0 < 0 && d1 < 0)
        nearer = -std::max(d0, d1);
    else
        return false;  // the ends straddle the plane or touch it (or are not numbers)
    const float limit = reach * (1.0f + 1e-4f);
    return nearer * nearer > limit * limit * normal2;
}

struct TrianglePoint {
    Vec3 point;
    int feature;
};

/// Closest point to p on triangle (a, b, c) and its Voronoi region (Ericson, RTCD 5.1.5).
TrianglePoint closestOnTriangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const float d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return {a, featureVertex(0)};
    const Vec3 bp = p - b;
    const float d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return {b, featureVertex(1)};
    const float vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return {a + ab * (d1 / (d1 - d3)), featureEdge(0)};
    const Vec3 cp = p - c;
    const float d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return {c, featureVertex(2)};
    const float vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return {a + ac * (d2 / (d2 - d6)), featureEdge(2)};
    const float va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return {b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))), featureEdge(1)};
    const float denom = 1.0f / (va + vb + vc);
    return {a + ab * (vb * denom) + ac * (vc * denom), kFeatureFace};
}

/// Whether closest-segment parameters lie at an end of either segment: the segments' closest points are then not
/// the shapes' closest points in general (an edge pair's axis gives their distance only inside both edges).
bool clampedToAnEnd(float s, float t) { return s <= 0 || s >= 1 || t <= 0 || t >= 1; }

/// Closest points of segments p1 + s d1 and p2 + t d2, s, t in [0, 1] (Ericson, RTCD 5.1.9).
void closestSegments(Vec3 p1, Vec3 d1, Vec3 p2, Vec3 d2, float& s, float& t) {
    const Vec3 r = p1 - p2;
    const float a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
    s = t = 0;
    if (a <= kMinSegmentSq && e <= kMinSegmentSq) return;
    if (a <= kMinSegmentSq) {
        t = std::clamp(f / e, 0.0f, 1.0f);
        return;
    }
    const float c = dot(d1, r);
    if (e <= kMinSegmentSq) {
        s = std::clamp(-c / a, 0.0f, 1.0f);
        return;
    }
    const float b = dot(d1, d2), denom = a * e - b * b;
    s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0f, 1.0f) : 0.0f;
    t = (b * s + f) / e;
    if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0f, 1.0f);
    } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0f, 1.0f);
    }
}

void addPoint(Manifold& out, Vec3 position, float depth, std::uint32_t feature) {
    ContactPoint& p = out.points[out.pointCount++];
    p.position = position;
    p.depth = depth;
    p.feature = feature;
}

/// Contact points gathered before the reduction to four, in the kernel's frame.
struct Candidates {
    Vec3 position[kClipCapacity];  // on the triangle
    float depth[kClipCapacity];
    std::uint32_t feature[kClipCapacity];
    int count = 0;

    void add(Vec3 p, float d, std::uint32_t f) {
        position[count] = p, depth[count] = d, feature[count] = f;
        ++count;
    }
};

/// Per-thread buffers of the box and hull kernels. Their element types initialise their members, so as locals they
/// would clear kilobytes per call that the call mostly does not use (measured: a quarter of the box kernel's time).
struct Scratch {
    ClipVertex poly[kClipCapacity], tmp[kClipCapacity];
    Vec3 planeNormals[kClipCapacity];
    float planeOffsets[kClipCapacity];
    Candidates cands;
    std::vector<float> faceDots;  // hull: per face, its dot products with the triangle's edges and side directions
};
Scratch& scratch() {
    thread_local Scratch s;
    return s;
}

/// Clips polygon `poly` (n vertices, capacity kClipCapacity; the scratch's `poly` buffer) against the planes
/// dot(normals[i], x) <= offsets[i], plane i numbered i for the point ids. Sets n to the new count and returns where
/// the polygon now is: the passes alternate between the scratch's two buffers instead of copying back. A plane with
/// every vertex inside would hand the polygon on unchanged, so it is skipped (for a body resting inside a triangle
/// most planes are).
const ClipVertex* clipAgainst(ClipVertex* poly, int& n, const Vec3* normals, const float* offsets, int planes) {
    ClipVertex* cur = poly;
    ClipVertex* spare = scratch().tmp;
    for (int p = 0; p < planes && n > 0; ++p) {
        bool inside = true;
        for (int e = 0; e < n; ++e) inside &= dot(normals[p], cur[e].p) - offsets[p] <= 0;
        if (inside) continue;
        n = clipPolygon(cur, n, spare, normals[p], offsets[p], p);
        std::swap(cur, spare);
    }
    return cur;
}

/// Drops candidates within `tol` of a deeper one (of an equally deep earlier one on ties). The deepest survives, and
/// every dropped point lies within a few `tol` of a kept one.
void mergeNearDuplicates(Candidates& c, float tol) {
    const float tol2 = tol * tol;
    bool drop[kClipCapacity] = {};
    for (int i = 0; i < c.count; ++i)
        for (int j = 0; j < c.count && !drop[i]; ++j) {
            const Vec3 d = c.position[i] - c.position[j];
            drop[i] = j != i && dot(d, d) <= tol2 && (c.depth[j] > c.depth[i] || (c.depth[j] == c.depth[i] && j < i));
        }
    int kept = 0;
    for (int i = 0; i < c.count; ++i) {
        if (drop[i]) continue;
        c.position[kept] = c.position[i], c.depth[kept] = c.depth[i], c.feature[kept] = c.feature[i];
        ++kept;
    }
    c.count = kept;
}

/// Which (at most 4) of the candidates to keep: the shared reduction, deepest first, then the largest area in the
/// plane across `n`. Returns how many of `chosen` are set.
int chooseReduced(const Candidates& c, Vec3 n, int (&chosen)[4]) {
    if (c.count <= 4) return c.count;
    Vec3 u, v;
    planeBasis(n, u, v);
    return reduceContactPoints(c.position, c.depth, c.count, u, v, chosen);
}

/// Writes the chosen candidates to `out`, moved from the kernel's frame to the world by `pose`.
int emitReduced(const Candidates& c, Vec3 n, const Transform& pose, Manifold& out) {
    int chosen[4] = {0, 1, 2, 3};
    const int count = chooseReduced(c, n, chosen);
    out.normal = rotate(pose.rotation, n);
    for (int i = 0; i < count; ++i)
        addPoint(out, rotate(pose.rotation, c.position[chosen[i]]) + pose.position, c.depth[chosen[i]],
                 c.feature[chosen[i]]);
    return out.pointCount;
}

/// The same for a kernel whose frame is a posed box (rotation as a matrix).
int emitReduced(const Candidates& c, Vec3 n, const TriangleBox& box, Manifold& out) {
    int chosen[4] = {0, 1, 2, 3};
    const int count = chooseReduced(c, n, chosen);
    out.normal = box.toWorld * n;
    for (int i = 0; i < count; ++i)
        addPoint(out, box.toWorld * c.position[chosen[i]] + box.pose.position, c.depth[chosen[i]],
                 c.feature[chosen[i]]);
    return out.pointCount;
}

/// What a box or hull kernel built, for the check of its distance: the candidates along `n` (the final axis, in the
/// body's frame), the separation of the triangle from the body along it (the best axis's: a lower bound on their
/// distance), and whether the candidates stand for the closest points only along the axis: the lone deepest vertex
/// taken when the clipped face lay beyond the margin (it lies beside the face), or edges' closest points clamped to
/// an end.
struct BuiltContact {
    float separation;
    bool offFace;
};

/// Whether every candidate lies apart (none touches or overlaps): only then can the shapes be apart, and the check
/// below worth its cost (most contacts of a resting pile overlap by a little).
bool allApart(const Candidates& cands) {
    for (int i = 0; i < cands.count; ++i)
        if (cands.depth[i] >= 0) return false;
    return true;
}

/// A box or hull apart from the triangle whose contact misstates their distance (closest_points_contact.h: its
/// deepest point lies farther out than the best axis's separation allows, or stands beside the face the axis
/// belongs to, or nothing lay within the margin) gets one point at GJK's closest points instead, its normal the
/// direction between them, unless the triangle's closest point lies on a feature the ghost rule makes inactive
/// (the face normal stands there: a neighbour's face covers it). Works in the body's frame: `body` is posed at the
/// identity, `t` the triangle there. `bodyVertex(p)` names the body's vertex nearest p for the feature id. Returns
/// whether the candidates were replaced (then `n` is the new normal).
template <class BodyVertex>
bool closestPointsInstead(const GjkShape& body, const Vec3 (&t)[3], std::uint8_t activeEdges, float margin, float size,
                          const BuiltContact& built, Candidates& cands, Vec3& n, BodyVertex&& bodyVertex) {
    // Touching within rounding (or overlapping), the direction between closest points is noise: the contact stands
    // unless it puts its deepest point clearly farther out than that.
    const bool touching = !(built.separation > kClosestPointsMinimumGap * size);
    if (touching && cands.count == 0) return false;
    if (cands.count > 0 && (touching || !built.offFace)) {
        float deepest = cands.depth[0];
        for (int i = 1; i < cands.count; ++i) deepest = std::max(deepest, cands.depth[i]);
        const float bound = std::max(built.separation, 0.0f) * (1 + kClosestPointsRelativeTolerance) +
                            (kClosestPointsAbsoluteTolerance + (touching ? kClosestPointsMinimumGap : 0.0f)) * size;
        if (deepest >= -bound) return false;
    }
    GjkShape triangle;
    triangle.core = GjkShape::Core::Points;
    triangle.points = t;
    triangle.pointCount = 3;
    const GjkResult g = gjkDistance(body, triangle);
    if (g.status != GjkStatus::Separated || g.distance > margin) return false;
    const int feature = closestOnTriangle(g.pointA, t[0], t[1], t[2]).feature;
    if (!featureActive(feature, activeEdges)) return false;
    n = g.normal;
    cands.count = 0;
    cands.add(g.pointB, -g.distance,
              kClosestPointsFeatureKind << 30 | (bodyVertex(g.pointA) & 0x3FFFFFu) << 8 |
                  static_cast<std::uint32_t>(feature));
    return true;
}

/// The triangle feature a face axis of the body touches: the triangle vertices within `tol` of the lowest along n
/// (3 = face, 2 = edge, 1 = vertex).
int featureAlong(const Vec3 (&t)[3], Vec3 n, float tol) {
    const float p[3] = {dot(n, t[0]), dot(n, t[1]), dot(n, t[2])};
    const float lo = std::min({p[0], p[1], p[2]});
    int count = 0, first = -1, last = -1;
    for (int i = 0; i < 3; ++i)
        if (p[i] <= lo + tol) ++count, last = i, first = first < 0 ? i : first;
    // Two vertices i < j: edge i when j = i + 1, edge 2 for the pair (0, 2).
    return count == 3 ? kFeatureFace : (count == 1 ? featureVertex(first) : featureEdge(last == first + 1 ? first : 2));
}

float component(Vec3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }
Vec3 axisVector(int k, float s) { return {k == 0 ? s : 0.0f, k == 1 ? s : 0.0f, k == 2 ? s : 0.0f}; }
Vec3 withComponents(int k, float xk, int u, float xu, int v, float xv) {
    float c[3];
    c[k] = xk, c[u] = xu, c[v] = xv;
    return {c[0], c[1], c[2]};
}

}  // namespace

// ---- Sphere -----------------------------------------------------------------------------------------------------

int collideSphereTriangle(Vec3 center, float radius, const TriangleVertices& tri, std::uint8_t activeEdges,
                          float margin, Manifold& out) {
    out.pointCount = 0;
    const Vec3 origin = tri[0];
    const Vec3 b = tri[1] - origin, c = tri[2] - origin, p = center - origin;
    Vec3 faceN;
    if (!faceNormal(b, c, faceN)) return 0;
    const float reach = radius + margin;
    const float h = dot(faceN, p);
    if (beyondReach(h, h, reach, 1.0f)) return 0;
    const TrianglePoint q = closestOnTriangle(p, {}, b, c);
    const Vec3 d = q.point - p;
    const float dist2 = dot(d, d);
    if (!(dist2 <= reach * reach)) return 0;  // also refuses NaN
    // Body to triangle: against the face normal on the centre's side (front when the centre is in the plane).
    const Vec3 toFace = dot(faceN, p) >= 0 ? -faceN : faceN;
    const bool useFace = q.feature == kFeatureFace || dist2 <= kMinDistanceSq || !featureActive(q.feature, activeEdges);
    const Vec3 n = useFace ? toFace : d / std::sqrt(dist2);
    const float depth = radius + dot(p - q.point, n);
    if (depth < -margin) return 0;
    out.normal = n;
    // Along the face normal the sphere touches the plane under its centre, wherever the closest point of this
    // triangle is: a point off that line would turn the sphere as it pushes (a rolling sphere's side moves along n).
    const Vec3 point = useFace ? p - faceN * h : q.point;
    addPoint(out, origin + point, depth, std::uint32_t(q.feature));
    return 1;
}

// ---- Capsule ----------------------------------------------------------------------------------------------------

int collideCapsuleTriangle(const CapsuleSegment& capsule, const TriangleVertices& tri, std::uint8_t activeEdges,
                           float margin, Manifold& out, bool inReach) {
    out.pointCount = 0;
    const Vec3 origin = tri[0];
    const Vec3 v[3] = {{}, tri[1] - origin, tri[2] - origin};
    Vec3 faceN;
    if (!faceNormal(v[1], v[2], faceN)) return 0;
    const float radius = capsule.radius;
    const Vec3 center = capsule.center - origin;
    const Vec3 s0 = center - capsule.halfAxis, axis = capsule.halfAxis * 2.0f;
    if (!isFinite(s0) || !isFinite(axis)) return 0;
    const float reach = radius + margin;
    const float h0 = dot(faceN, s0), h1 = dot(faceN, s0 + axis);
    // The quick rejections below only ever refuse what the exact test further down refuses too: a caller that has
    // found the triangle in reach already skips them.
    if (!inReach && beyondReach(h0, h1, reach, 1.0f)) return 0;
    for (int e = 0; e < 3 && !inReach; ++e) {
        const Vec3 edge = v[e == 2 ? 0 : e + 1] - v[e], side = cross(edge, faceN);  // outward, |side| = |edge|
        const float f0 = dot(side, s0 - v[e]), f1 = dot(side, s0 + axis - v[e]);
        if (f0 > 0 && f1 > 0 && beyondReach(f0, f1, reach, dot(edge, edge))) return 0;
        // Segment x edge: the whole segment projects to one point, the triangle to [min(0, w), max(0, w)] (w: the
        // opposite vertex; the edge's own two project to 0).
        const Vec3 across = cross(axis, edge);
        const float w = dot(across, v[e == 0 ? 2 : e - 1] - v[e]), at = dot(across, s0 - v[e]);
        const float gap = at > 0 ? at - std::max(w, 0.0f) : std::min(w, 0.0f) - at;
        if (gap > 0 && beyondReach(gap, gap, reach, dot(across, across))) return 0;
    }

    // Closest pair: both ends against the triangle, the segment against the edges, the segment through the face.
    struct Pair {
        float dist2 = INFINITY;
        float t = 0;      // segment parameter
        Vec3 onTriangle;  // closest point on the triangle
        int segment = 0;  // 0 interior, 1 start, 2 end
        int feature = 0;  // triangle feature code
    } best;
    auto consider = [&](float t, Vec3 onTriangle, int feature) {
        const Vec3 d = onTriangle - (s0 + axis * t);
        const float d2 = dot(d, d);
        if (d2 < best.dist2) best = {d2, t, onTriangle, t <= 0 ? 1 : (t >= 1 ? 2 : 0), feature};
    };
    for (int end = 0; end < 2; ++end) {
        const TrianglePoint q = closestOnTriangle(s0 + axis * float(end), v[0], v[1], v[2]);
        consider(float(end), q.point, q.feature);
    }
    for (int e = 0; e < 3; ++e) {
        const Vec3 a = v[e], edge = v[(e + 1) % 3] - a;
        float s, t;
        closestSegments(s0, axis, a, edge, s, t);
        consider(s, a + edge * t, t <= 0 ? featureVertex(e) : (t >= 1 ? featureVertex((e + 1) % 3) : featureEdge(e)));
    }
    if ((h0 < 0) != (h1 < 0) && h0 != h1) {
        const float t = h0 / (h0 - h1);
        const TrianglePoint q = closestOnTriangle(s0 + axis * t, v[0], v[1], v[2]);
        if (q.feature == kFeatureFace) consider(t, q.point, kFeatureFace);
    }
    if (!(best.dist2 <= reach * reach)) return 0;

    // The face counts on the side of the closest segment point, or of the centre when the segment touches it.
    const Vec3 closest = s0 + axis * best.t;
    const Vec3 sidePoint = best.dist2 <= kMinDistanceSq ? center : closest;
    const Vec3 toFace = dot(faceN, sidePoint) >= 0 ? -faceN : faceN;
    const bool useFace =
        best.feature == kFeatureFace || best.dist2 <= kMinDistanceSq || !featureActive(best.feature, activeEdges);
    const Vec3 n = useFace ? toFace : (best.onTriangle - closest) / std::sqrt(best.dist2);
    out.normal = n;

    // Lying along the face: the segment clipped to the triangle's prism gives two points.
    const float axis2 = dot(axis, axis);
    const float along = dot(axis, faceN);
    if (useFace && axis2 > kMinSegmentSq &&
        along * along < kCapsuleFaceParallelSine * kCapsuleFaceParallelSine * axis2) {
        float lo = 0, hi = 1;
        int clipLo = 0, clipHi = 0;
        bool empty = false;
        for (int e = 0; e < 3 && !empty; ++e) {
            const Vec3 side = cross(v[(e + 1) % 3] - v[e], faceN);  // outward for counter-clockwise v
            const float f0 = dot(side, s0 - v[e]), f1 = dot(side, s0 + axis - v[e]);
            if (f0 > 0 && f1 > 0)
                empty = true;
            else if (f0 > 0) {
                const float t = f0 / (f0 - f1);
                if (t > lo) lo = t, clipLo = 1 + e;
            } else if (f1 > 0) {
                const float t = f0 / (f0 - f1);
                if (t < hi) hi = t, clipHi = 1 + e;
            }
        }
        if (!empty && (hi - lo) * (hi - lo) * axis2 > kMinSegmentSq) {
            const float ts[2] = {lo, hi};
            const int clips[2] = {clipLo, clipHi};
            for (int k = 0; k < 2; ++k) {
                const Vec3 x = s0 + axis * ts[k];
                const Vec3 onPlane = x - faceN * dot(faceN, x);
                const float depth = radius + dot(x - onPlane, n);
                if (depth >= -margin) addPoint(out, origin + onPlane, depth, 0x100u | std::uint32_t(k << 4 | clips[k]));
            }
            if (out.pointCount > 0) return out.pointCount;
        }
    }
    if (best.dist2 <= kMinDistanceSq) {
        // The segment touches or crosses the triangle: push out along the face normal by the deeper end.
        const Vec3 s1 = s0 + axis;
        const int end = dot(s1, n) > dot(s0, n) ? 1 : 0;
        const Vec3 deeper = end == 1 ? s1 : s0;
        const TrianglePoint q = closestOnTriangle(deeper, v[0], v[1], v[2]);
        const Vec3 under = deeper - faceN * dot(faceN, deeper);
        addPoint(out, origin + under, radius + dot(deeper - under, n), std::uint32_t((1 + end) * 8 + q.feature));
        return 1;
    }
    const float depth = radius + dot(closest - best.onTriangle, n);
    if (depth < -margin) return 0;
    // Along the face normal the capsule touches the plane under its segment (as for the sphere): a point off that
    // line would turn a rolling capsule as it pushes.
    const Vec3 point = useFace ? closest - faceN * dot(faceN, closest) : best.onTriangle;
    addPoint(out, origin + point, depth, std::uint32_t(best.segment * 8 + best.feature));
    return 1;
}

// ---- Box --------------------------------------------------------------------------------------------------------

Mat3 rotationMatrix(Quat q) {
    const float xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    const float xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    const float wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    Mat3 m;
    m.rows[0] = {1 - 2 * (yy + zz), 2 * (xy - wz), 2 * (xz + wy)};
    m.rows[1] = {2 * (xy + wz), 1 - 2 * (xx + zz), 2 * (yz - wx)};
    m.rows[2] = {2 * (xz - wy), 2 * (yz + wx), 1 - 2 * (xx + yy)};
    return m;
}

TriangleBox triangleBox(const Transform& pose, Vec3 halfExtents) {
    TriangleBox box;
    box.pose = pose;
    box.halfExtents = halfExtents;
    box.toWorld = rotationMatrix(pose.rotation);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) box.toBox(r, c) = box.toWorld(c, r);
    return box;
}

int collideBoxTriangle(const Transform& boxPose, Vec3 halfExtents, const TriangleVertices& tri,
                       std::uint8_t activeEdges, float margin, Manifold& out) {
    return collideBoxTriangle(triangleBox(boxPose, halfExtents), tri, activeEdges, margin, out);
}

namespace {

/// The box-triangle SAT of collideBoxTriangle, written once over the lane type (simd/): one triangle per lane, world
/// vertices in. Every lane runs every axis (a lane found apart stays apart); the float form exits as soon as its
/// triangle is apart, the wide form when all its lanes are. Both round as each other (simd.h), so boxTriangleAxes and
/// collideBoxTriangle make the same choice.
template <class F>
struct BoxSat {
    simd::MaskOf<F> contact;   ///< finite, not degenerate, and no axis separates beyond the margin
    F kind, boxAxis, triEdge;  ///< BoxTriangleAxis codes, as floats
    simd::Vec3W<F> n;
    simd::Vec3W<F> t[3];  ///< the triangle in the box frame
    simd::Vec3W<F> faceN;
};

template <class F>
simd::Vec3W<F> wide(Vec3 v) {
    return simd::Vec3W<F>::broadcast(v.x, v.y, v.z);
}

template <class F>
BoxSat<F> boxTriangleSat(const TriangleBox& box, const simd::Vec3W<F> (&tri)[3], float margin) {
    using simd::andMask;
    using simd::notMask;
    using simd::orMask;
    using simd::select;
    using V = simd::Vec3W<F>;
    const F zero(0.0f), one(1.0f);
    BoxSat<F> r{simd::MaskOf<F>(false), zero, zero, zero, V::zero(), {}, V::zero()};
    // Box frame, relative to the box centre (as toBox * (v - position)).
    const V position = wide<F>(box.pose.position);
    const V rows[3] = {wide<F>(box.toBox.rows[0]), wide<F>(box.toBox.rows[1]), wide<F>(box.toBox.rows[2])};
    V t[3];
    for (int k = 0; k < 3; ++k) {
        const V d = tri[k] - position;
        t[k] = {dot(rows[0], d), dot(rows[1], d), dot(rows[2], d)};
    }
    // faceNormal, lane-wise.
    const V ab = t[1] - t[0], ac = t[2] - t[0], bc = ac - ab;
    const V cr = cross(ab, ac);
    const F longest = simd::max(simd::max(dot(ab, ab), dot(ac, ac)), dot(bc, bc));
    const F n2 = dot(cr, cr);
    simd::MaskOf<F> live =
        andMask(n2 > F(kDegenerateAreaSq) * longest * longest, andMask(simd::isFinite(n2), simd::isFinite(longest)));
    live = andMask(live, simd::isFinite(t[0]));
    const V faceN = cr * (one / simd::sqrt(n2));
    r.t[0] = t[0], r.t[1] = t[1], r.t[2] = t[2], r.faceN = faceN;
    const Vec3 hs = box.halfExtents;
    const V h = wide<F>(hs);
    auto boxRadius = [&](const V& L) { return simd::abs(L.x) * h.x + simd::abs(L.y) * h.y + simd::abs(L.z) * h.z; };
    // The triangle face on the side of the box centre (two-sided triangles), first: it separates most triangles.
    const V toFace = select(dot(faceN, -t[0]) >= zero, -faceN, faceN);
    F best = dot(toFace, t[0]) - boxRadius(toFace);
    const F marginW(margin);
    live = andMask(live, notMask(best > marginW));
    if (simd::none(live)) return r;
    const V edges[3] = {t[1] - t[0], t[2] - t[1], t[0] - t[2]};
    const F size = simd::max(
        simd::max(simd::max(h.x, h.y), h.z),
        simd::sqrt(simd::max(simd::max(dot(edges[0], edges[0]), dot(edges[1], edges[1])), dot(edges[2], edges[2]))));
    V n = toFace;
    F kind = zero, boxAxis = zero, triEdge = zero;
    auto threshold = [&] {
        return best + F(kAxisRelativeTolerance) * simd::abs(best) + F(kAxisAbsoluteTolerance) * size;
    };
    const F hk[3] = {h.x, h.y, h.z};
    for (int k = 0; k < 3; ++k) {
        const F p0 = k == 0 ? t[0].x : (k == 1 ? t[0].y : t[0].z);
        const F p1 = k == 0 ? t[1].x : (k == 1 ? t[1].y : t[1].z);
        const F p2 = k == 0 ? t[2].x : (k == 1 ? t[2].y : t[2].z);
        const F pos = simd::min(simd::min(p0, p1), p2) - hk[k], neg = -simd::max(simd::max(p0, p1), p2) - hk[k];
        const F sep = simd::max(pos, neg);
        live = andMask(live, notMask(sep > marginW));
        if (simd::none(live)) return r;
        const simd::MaskOf<F> take = sep > threshold();
        const F sign = select(pos >= neg, one, -one);
        const V axis{k == 0 ? sign : zero, k == 1 ? sign : zero, k == 2 ? sign : zero};
        best = select(take, sep, best);
        n = select(take, axis, n);
        kind = select(take, one, kind);
        boxAxis = select(take, F(float(k)), boxAxis);
    }
    // Of an edge axis only the direction in which triangle edge j is the triangle's support towards the box can be
    // the contact's (see collideBoxTriangle); tested unnormalised, only a winner is normalised.
    V sides[3];
    for (int j = 0; j < 3; ++j) sides[j] = cross(edges[j], faceN);
    const F parallel2(kTriangleEdgeParallelEpsilon * kTriangleEdgeParallelEpsilon);
    // num / sqrt(len2) > limit without the square root (the scalar `exceeds`).
    auto exceeds = [&](const F& num, const F& limit, const F& len2) {
        const F lhs = num * num, rhs = limit * limit * len2;
        if constexpr (std::is_same_v<F, float>)  // one triangle: branch (both forms give the same answer)
            return limit >= 0 ? num > 0 && lhs > rhs : num >= 0 || lhs < rhs;
        const simd::MaskOf<F> nonNegative = limit >= zero;
        return orMask(andMask(nonNegative, andMask(num > zero, lhs > rhs)),
                      andMask(notMask(nonNegative), orMask(num >= zero, lhs < rhs)));
    };
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            const V e = edges[j];
            const V L = i == 0 ? V{zero, -e.z, e.y} : (i == 1 ? V{e.z, zero, -e.x} : V{-e.y, e.x, zero});
            const F len2 = dot(L, L);
            const simd::MaskOf<F> tested = notMask(len2 <= parallel2 * dot(e, e));
            const F p0 = dot(L, t[0]), p1 = dot(L, t[1]), p2 = dot(L, t[2]);
            const F radius = boxRadius(L);
            const F pos = simd::min(simd::min(p0, p1), p2) - radius, neg = -simd::max(simd::max(p0, p1), p2) - radius;
            live = andMask(live, notMask(andMask(tested, exceeds(simd::max(pos, neg), marginW, len2))));
            if (simd::none(live)) return r;
            const F side = dot(L, sides[j]);
            const F sepU = select(side < zero, pos, neg);
            const simd::MaskOf<F> take =
                andMask(andMask(tested, notMask(side == zero)), exceeds(sepU, threshold(), len2));
            if (simd::none(take)) continue;  // the square root only for a lane whose axis wins
            const F inv = one / simd::sqrt(len2);
            best = select(take, sepU * inv, best);
            n = select(take, select(side < zero, L, -L) * inv, n);
            kind = select(take, F(2.0f), kind);
            boxAxis = select(take, F(float(i)), boxAxis);
            triEdge = select(take, F(float(j)), triEdge);
        }
    }
    r.contact = live;
    r.kind = kind, r.boxAxis = boxAxis, r.triEdge = triEdge, r.n = n;
    return r;
}

BoxTriangleAxis axisOfLane(const BoxSat<float>& sat) {
    BoxTriangleAxis axis;
    if (!sat.contact) return axis;
    axis.kind = static_cast<int>(sat.kind), axis.boxAxis = static_cast<int>(sat.boxAxis);
    axis.triEdge = static_cast<int>(sat.triEdge), axis.n = {sat.n.x, sat.n.y, sat.n.z};
    return axis;
}

template <class F>
void boxTriangleAxesAt(const TriangleBox& box, float margin, const TriangleLanes& tris, std::size_t i,
                       BoxTriangleAxis* out) {
    simd::Vec3W<F> v[3];
    for (int k = 0; k < 3; ++k) v[k] = simd::Vec3W<F>::load(tris.x[k], tris.y[k], tris.z[k], i);
    const BoxSat<F> sat = boxTriangleSat<F>(box, v, margin);
    for (std::size_t lane = 0; lane < simd::lanesOf<F>; ++lane) {
        BoxSat<float> one{simd::lane(sat.contact, lane),
                          simd::lane(sat.kind, lane),
                          simd::lane(sat.boxAxis, lane),
                          simd::lane(sat.triEdge, lane),
                          {simd::lane(sat.n.x, lane), simd::lane(sat.n.y, lane), simd::lane(sat.n.z, lane)}};
        out[i + lane] = axisOfLane(one);
    }
}

void boxTriangleAxesRun(const TriangleBox& box, float margin, const TriangleLanes& tris, std::size_t n,
                        BoxTriangleAxis* out, bool wide) {
    if (!isFinite(box.halfExtents)) {  // the kernel refuses such a box: no contacts
        std::fill(out, out + (wide ? triangleLanesPadded(n) : n), BoxTriangleAxis{});
        return;
    }
    if (wide)
        for (std::size_t i = 0; i < n; i += simd::kLanes) boxTriangleAxesAt<simd::FloatW>(box, margin, tris, i, out);
    else
        for (std::size_t i = 0; i < n; ++i) boxTriangleAxesAt<float>(box, margin, tris, i, out);
}

}  // namespace

std::size_t triangleLanesPadded(std::size_t n) { return simd::roundUpToLanes<simd::FloatW>(n); }

void boxTriangleAxes(const TriangleBox& box, float margin, const TriangleLanes& tris, std::size_t n,
                     BoxTriangleAxis* out) {
    boxTriangleAxesRun(box, margin, tris, n, out, true);
}
void boxTriangleAxesScalar(const TriangleBox& box, float margin, const TriangleLanes& tris, std::size_t n,
                           BoxTriangleAxis* out) {
    boxTriangleAxesRun(box, margin, tris, n, out, false);
}

namespace {

int boxTriangleContacts(const TriangleBox& box, const Vec3 (&t)[3], Vec3 faceN, const BoxTriangleAxis& axis,
                        std::uint8_t activeEdges, float margin, Manifold& out);

Vec3 narrow(const simd::Vec3W<float>& v) { return {v.x, v.y, v.z}; }

}  // namespace

int collideBoxTriangle(const TriangleBox& box, const TriangleVertices& tri, std::uint8_t activeEdges, float margin,
                       Manifold& out) {
    out.pointCount = 0;
    if (!isFinite(box.halfExtents)) return 0;
    const simd::Vec3W<float> v[3] = {
        {tri[0].x, tri[0].y, tri[0].z}, {tri[1].x, tri[1].y, tri[1].z}, {tri[2].x, tri[2].y, tri[2].z}};
    const BoxSat<float> sat = boxTriangleSat<float>(box, v, margin);
    const BoxTriangleAxis axis = axisOfLane(sat);
    if (axis.kind < 0) return 0;
    const Vec3 t[3] = {narrow(sat.t[0]), narrow(sat.t[1]), narrow(sat.t[2])};
    return boxTriangleContacts(box, t, narrow(sat.faceN), axis, activeEdges, margin, out);
}

int collideBoxTriangle(const TriangleBox& box, const TriangleVertices& tri, std::uint8_t activeEdges, float margin,
                       const BoxTriangleAxis& axis, Manifold& out) {
    out.pointCount = 0;
    if (axis.kind < 0) return 0;
    // The frame and normal the SAT worked with, computed as it does (so the same to the last bit).
    const Vec3 t[3] = {box.toBox * (tri[0] - box.pose.position), box.toBox * (tri[1] - box.pose.position),
                       box.toBox * (tri[2] - box.pose.position)};
    Vec3 faceN;
    if (!faceNormal(t[1] - t[0], t[2] - t[0], faceN)) return 0;
    return boxTriangleContacts(box, t, faceN, axis, activeEdges, margin, out);
}

namespace {

/// The box kernel after its SAT: the ghost rule, then the clipped contacts.
int boxTriangleContacts(const TriangleBox& box, const Vec3 (&t)[3], Vec3 faceN, const BoxTriangleAxis& axis,
                        std::uint8_t activeEdges, float margin, Manifold& out) {
    const Vec3 h = box.halfExtents;
    enum class Axis { TriangleFace, BoxFace, EdgeEdge };
    Axis kind = axis.kind == 0 ? Axis::TriangleFace : (axis.kind == 1 ? Axis::BoxFace : Axis::EdgeEdge);
    const int boxAxis = axis.boxAxis, triEdge = axis.triEdge;
    const Vec3 toFace = dot(faceN, -t[0]) >= 0 ? -faceN : faceN;
    const Vec3 edges[3] = {t[1] - t[0], t[2] - t[1], t[0] - t[2]};
    const float size =
        std::max({h.x, h.y, h.z,
                  std::sqrt(std::max({dot(edges[0], edges[0]), dot(edges[1], edges[1]), dot(edges[2], edges[2])}))});
    Vec3 sides[3];
    for (int j = 0; j < 3; ++j) sides[j] = cross(edges[j], faceN);  // outward: t is counter-clockwise about faceN
    Vec3 n = axis.n;

    // Ghost rule: the triangle feature the contact lies on must be active to keep a non-face normal.
    if (kind != Axis::TriangleFace) {
        const int feature = kind == Axis::BoxFace ? featureAlong(t, n, kFeatureTolerance * size) : featureEdge(triEdge);
        if (!featureActive(feature, activeEdges)) kind = Axis::TriangleFace, n = toFace;
    }

    const bool ruled = kind == Axis::TriangleFace && axis.kind != 0;  // the ghost rule chose the face normal
    bool offFace = false;
    Scratch& sc = scratch();
    Candidates& cands = sc.cands;
    cands.count = 0;
    if (kind == Axis::TriangleFace) {
        // Incident box face: the one facing the triangle; clipped by the triangle's side planes.
        const float nc[3] = {n.x, n.y, n.z};
        int k = 0;
        for (int i = 1; i < 3; ++i)
            if (std::abs(nc[i]) > std::abs(nc[k])) k = i;
        const float s = nc[k] < 0 ? -1.0f : 1.0f;
        const int u = (k + 1) % 3, w = (k + 2) % 3;
        const float hk = component(h, k), hu = component(h, u), hw = component(h, w);
        ClipVertex* poly = sc.poly;
        poly[0] = {withComponents(k, s * hk, u, hu, w, hw), 0, 0};
        poly[1] = {withComponents(k, s * hk, u, -hu, w, hw), 1, 1};
        poly[2] = {withComponents(k, s * hk, u, -hu, w, -hw), 2, 2};
        poly[3] = {withComponents(k, s * hk, u, hu, w, -hw), 3, 3};
        float offsets[3];
        for (int e = 0; e < 3; ++e) offsets[e] = dot(sides[e], t[e]);
        int m = 4;
        const ClipVertex* clipped = clipAgainst(poly, m, sides, offsets, 3);
        const std::uint32_t face = std::uint32_t(2 * k + (s < 0 ? 1 : 0));
        for (int i = 0; i < m; ++i) {
            const float depth = dot(clipped[i].p - t[0], n);
            if (depth >= -margin) cands.add(clipped[i].p - n * depth, depth, face << 16 | clipped[i].id);
        }
        if (cands.count == 0) {
            // The face lies beside the triangle while a corner reaches it: that corner (the deepest) alone.
            const float su = component(n, u) < 0 ? -1.0f : 1.0f, sw = component(n, w) < 0 ? -1.0f : 1.0f;
            const Vec3 corner = withComponents(k, s * hk, u, su * hu, w, sw * hw);
            const float depth = dot(corner - t[0], n);
            const std::uint32_t id = su > 0 ? (sw > 0 ? 0u : 3u) : (sw > 0 ? 1u : 2u);
            if (depth >= -margin) cands.add(closestOnTriangle(corner, t[0], t[1], t[2]).point, depth, face << 16 | id);
            offFace = true;
        }
    } else if (kind == Axis::BoxFace) {
        // Reference face of the box: the triangle clipped to the face's four side planes.
        const int k = boxAxis, u = (k + 1) % 3, w = (k + 2) % 3;
        const float s = component(n, k) < 0 ? -1.0f : 1.0f;
        ClipVertex* poly = sc.poly;
        for (int i = 0; i < 3; ++i) poly[i] = {t[i], std::uint16_t(i), std::uint16_t(i)};
        const Vec3 planes[4] = {axisVector(u, 1), axisVector(u, -1), axisVector(w, 1), axisVector(w, -1)};
        const float offsets[4] = {component(h, u), component(h, u), component(h, w), component(h, w)};
        int m = 3;
        const ClipVertex* clipped = clipAgainst(poly, m, planes, offsets, 4);
        const std::uint32_t face = std::uint32_t(2 * k + (s < 0 ? 1 : 0));
        for (int i = 0; i < m; ++i) {
            const float depth = component(h, k) - s * component(clipped[i].p, k);
            if (depth >= -margin) cands.add(clipped[i].p, depth, 1u << 30 | face << 16 | clipped[i].id);
        }
        if (cands.count == 0) {
            // The triangle lies beside the face while one of its vertices reaches it: that vertex (the deepest).
            int d = 0;
            for (int i = 1; i < 3; ++i)
                if (dot(n, t[i]) < dot(n, t[d])) d = i;
            const float depth = component(h, k) - s * component(t[d], k);
            if (depth >= -margin) cands.add(t[d], depth, 1u << 30 | face << 16 | std::uint32_t(d));
            offFace = true;
        }
    } else {
        // Edge-edge: the box edge along boxAxis farthest along n against triangle edge triEdge.
        const int i = boxAxis, u = (i + 1) % 3, w = (i + 2) % 3;
        const float su = component(n, u) < 0 ? -1.0f : 1.0f, sw = component(n, w) < 0 ? -1.0f : 1.0f;
        const float hi = component(h, i);
        const Vec3 boxStart = withComponents(i, -hi, u, su * component(h, u), w, sw * component(h, w));
        const Vec3 boxDir = axisVector(i, 2 * hi);
        float sb, st;
        closestSegments(boxStart, boxDir, t[triEdge], edges[triEdge], sb, st);
        const Vec3 onBox = boxStart + boxDir * sb, onTri = t[triEdge] + edges[triEdge] * st;
        const float depth = dot(onBox - onTri, n);
        const std::uint32_t boxEdge = std::uint32_t(4 * i + (su < 0 ? 1 : 0) + (sw < 0 ? 2 : 0));
        if (depth >= -margin) cands.add(onTri, depth, 2u << 30 | boxEdge << 8 | std::uint32_t(triEdge));
        offFace = clampedToAnEnd(sb, st);
    }
    if (!ruled && allApart(cands)) {
        const float separation = std::min({dot(n, t[0]), dot(n, t[1]), dot(n, t[2])}) -
                                 (std::abs(n.x) * h.x + std::abs(n.y) * h.y + std::abs(n.z) * h.z);
        GjkShape body;
        body.core = GjkShape::Core::Box;
        body.halfExtents = h;
        closestPointsInstead(body, t, activeEdges, margin, size, {separation, offFace}, cands, n, [&](Vec3 p) {
            return std::uint32_t((p.x > 0 ? 1 : 0) | (p.y > 0 ? 2 : 0) | (p.z > 0 ? 4 : 0));
        });
    }
    if (cands.count == 0) return 0;
    return emitReduced(cands, n, box, out);
}

}  // namespace

// ---- Hull -------------------------------------------------------------------------------------------------------

int collideHullTriangle(const ConvexHull& hull, const HullAdjacency& adjacency, const Transform& hullPose,
                        const TriangleVertices& tri, std::uint8_t activeEdges, float margin, Manifold& out) {
    out.pointCount = 0;
    // Hull frame, relative to the hull's origin.
    const Quat inv = conjugate(hullPose.rotation);
    const Vec3 t[3] = {rotate(inv, tri[0] - hullPose.position), rotate(inv, tri[1] - hullPose.position),
                       rotate(inv, tri[2] - hullPose.position)};
    Vec3 faceN;
    if (!faceNormal(t[1] - t[0], t[2] - t[0], faceN)) return 0;
    if (!isFinite(t[0]) || !isFinite(t[1]) || !isFinite(t[2])) return 0;
    const Vec3* V = hull.vertices.data();
    const int vertexCount = static_cast<int>(hull.vertices.size());
    const Vec3* N = hull.faceNormals.data();
    const float* offsets = hull.faceOffsets.data();
    const int faceCount = static_cast<int>(hull.faceNormals.size());
    const int edgeCount = static_cast<int>(adjacency.edges.size());
    if (vertexCount == 0 || faceCount == 0) return 0;
    const Vec3 edges[3] = {t[1] - t[0], t[2] - t[1], t[0] - t[2]};
    const float size =
        std::max(adjacency.size,
                 std::sqrt(std::max({dot(edges[0], edges[0]), dot(edges[1], edges[1]), dot(edges[2], edges[2])})));
    auto support = [&](Vec3 d) {  // index of the hull vertex farthest along d
        int best = 0;
        float hi = dot(d, V[0]);
        for (int i = 1; i < vertexCount; ++i) {
            const float x = dot(d, V[i]);
            if (x > hi) hi = x, best = i;
        }
        return best;
    };

    // Each family's best axis, then the hysteresis of hull_pairs.h between families (not within one, where it
    // would only make the choice depend on the hull's face and edge order): the triangle face, a hull face only if
    // clearly better, an edge pair only if clearly better than the chosen face.
    // The triangle face counts on the side of the hull's centre (two-sided triangles).
    const Vec3 toFace = dot(faceN, adjacency.interior - t[0]) >= 0 ? -faceN : faceN;
    const int deepestOnFace = support(toFace);
    const float sepT = dot(toFace, t[0] - V[deepestOnFace]);
    if (sepT > margin) return 0;
    // Face axes of the hull: the lowest triangle vertex above the face plane.
    float sepH = -INFINITY;
    int hullFace = 0;
    for (int f = 0; f < faceCount; ++f) {
        const float sep = std::min({dot(N[f], t[0]), dot(N[f], t[1]), dot(N[f], t[2])}) - offsets[f];
        if (sep > margin) return 0;
        if (sep > sepH) sepH = sep, hullFace = f;
    }
    // Edge pairs. The triangle's Gauss map (negated for the Minkowski difference hull - triangle) joins -n and n, for
    // edge j, by the half circle orthogonal to e_j through -s_j, s_j its outward side direction. Hull edge arc (a, b)
    // crosses that great circle where dot(x, e_j) = 0, at x ~ |be| a + |ae| b (ae = dot(a, e_j), be = dot(b, e_j) of
    // opposite signs); the pair makes a face of the difference when that point is on the -s_j half.
    Vec3 sides[3];
    for (int j = 0; j < 3; ++j) sides[j] = cross(edges[j], faceN);  // outward: t is counter-clockwise about faceN
    Scratch& sc = scratch();
    std::vector<float>& faceDots = sc.faceDots;  // per hull face: dot with e_0..e_2, then with s_0..s_2
    if (faceDots.size() < 6 * static_cast<std::size_t>(faceCount))
        faceDots.resize(6 * static_cast<std::size_t>(faceCount));
    for (int f = 0; f < faceCount; ++f) {
        float* d = &faceDots[6 * static_cast<std::size_t>(f)];
        for (int j = 0; j < 3; ++j) d[j] = dot(N[f], edges[j]), d[3 + j] = dot(N[f], sides[j]);
    }
    constexpr float kParallel2 = kTriangleEdgeParallelEpsilon * kTriangleEdgeParallelEpsilon;
    float sepE = -INFINITY;
    int hullEdge = -1, triEdge = 0;
    Vec3 axisE{};
    for (int i = 0; i < edgeCount; ++i) {
        const HullEdge& e = adjacency.edges[i];
        const float* da = &faceDots[6 * static_cast<std::size_t>(e.face0)];
        const float* db = &faceDots[6 * static_cast<std::size_t>(e.face1)];
        const Vec3 p = V[e.v0], d = V[e.v1] - p;
        for (int j = 0; j < 3; ++j) {
            const float ae = da[j], be = db[j];
            if (!(ae * be < 0) || !(std::abs(be) * da[3 + j] + std::abs(ae) * db[3 + j] < 0)) continue;
            Vec3 L = cross(d, edges[j]);
            const float len2 = dot(L, L);
            if (len2 <= kParallel2 * dot(d, d) * dot(edges[j], edges[j])) continue;
            if (dot(L, p - adjacency.interior) < 0) L = -L;  // outward from the hull, i.e. towards the triangle
            L = L / std::sqrt(len2);
            const float sep = dot(L, t[j] - p);
            if (sep > margin) return 0;
            if (sep > sepE) sepE = sep, hullEdge = i, triEdge = j, axisE = L;
        }
    }
    auto clearlyBetter = [&](float candidate, float current) {
        return candidate > current + kAxisRelativeTolerance * std::abs(current) + kAxisAbsoluteTolerance * size;
    };
    enum class Axis { TriangleFace, HullFace, EdgeEdge };
    Axis kind = Axis::TriangleFace;
    float best = sepT;
    Vec3 n = toFace;
    if (clearlyBetter(sepH, best)) kind = Axis::HullFace, best = sepH, n = N[hullFace];
    if (hullEdge >= 0 && clearlyBetter(sepE, best)) kind = Axis::EdgeEdge, n = axisE;

    // Ghost rule: the triangle feature the contact lies on must be active to keep a non-face normal.
    bool ruled = false;
    if (kind != Axis::TriangleFace) {
        const int feature =
            kind == Axis::HullFace ? featureAlong(t, n, kFeatureTolerance * size) : featureEdge(triEdge);
        if (!featureActive(feature, activeEdges)) kind = Axis::TriangleFace, n = toFace, ruled = true;
    }

    bool offFace = false;
    Candidates& cands = sc.cands;
    cands.count = 0;
    if (kind == Axis::TriangleFace) {
        // Incident face: among the faces through the deepest vertex, the most aligned with n (the most aligned face
        // overall can lie beside the triangle on general hulls); clipped by the triangle's side planes.
        int fi = -1;
        std::uint32_t deepestIndex = 0x7FFF;
        float align = -INFINITY;
        for (int f = 0; f < faceCount; ++f) {
            const float c = dot(N[f], n);
            if (c <= align) continue;
            for (std::uint32_t k = hull.faceStart[f]; k < hull.faceStart[f + 1]; ++k)
                if (hull.faceVertices[k] == static_cast<std::uint32_t>(deepestOnFace)) {
                    align = c, fi = f, deepestIndex = k - hull.faceStart[f];
                    break;
                }
        }
        if (fi < 0) fi = 0;  // only for a malformed hull whose support vertex is on no face
        ClipVertex* poly = sc.poly;
        int m = 0;
        for (std::uint32_t k = hull.faceStart[fi]; k < hull.faceStart[fi + 1] && m < kClipCapacity; ++k, ++m)
            poly[m] = {V[hull.faceVertices[k]], static_cast<std::uint16_t>(m), static_cast<std::uint16_t>(m)};
        float sideOffsets[3];
        for (int j = 0; j < 3; ++j) sideOffsets[j] = dot(sides[j], t[j]) + kClipSlack * size * length(sides[j]);
        const ClipVertex* clipped = clipAgainst(poly, m, sides, sideOffsets, 3);
        const std::uint32_t face = (static_cast<std::uint32_t>(fi) & 0x3FFFu) << 16;
        for (int k = 0; k < m; ++k) {
            const float depth = dot(clipped[k].p - t[0], n);
            if (depth >= -margin) cands.add(clipped[k].p - n * depth, depth, face | clipped[k].id);
        }
        if (cands.count == 0) {
            // Nothing of the face lies over the triangle within the margin while the hull reaches it: the deepest
            // vertex alone, over its closest triangle point (the SAT put it within the margin of the plane).
            const Vec3 v = V[deepestOnFace];
            const float depth = dot(v - t[0], n);
            if (depth >= -margin) cands.add(closestOnTriangle(v, t[0], t[1], t[2]).point, depth, face | deepestIndex);
            offFace = true;
        }
    } else if (kind == Axis::HullFace) {
        // Reference face of the hull: the triangle clipped to the face's side planes.
        const std::uint32_t s0 = hull.faceStart[hullFace], s1 = hull.faceStart[hullFace + 1];
        const int planes = std::min(static_cast<int>(s1 - s0), kClipCapacity);
        Vec3* normals = sc.planeNormals;
        float* planeOffsets = sc.planeOffsets;
        for (int k = 0; k < planes; ++k) {
            const std::uint32_t at = s0 + static_cast<std::uint32_t>(k);
            const Vec3 p0 = V[hull.faceVertices[at]], p1 = V[hull.faceVertices[at + 1 == s1 ? s0 : at + 1]];
            normals[k] = cross(p1 - p0, n);  // outward: hull faces are counter-clockwise from outside
            planeOffsets[k] = dot(normals[k], p0) + kClipSlack * size * length(normals[k]);
        }
        ClipVertex* poly = sc.poly;
        for (int i = 0; i < 3; ++i) poly[i] = {t[i], std::uint16_t(i), std::uint16_t(i)};
        int m = 3;
        const ClipVertex* clipped = clipAgainst(poly, m, normals, planeOffsets, planes);
        const std::uint32_t face = 1u << 30 | (static_cast<std::uint32_t>(hullFace) & 0x3FFFu) << 16;
        for (int k = 0; k < m; ++k) {
            const float depth = offsets[hullFace] - dot(n, clipped[k].p);
            if (depth >= -margin) cands.add(clipped[k].p, depth, face | clipped[k].id);
        }
        if (cands.count == 0) {
            // The triangle lies beside the face while one of its vertices reaches it: that vertex (the deepest).
            int d = 0;
            for (int i = 1; i < 3; ++i)
                if (dot(n, t[i]) < dot(n, t[d])) d = i;
            const float depth = offsets[hullFace] - dot(n, t[d]);
            if (depth >= -margin) cands.add(t[d], depth, face | std::uint32_t(d));
            offFace = true;
        }
    } else {
        // Edge-edge: one point, the closest points of the two edges. Both edges are orthogonal to n, so its depth is
        // the SAT's whatever the clamping: the pair never drops out here.
        const HullEdge& e = adjacency.edges[hullEdge];
        const Vec3 p = V[e.v0], d = V[e.v1] - p;
        float sh, st;
        closestSegments(p, d, t[triEdge], edges[triEdge], sh, st);
        const Vec3 onTri = t[triEdge] + edges[triEdge] * st;
        const float depth = dot(p + d * sh - onTri, n);
        const std::uint32_t id = 2u << 30 | (static_cast<std::uint32_t>(hullEdge) & 0xFFFFFFFu) << 2;
        if (depth >= -margin) cands.add(onTri, depth, id | static_cast<std::uint32_t>(triEdge));
        offFace = clampedToAnEnd(sh, st);
    }
    if (!ruled && allApart(cands)) {
        const float separation = std::min({dot(n, t[0]), dot(n, t[1]), dot(n, t[2])}) - dot(n, V[support(n)]);
        GjkShape body;
        body.core = GjkShape::Core::Points;
        body.points = V;
        body.pointCount = static_cast<std::uint32_t>(vertexCount);
        closestPointsInstead(body, t, activeEdges, margin, size, {separation, offFace}, cands, n, [&](Vec3 p) {
            std::uint32_t nearest = 0;
            float nearestSq = INFINITY;
            for (int i = 0; i < vertexCount; ++i)
                if (const float d2 = dot(V[i] - p, V[i] - p); d2 < nearestSq)
                    nearestSq = d2, nearest = std::uint32_t(i);
            return nearest;
        });
    }
    if (cands.count == 0) return 0;
    mergeNearDuplicates(cands, kMergeDistance * size);
    return emitReduced(cands, n, hullPose, out);
}

}  // namespace rubble::detail
