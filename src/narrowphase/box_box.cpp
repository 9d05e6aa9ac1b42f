// Box-box contact: SAT over 15 axes in A's frame, then face clipping in the reference box's frame or a single
// edge-edge point. See box_box.h for the robustness choices and the feature-id encoding.
#include "narrowphase/box_box.h"

#include <cmath>
#include <cstdint>

namespace rubble::detail {
namespace {

/// Rotation matrix of a unit quaternion; m[r][c], column c is the rotated basis vector c.
struct Rot {
    float m[3][3];
};

inline Rot toRot(Quat q) {
    const float xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    const float xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    const float wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    Rot r;
    r.m[0][0] = 1 - 2 * (yy + zz), r.m[0][1] = 2 * (xy - wz), r.m[0][2] = 2 * (xz + wy);
    r.m[1][0] = 2 * (xy + wz), r.m[1][1] = 1 - 2 * (xx + zz), r.m[1][2] = 2 * (yz - wx);
    r.m[2][0] = 2 * (xz - wy), r.m[2][1] = 2 * (yz + wx), r.m[2][2] = 1 - 2 * (xx + yy);
    return r;
}

Vec3 mul(const Rot& r, const float v[3]) {
    return {r.m[0][0] * v[0] + r.m[0][1] * v[1] + r.m[0][2] * v[2],
            r.m[1][0] * v[0] + r.m[1][1] * v[1] + r.m[1][2] * v[2],
            r.m[2][0] * v[0] + r.m[2][1] * v[1] + r.m[2][2] * v[2]};
}

// Plain comparisons: std::fmin/fmax handle NaN specially and end up as library calls.
inline float minf(float x, float y) { return x < y ? x : y; }
inline float maxf(float x, float y) { return x > y ? x : y; }
inline float signOf(float v) { return v < 0 ? -1.0f : 1.0f; }

/// A candidate point of a face contact, in the reference frame.
struct ClipPoint {
    float p[3];
    std::uint8_t id;     ///< point part of the feature id (bits 0-7)
    std::uint8_t label;  ///< segment label of the edge from this point to the next (0..3 incident, 4..7 side plane)
};

/// Room for a clipped polygon. A convex quadrilateral gains at most one vertex per side plane (8 in all); the
/// spare room and the guard below only matter for nearly degenerate polygons whose rounding breaks convexity.
constexpr int kClipCapacity = 12;

/// Sutherland-Hodgman step: keeps the part of polygon `in` (n points) with sg * p[k] <= h; returns the new count.
/// A new point gets the id (segment label, plane); the new edge along the plane gets label 4 + plane.
[[gnu::always_inline]] inline int clipSide(const ClipPoint* in, int n, ClipPoint* out, int k, float sg, float h,
                                           int plane) {
    int m = 0;
    for (int e = 0; e < n && m + 2 <= kClipCapacity; ++e) {
        const ClipPoint& c = in[e];
        const ClipPoint& d = in[e + 1 == n ? 0 : e + 1];
        const float dc = sg * c.p[k] - h, dd = sg * d.p[k] - h;
        const bool cIn = dc <= 0, dIn = dd <= 0;
        if (cIn) out[m++] = c;
        if (cIn != dIn) {
            // dc and dd have opposite signs (one may be zero only when cIn), so the division is safe.
            const float s = dc / (dc - dd);
            ClipPoint& x = out[m++];
            for (int q = 0; q < 3; ++q) x.p[q] = c.p[q] + s * (d.p[q] - c.p[q]);
            x.p[k] = sg * h;  // exactly on the plane
            x.id = static_cast<std::uint8_t>(0x20 | (c.label << 2) | plane);
            x.label = cIn ? static_cast<std::uint8_t>(4 + plane) : c.label;
        }
    }
    return m;
}

/// Face contact in the reference frame. r: incident box axes (columns) in the reference frame, t: incident centre,
/// hr/hi: half extents, axis/s: reference face normal s * e_axis. Writes up to 4 points (position in the
/// reference frame on the incident face, depth, point id) and returns the count.
int clipFace(const float r[3][3], const float t[3], const float hr[3], const float hi[3], int axis, float s,
             float margin, float outP[4][3], float outDepth[4], std::uint8_t outId[4], int& incidentFace) {
    // Incident face: the face of the other box most anti-parallel to the reference normal.
    const float a0 = std::fabs(r[axis][0]), a1 = std::fabs(r[axis][1]), a2 = std::fabs(r[axis][2]);
    const int j = (a0 >= a1 && a0 >= a2) ? 0 : (a1 >= a2 ? 1 : 2);
    const float sj = s * r[axis][j] > 0 ? -1.0f : 1.0f;  // incident face normal = sj * B_j
    incidentFace = 2 * j + (sj < 0 ? 1 : 0);
    const int j1 = j == 2 ? 0 : j + 1, j2 = j == 0 ? 2 : j - 1;
    float c[3], u[3], v[3];
    for (int q = 0; q < 3; ++q) {
        c[q] = t[q] + sj * hi[j] * r[q][j];
        u[q] = hi[j1] * r[q][j1];
        v[q] = hi[j2] * r[q][j2];
    }
    ClipPoint bufA[kClipCapacity], bufB[kClipCapacity];
    static constexpr float kSu[4] = {1, -1, -1, 1}, kSv[4] = {1, 1, -1, -1};
    for (int k = 0; k < 4; ++k) {
        for (int q = 0; q < 3; ++q) bufA[k].p[q] = c[q] + kSu[k] * u[q] + kSv[k] * v[q];
        bufA[k].id = static_cast<std::uint8_t>(k);
        bufA[k].label = static_cast<std::uint8_t>(k);
    }
    const int ku = axis == 2 ? 0 : axis + 1, kv = axis == 0 ? 2 : axis - 1;
    int n = 4;
    n = clipSide(bufA, n, bufB, ku, 1.0f, hr[ku], 0);
    n = clipSide(bufB, n, bufA, ku, -1.0f, hr[ku], 1);
    n = clipSide(bufA, n, bufB, kv, 1.0f, hr[kv], 2);
    n = clipSide(bufB, n, bufA, kv, -1.0f, hr[kv], 3);

    // Keep points below the reference face plus margin.
    float depth[kClipCapacity];
    int keep[kClipCapacity];
    int m = 0;
    for (int k = 0; k < n; ++k) {
        const float d = hr[axis] - s * bufA[k].p[axis];
        if (d >= -margin) {
            depth[m] = d;
            keep[m++] = k;
        }
    }

    int chosen[4];
    int count;
    if (m <= 4) {
        for (int k = 0; k < m; ++k) chosen[k] = k;
        count = m;
    } else {
        // Reduction (as in Gregorius' contact reduction): the deepest point, the point farthest from it, then the
        // points that add the most area, measured in the reference plane (coordinates ku, kv). This is the same
        // rule as reduceContactPoints in clip.cpp, specialised to the box frame: calling the shared function
        // (copying points out and projecting them) made box-box 9% slower (9.3 -> 8.5 M manifolds/s, mixed poses).
        auto pu = [&](int k) { return bufA[keep[k]].p[ku]; };
        auto pv = [&](int k) { return bufA[keep[k]].p[kv]; };
        int i0 = 0;
        for (int k = 1; k < m; ++k) i0 = depth[k] > depth[i0] ? k : i0;
        int i1 = i0 == 0 ? 1 : 0;
        float best = -1;
        for (int k = 0; k < m; ++k) {
            const float du = pu(k) - pu(i0), dv = pv(k) - pv(i0);
            const float d2 = du * du + dv * dv;
            if (k != i0 && d2 > best) best = d2, i1 = k;
        }
        // Third: largest |area| of triangle (i0, i1, k); orient the triangle so that it is counter-clockwise.
        const float eu = pu(i1) - pu(i0), ev = pv(i1) - pv(i0);
        int i2 = -1;
        float bestArea = -1, orient = 1;
        for (int k = 0; k < m; ++k) {
            if (k == i0 || k == i1) continue;
            const float area = eu * (pv(k) - pv(i0)) - ev * (pu(k) - pu(i0));
            if (std::fabs(area) > bestArea) bestArea = std::fabs(area), i2 = k, orient = signOf(area);
        }
        // Fourth: the point farthest outside the triangle, i.e. adding the most area to the quadrilateral.
        const int tri[3] = {i0, i1, i2};
        int i3 = -1;
        float bestAdd = -INFINITY;
        for (int k = 0; k < m; ++k) {
            if (k == i0 || k == i1 || k == i2) continue;
            float add = -INFINITY;
            for (int e = 0; e < 3; ++e) {
                const int pa = tri[e], pb = tri[e == 2 ? 0 : e + 1];
                const float area =
                    -orient * ((pu(pb) - pu(pa)) * (pv(k) - pv(pa)) - (pv(pb) - pv(pa)) * (pu(k) - pu(pa)));
                add = area > add ? area : add;
            }
            if (add > bestAdd) bestAdd = add, i3 = k;
        }
        // Report in the clipped polygon's order (stable across steps): sort the four indices.
        int sel[4] = {i0, i1, i2, i3};
        for (int x = 1; x < 4; ++x)
            for (int y = x; y > 0 && sel[y] < sel[y - 1]; --y) {
                const int tmp = sel[y];
                sel[y] = sel[y - 1];
                sel[y - 1] = tmp;
            }
        for (int k = 0; k < 4; ++k) chosen[k] = sel[k];
        count = 4;
    }
    for (int k = 0; k < count; ++k) {
        const ClipPoint& cp = bufA[keep[chosen[k]]];
        for (int q = 0; q < 3; ++q) outP[k][q] = cp.p[q];
        outDepth[k] = depth[chosen[k]];
        outId[k] = cp.id;
    }
    return count;
}

}  // namespace

bool collideBoxes(const Transform& a, Vec3 halfA, const Transform& b, Vec3 halfB, float margin, Manifold& out) {
    out.pointCount = 0;
    const float ha[3] = {halfA.x, halfA.y, halfA.z}, hb[3] = {halfB.x, halfB.y, halfB.z};

    // B in A's frame: r (columns = B's axes), t (B's centre). Only the centre difference is taken in world space.
    const Rot ra = toRot(a.rotation), rb = toRot(b.rotation);
    const Vec3 d = b.position - a.position;
    float r[3][3], ar[3][3], t[3];
    for (int i = 0; i < 3; ++i) {
        t[i] = ra.m[0][i] * d.x + ra.m[1][i] * d.y + ra.m[2][i] * d.z;
        for (int j = 0; j < 3; ++j) {
            r[i][j] = ra.m[0][i] * rb.m[0][j] + ra.m[1][i] * rb.m[1][j] + ra.m[2][i] * rb.m[2][j];
            ar[i][j] = std::fabs(r[i][j]);
        }
    }
    const float maxA = maxf(ha[0], maxf(ha[1], ha[2])), maxB = maxf(hb[0], maxf(hb[1], hb[2]));
    const float absTol = kBoxAxisAbsoluteTolerance * maxf(maxA, maxB);
    auto clearlyBetter = [&](float candidate, float current) {
        return candidate > current + kBoxAxisRelativeTolerance * std::fabs(current) + absTol;
    };

    // Face axes of A.
    float sepA = -INFINITY;
    int axisA = 0;
    for (int i = 0; i < 3; ++i) {
        const float sep = std::fabs(t[i]) - (ha[i] + hb[0] * ar[i][0] + hb[1] * ar[i][1] + hb[2] * ar[i][2]);
        if (sep > sepA) sepA = sep, axisA = i;
    }
    if (sepA > margin) return false;

    // Face axes of B.
    float sepB = -INFINITY, tbBest = 0;
    int axisB = 0;
    for (int j = 0; j < 3; ++j) {
        const float tb = t[0] * r[0][j] + t[1] * r[1][j] + t[2] * r[2][j];
        const float sep = std::fabs(tb) - (ha[0] * ar[0][j] + ha[1] * ar[1][j] + ha[2] * ar[2][j] + hb[j]);
        if (sep > sepB) sepB = sep, axisB = j, tbBest = tb;
    }
    if (sepB > margin) return false;

    // Axis choice with hysteresis: A's faces, then B's faces, then edges, each only if clearly better.
    const bool useB = clearlyBetter(sepB, sepA);
    const float sepFace = useB ? sepB : sepA;

    // Edge axes e_i x B_j (in A's frame: component i is 0, i1 is -r[i2][j], i2 is r[i1][j]). An edge axis matters
    // only if its separation exceeds `limit` (it would separate the boxes or beat the face axis); since the axis
    // length is at most 1, separation = num / len > limit needs num > limit * len, which is tested first without
    // the square root and the division, so most axes of a resting or deep contact cost a few multiplies.
    const float limit = minf(margin, sepFace + kBoxAxisRelativeTolerance * std::fabs(sepFace) + absTol);
    float sepE = -INFINITY;
    int edgeI = 0, edgeJ = 0;
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
        const int i1 = i == 2 ? 0 : i + 1, i2 = i == 0 ? 2 : i - 1;
#pragma GCC unroll 3
        for (int j = 0; j < 3; ++j) {
            const int j1 = j == 2 ? 0 : j + 1, j2 = j == 0 ? 2 : j - 1;
            const float len2 = r[i1][j] * r[i1][j] + r[i2][j] * r[i2][j];
            const float tl = t[i2] * r[i1][j] - t[i1] * r[i2][j];
            const float ra_ = ha[i1] * ar[i2][j] + ha[i2] * ar[i1][j];
            const float rb_ = hb[j1] * ar[i][j2] + hb[j2] * ar[i][j1];
            const float num = std::fabs(tl) - ra_ - rb_;
            const bool candidate = limit <= 0 ? num > limit : num > 0 && num * num > limit * limit * len2;
            if (!candidate || len2 < kBoxEdgeParallelEpsilon * kBoxEdgeParallelEpsilon) continue;
            const float sep = num / std::sqrt(len2);
            if (sep > sepE) sepE = sep, edgeI = i, edgeJ = j;
        }
    }
    if (sepE > margin) return false;

