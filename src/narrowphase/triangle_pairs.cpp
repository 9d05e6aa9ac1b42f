// Sphere-, capsule- and box-triangle contact kernels; the rules and feature ids are documented in the header.
#include "narrowphase/triangle_pairs.h"

#include <algorithm>
#include <cmath>

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
/// ... plus this fraction of the size (largest box half extent or triangle edge).
constexpr float kAxisAbsoluteTolerance = 1e-4f;
/// Triangle vertices within this fraction of the size of the deepest one along the normal share its feature.
constexpr float kFeatureTolerance = 1e-4f;

constexpr int kFeatureFace = 0;
constexpr int featureEdge(int e) { return 1 + e; }
constexpr int featureVertex(int v) { return 4 + v; }

/// Unit normal of triangle (0, ab, ac), counter-clockwise; false for (nearly) zero-area or non-finite triangles.
bool faceNormal(Vec3 ab, Vec3 ac, Vec3& normal) {
    const Vec3 n = cross(ab, ac);
    const Vec3 bc = ac - ab;
    const float longest = std::max({dot(ab, ab), dot(ac, ac), dot(bc, bc)});
    const float n2 = dot(n, n);
    if (!(n2 > kDegenerateAreaSq * longest * longest) || !std::isfinite(n2) || !std::isfinite(longest)) return false;
    normal = n / std::sqrt(n2);
    return true;
}

/// The ghost rule: may a contact on `feature` keep a normal other than the face normal?
bool featureActive(int feature, std::uint8_t activeEdges) {
    if (feature == kFeatureFace) return true;
    if (feature < 4) return ((activeEdges >> (feature - 1)) & 1u) != 0;
    const int v = feature - 4;  // vertex v ends edge v - 1 and starts edge v
    return ((activeEdges >> v) & 1u) != 0 || ((activeEdges >> ((v + 2) % 3)) & 1u) != 0;
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

// ---- Polygon clipping with feature tracking ---------------------------------------------------------------------

constexpr int kMaxClip = 8;  // a quad or triangle clipped by at most 4 planes has at most 7 vertices

struct ClipVertex {
    Vec3 p;
    std::uint8_t id;    ///< point feature (see header)
    std::uint8_t edge;  ///< tag of the polygon edge from this vertex to the next
};

/// Sutherland-Hodgman against dot(normal, x) <= offset. A crossing vertex gets id 0x20 | edge << 2 | plane; the
/// polygon edge along the plane gets `planeTag`.
int clipPolygon(const ClipVertex* in, int n, Vec3 normal, float offset, int plane, std::uint8_t planeTag,
                ClipVertex* out) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const ClipVertex& a = in[i];
        const ClipVertex& b = in[(i + 1) % n];
        const float da = dot(normal, a.p) - offset, db = dot(normal, b.p) - offset;
        if (da <= 0) out[m++] = a;
        if ((da <= 0) != (db <= 0)) {
            const float t = da / (da - db);
            out[m++] = {a.p + (b.p - a.p) * t, std::uint8_t(0x20 | (a.edge << 2) | plane), da <= 0 ? planeTag : a.edge};
        }
    }
    return m;
}

struct Candidate {
    Vec3 position;  // on the triangle, box frame
    float depth;
    std::uint32_t feature;
};

/// Keeps at most 4 of `n` candidates: the deepest, the farthest from it, then the two that span the largest
/// areas on either side of their line (Box2D / Bullet style manifold reduction).
int reduceToFour(Candidate* c, int n, Vec3 normal) {
    if (n <= 4) return n;
    int i0 = 0;
    for (int i = 1; i < n; ++i)
        if (c[i].depth > c[i0].depth) i0 = i;
    int i1 = -1;
    float far = -1;
    for (int i = 0; i < n; ++i) {
        const Vec3 d = c[i].position - c[i0].position;
        if (i != i0 && dot(d, d) > far) far = dot(d, d), i1 = i;
    }
    int i2 = -1, i3 = -1;
    float most = -INFINITY, least = INFINITY;
    const Vec3 base = c[i1].position - c[i0].position;
    for (int i = 0; i < n; ++i) {
        if (i == i0 || i == i1) continue;
        const float area = dot(cross(base, c[i].position - c[i0].position), normal);
        if (area > most) most = area, i2 = i;
        if (area < least) least = area, i3 = i;
    }
    if (i3 == i2) {  // only possible with a single remaining candidate
        for (int i = 0; i < n; ++i)
            if (i != i0 && i != i1 && i != i2) i3 = i;
    }
    const Candidate kept[4] = {c[i0], c[i1], c[i2], c[i3]};
    for (int i = 0; i < 4; ++i) c[i] = kept[i];
    return 4;
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
    const TrianglePoint q = closestOnTriangle(p, {}, b, c);
    const Vec3 d = q.point - p;
    const float dist2 = dot(d, d), reach = radius + margin;
    if (!(dist2 <= reach * reach)) return 0;  // also refuses NaN
    // Body to triangle: against the face normal on the centre's side (front when the centre is in the plane).
    const Vec3 toFace = dot(faceN, p) >= 0 ? -faceN : faceN;
    const bool useFace = q.feature == kFeatureFace || dist2 <= kMinDistanceSq || !featureActive(q.feature, activeEdges);
    const Vec3 n = useFace ? toFace : d / std::sqrt(dist2);
    const float depth = radius + dot(p - q.point, n);
    if (depth < -margin) return 0;
    out.normal = n;
    addPoint(out, origin + q.point, depth, std::uint32_t(q.feature));
    return 1;
}

// ---- Capsule ----------------------------------------------------------------------------------------------------

int collideCapsuleTriangle(const CapsuleSegment& capsule, const TriangleVertices& tri, std::uint8_t activeEdges,
                           float margin, Manifold& out) {
    out.pointCount = 0;
    const Vec3 origin = tri[0];
    const Vec3 v[3] = {{}, tri[1] - origin, tri[2] - origin};
    Vec3 faceN;
    if (!faceNormal(v[1], v[2], faceN)) return 0;
    const float radius = capsule.radius;
    const Vec3 center = capsule.center - origin;
    const Vec3 s0 = center - capsule.halfAxis, axis = capsule.halfAxis * 2.0f;
    if (!isFinite(s0) || !isFinite(axis)) return 0;

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
    const float h0 = dot(faceN, s0), h1 = dot(faceN, s0 + axis);
    if ((h0 < 0) != (h1 < 0) && h0 != h1) {
        const float t = h0 / (h0 - h1);
        const TrianglePoint q = closestOnTriangle(s0 + axis * t, v[0], v[1], v[2]);
        if (q.feature == kFeatureFace) consider(t, q.point, kFeatureFace);
    }
    const float reach = radius + margin;
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
        addPoint(out, origin + q.point, radius + dot(deeper - q.point, n), std::uint32_t((1 + end) * 8 + q.feature));
        return 1;
    }
    const float depth = radius + dot(closest - best.onTriangle, n);
    if (depth < -margin) return 0;
    addPoint(out, origin + best.onTriangle, depth, std::uint32_t(best.segment * 8 + best.feature));
    return 1;
}

// ---- Box --------------------------------------------------------------------------------------------------------