    if (clearlyBetter(sepE, sepFace)) {
        // Edge-edge: one point at the closest points of the two supporting edges.
        const int i = edgeI, j = edgeJ;
        const int i1 = i == 2 ? 0 : i + 1, i2 = i == 0 ? 2 : i - 1;
        const int j1 = j == 2 ? 0 : j + 1, j2 = j == 0 ? 2 : j - 1;
        float n[3];
        n[i] = 0, n[i1] = -r[i2][j], n[i2] = r[i1][j];
        const float inv = 1.0f / std::sqrt(n[i1] * n[i1] + n[i2] * n[i2]);
        const float flip = (n[0] * t[0] + n[1] * t[1] + n[2] * t[2]) < 0 ? -inv : inv;
        for (float& c : n) c *= flip;
        // Supporting edge of A along +n (centre point pa, direction e_i) and of B along -n (pb, direction B_j).
        const float su = signOf(n[i1]), sv = signOf(n[i2]);
        float pa[3];
        pa[i] = 0, pa[i1] = su * ha[i1], pa[i2] = sv * ha[i2];
        const float nb1 = n[0] * r[0][j1] + n[1] * r[1][j1] + n[2] * r[2][j1];
        const float nb2 = n[0] * r[0][j2] + n[1] * r[1][j2] + n[2] * r[2][j2];
        const float tu = nb1 > 0 ? -1.0f : 1.0f, tv = nb2 > 0 ? -1.0f : 1.0f;
        float pb[3], rr[3];
        for (int q = 0; q < 3; ++q) {
            pb[q] = t[q] + tu * hb[j1] * r[q][j1] + tv * hb[j2] * r[q][j2];
            rr[q] = pa[q] - pb[q];
        }
        // Closest points of the segments pa + s e_i (|s| <= ha[i]) and pb + w B_j (|w| <= hb[j]).
        const float bb = r[i][j];
        const float c = rr[i];
        const float f = rr[0] * r[0][j] + rr[1] * r[1][j] + rr[2] * r[2][j];
        const float denom = 1 - bb * bb;  // >= epsilon^2 because the axis was not skipped
        float s = (bb * f - c) / denom;
        s = minf(maxf(s, -ha[i]), ha[i]);
        float w = bb * s + f;
        if (std::fabs(w) > hb[j]) {
            w = minf(maxf(w, -hb[j]), hb[j]);
            s = minf(maxf(bb * w - c, -ha[i]), ha[i]);
        }
        float cb[3], depth = 0;
        for (int q = 0; q < 3; ++q) {
            cb[q] = pb[q] + w * r[q][j];
            const float ca = pa[q] + (q == i ? s : 0.0f);
            depth += (ca - cb[q]) * n[q];
        }
        if (depth < -margin) return false;
        out.normal = mul(ra, n);
        out.points[0].position = a.position + mul(ra, cb);
        out.points[0].depth = depth;
        const std::uint32_t edgeA = 4u * i + (su < 0 ? 1u : 0u) + (sv < 0 ? 2u : 0u);
        const std::uint32_t edgeB = 4u * j + (tu < 0 ? 1u : 0u) + (tv < 0 ? 2u : 0u);
        out.points[0].feature = (kBoxFeatureEdgeEdge << kBoxFeatureKindShift) | (edgeA << 8) | edgeB;
        out.pointCount = 1;
        return true;
    }