int collideBoxTriangle(const Transform& boxPose, Vec3 halfExtents, const TriangleVertices& tri,
                       std::uint8_t activeEdges, float margin, Manifold& out) {
    out.pointCount = 0;
    // Box frame, relative to the box centre.
    const Quat inv = conjugate(boxPose.rotation);
    const Vec3 t[3] = {rotate(inv, tri[0] - boxPose.position), rotate(inv, tri[1] - boxPose.position),
                       rotate(inv, tri[2] - boxPose.position)};
    Vec3 faceN;
    if (!faceNormal(t[1] - t[0], t[2] - t[0], faceN)) return 0;
    if (!isFinite(t[0]) || !isFinite(halfExtents)) return 0;
    const Vec3 h = halfExtents;
    const Vec3 edges[3] = {t[1] - t[0], t[2] - t[1], t[0] - t[2]};
    const float size =
        std::max({h.x, h.y, h.z,
                  std::sqrt(std::max({dot(edges[0], edges[0]), dot(edges[1], edges[1]), dot(edges[2], edges[2])}))});

    auto boxRadius = [&](Vec3 L) { return std::abs(L.x) * h.x + std::abs(L.y) * h.y + std::abs(L.z) * h.z; };
    // Separation along L and the direction (box to triangle) that achieves it.
    auto separation = [&](Vec3 L, Vec3& dir) {
        const float p0 = dot(L, t[0]), p1 = dot(L, t[1]), p2 = dot(L, t[2]);
        const float lo = std::min({p0, p1, p2}), hi = std::max({p0, p1, p2}), r = boxRadius(L);
        const float pos = lo - r, neg = -hi - r;
        dir = pos >= neg ? L : -L;
        return std::max(pos, neg);
    };

    enum class Axis { TriangleFace, BoxFace, EdgeEdge };
    Axis kind = Axis::TriangleFace;
    int boxAxis = 0, triEdge = 0;
    // The triangle face counts on the side of the box centre (two-sided triangles).
    const Vec3 toFace = dot(faceN, -t[0]) >= 0 ? -faceN : faceN;
    float best = dot(toFace, t[0]) - boxRadius(toFace);
    if (best > margin) return 0;
    Vec3 n = toFace;
    auto better = [&](float sep) {
        return sep > best + kAxisRelativeTolerance * std::abs(best) + kAxisAbsoluteTolerance * size;
    };
    for (int k = 0; k < 3; ++k) {
        Vec3 dir;
        const float sep = separation(axisVector(k, 1), dir);
        if (sep > margin) return 0;
        if (better(sep)) best = sep, n = dir, kind = Axis::BoxFace, boxAxis = k;
    }
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            const Vec3 L = cross(axisVector(i, 1), edges[j]);
            const float len2 = dot(L, L);
            if (len2 <= kTriangleEdgeParallelEpsilon * kTriangleEdgeParallelEpsilon * dot(edges[j], edges[j])) continue;
            Vec3 dir;
            const float sep = separation(L / std::sqrt(len2), dir);
            if (sep > margin) return 0;
            if (better(sep)) best = sep, n = dir, kind = Axis::EdgeEdge, boxAxis = i, triEdge = j;
        }
    }

    // Ghost rule: the triangle feature the contact lies on must be active to keep a non-face normal.
    if (kind != Axis::TriangleFace) {
        int feature = featureEdge(triEdge);
        if (kind == Axis::BoxFace) {
            const float p[3] = {dot(n, t[0]), dot(n, t[1]), dot(n, t[2])};
            const float lo = std::min({p[0], p[1], p[2]}), tol = kFeatureTolerance * size;
            int count = 0, first = -1, last = -1;
            for (int i = 0; i < 3; ++i)
                if (p[i] <= lo + tol) ++count, last = i, first = first < 0 ? i : first;
            // Two vertices i < j: edge i when j = i + 1, edge 2 for the pair (0, 2).
            feature = count == 3 ? kFeatureFace
                                 : (count == 1 ? featureVertex(first) : featureEdge(last == first + 1 ? first : 2));
        }
        if (!featureActive(feature, activeEdges)) kind = Axis::TriangleFace, n = toFace;
    }

    Candidate cands[kMaxClip];
    int count = 0;
    if (kind == Axis::TriangleFace) {
        // Incident box face: the one facing the triangle; clipped by the triangle's side planes.
        const float nc[3] = {n.x, n.y, n.z};
        int k = 0;
        for (int i = 1; i < 3; ++i)
            if (std::abs(nc[i]) > std::abs(nc[k])) k = i;
        const float s = nc[k] < 0 ? -1.0f : 1.0f;
        const int u = (k + 1) % 3, w = (k + 2) % 3;
        const float hk = component(h, k), hu = component(h, u), hw = component(h, w);
        ClipVertex poly[kMaxClip], tmp[kMaxClip];
        poly[0] = {withComponents(k, s * hk, u, hu, w, hw), 0, 0};
        poly[1] = {withComponents(k, s * hk, u, -hu, w, hw), 1, 1};
        poly[2] = {withComponents(k, s * hk, u, -hu, w, -hw), 2, 2};
        poly[3] = {withComponents(k, s * hk, u, hu, w, -hw), 3, 3};
        int m = 4;
        for (int e = 0; e < 3 && m > 0; ++e) {
            const Vec3 side = cross(edges[e], faceN);  // outward: t is counter-clockwise about faceN
            m = clipPolygon(poly, m, side, dot(side, t[e]), e, std::uint8_t(4 + e), tmp);
            std::copy(tmp, tmp + m, poly);
        }
        const std::uint32_t face = std::uint32_t(2 * k + (s < 0 ? 1 : 0));
        for (int i = 0; i < m; ++i) {
            const float depth = dot(poly[i].p - t[0], n);
            if (depth >= -margin) cands[count++] = {poly[i].p - n * depth, depth, face << 8 | poly[i].id};
        }
    } else if (kind == Axis::BoxFace) {
        // Reference face of the box: the triangle clipped to the face's four side planes.
        const int k = boxAxis, u = (k + 1) % 3, w = (k + 2) % 3;
        const float s = component(n, k) < 0 ? -1.0f : 1.0f;
        ClipVertex poly[kMaxClip], tmp[kMaxClip];
        for (int i = 0; i < 3; ++i) poly[i] = {t[i], std::uint8_t(i), std::uint8_t(i)};
        int m = 3;
        const Vec3 sides[4] = {axisVector(u, 1), axisVector(u, -1), axisVector(w, 1), axisVector(w, -1)};
        const float offsets[4] = {component(h, u), component(h, u), component(h, w), component(h, w)};
        for (int p = 0; p < 4 && m > 0; ++p) {
            m = clipPolygon(poly, m, sides[p], offsets[p], p, std::uint8_t(3 + p), tmp);
            std::copy(tmp, tmp + m, poly);
        }
        const std::uint32_t face = std::uint32_t(2 * k + (s < 0 ? 1 : 0));
        for (int i = 0; i < m; ++i) {
            const float depth = component(h, k) - s * component(poly[i].p, k);
            if (depth >= -margin) cands[count++] = {poly[i].p, depth, 1u << 30 | face << 8 | poly[i].id};
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
        if (depth >= -margin) cands[count++] = {onTri, depth, 2u << 30 | boxEdge << 8 | std::uint32_t(triEdge)};
    }
    if (count == 0) return 0;
    count = reduceToFour(cands, count, n);
    out.normal = rotate(boxPose.rotation, n);
    for (int i = 0; i < count; ++i)
        addPoint(out, rotate(boxPose.rotation, cands[i].position) + boxPose.position, cands[i].depth, cands[i].feature);
    return out.pointCount;
}

}  // namespace rubble::detail