    float p[4][3], depth[4];
    std::uint8_t ids[4];
    int incidentFace = 0, count, axis;
    float s;
    if (!useB) {
        axis = axisA, s = signOf(t[axisA]);
        count = clipFace(r, t, ha, hb, axis, s, margin, p, depth, ids, incidentFace);
        const float nl[3] = {axis == 0 ? s : 0.0f, axis == 1 ? s : 0.0f, axis == 2 ? s : 0.0f};
        out.normal = mul(ra, nl);
        for (int k = 0; k < count; ++k) out.points[k].position = a.position + mul(ra, p[k]);
    } else {
        // A in B's frame: transpose of r, centre -r^T t.
        float rt[3][3], tt[3];
        for (int i = 0; i < 3; ++i) {
            tt[i] = -(t[0] * r[0][i] + t[1] * r[1][i] + t[2] * r[2][i]);
            for (int j = 0; j < 3; ++j) rt[i][j] = r[j][i];
        }
        axis = axisB, s = signOf(-tbBest);  // B's face pointing towards A
        count = clipFace(rt, tt, hb, ha, axis, s, margin, p, depth, ids, incidentFace);
        const float nl[3] = {axis == 0 ? s : 0.0f, axis == 1 ? s : 0.0f, axis == 2 ? s : 0.0f};
        out.normal = -mul(rb, nl);
        // The clipped points lie on A's incident face; move them onto B's reference face (B's surface).
        for (int k = 0; k < count; ++k) {
            p[k][axis] += s * depth[k];
            out.points[k].position = b.position + mul(rb, p[k]);
        }
    }
    const std::uint32_t refFace = 2u * static_cast<std::uint32_t>(axis) + (s < 0 ? 1u : 0u);
    const std::uint32_t base = ((useB ? kBoxFeatureFaceB : kBoxFeatureFaceA) << kBoxFeatureKindShift) |
                               (refFace << 16) | (static_cast<std::uint32_t>(incidentFace) << 8);
    for (int k = 0; k < count; ++k) {
        out.points[k].depth = depth[k];
        out.points[k].feature = base | ids[k];
    }
    out.pointCount = count;
    return count > 0;
}

}  // namespace rubble::detail
