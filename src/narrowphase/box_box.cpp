// Box-box contact: SAT over 15 axes in A's frame, then face clipping in the reference box's frame or a single
// edge-edge point. See box_box.h for the robustness choices and the feature-id encoding.
#include "narrowphase/box_box.h"

#include <cmath>
#include <cstdint>

#include "narrowphase/clip.h"
#include "simd/simd.h"
#include "simd/vec.h"

namespace rubble::detail {
namespace {

using simd::FloatW;
using simd::MaskOf;
using simd::QuatW;
using simd::Vec3W;

// Plain comparisons: std::fmin/fmax handle NaN specially and end up as library calls.
inline float minf(float x, float y) { return x < y ? x : y; }
inline float maxf(float x, float y) { return x > y ? x : y; }
inline float signOf(float v) { return v < 0 ? -1.0f : 1.0f; }

/// Room for a clipped polygon. A convex quadrilateral gains at most one vertex per side plane (8 in all); the
/// spare room and the guard below only matter for nearly degenerate polygons whose rounding breaks convexity.
constexpr int kClipCapacity = 12;

/// A polygon being clipped, in the reference frame, one array per coordinate.
struct ClipPolygon {
    float p[3][kClipCapacity];
    std::uint8_t id[kClipCapacity];     ///< point part of the feature id (bits 0-7)
    std::uint8_t label[kClipCapacity];  ///< segment label of the edge from this point to the next (0..3 incident,
                                        ///< 4..7 side plane)
    int n = 0;
};

/// Sutherland-Hodgman step: keeps the part of polygon `in` with sg * p[k] <= h, given dist[e] = sg * p[k][e] - h.
/// A new point gets the id (segment label, plane); the new edge along the plane gets label 4 + plane. (Branches beat
/// a branch-free form that writes every point and crossing and computes every division: 7% on S1's box pairs.)
[[gnu::always_inline]] inline void clipSide(const ClipPolygon& in, const float* dist, ClipPolygon& out, int k, float sg,
                                            float h, int plane) {
    int m = 0;
    for (int e = 0; e < in.n && m + 2 <= kClipCapacity; ++e) {
        const int f = e + 1 == in.n ? 0 : e + 1;
        const float dc = dist[e], dd = dist[f];
        const bool cIn = dc <= 0, dIn = dd <= 0;
        if (cIn) {
            for (int q = 0; q < 3; ++q) out.p[q][m] = in.p[q][e];
            out.id[m] = in.id[e];
            out.label[m] = in.label[e];
            ++m;
        }
        if (cIn != dIn) {
            // dc and dd have opposite signs (one may be zero only when cIn), so the division is safe.
            const float s = dc / (dc - dd);
            for (int q = 0; q < 3; ++q) out.p[q][m] = in.p[q][e] + s * (in.p[q][f] - in.p[q][e]);
            out.p[k][m] = sg * h;  // exactly on the plane
            out.id[m] = static_cast<std::uint8_t>(0x20 | (in.label[e] << 2) | plane);
            out.label[m] = cIn ? static_cast<std::uint8_t>(4 + plane) : in.label[e];
            ++m;
        }
    }
    out.n = m;
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
    ClipPolygon bufA, bufB;
    static constexpr float kSu[4] = {1, -1, -1, 1}, kSv[4] = {1, 1, -1, -1};
    for (int k = 0; k < 4; ++k) {
        for (int q = 0; q < 3; ++q) bufA.p[q][k] = c[q] + kSu[k] * u[q] + kSv[k] * v[q];
        bufA.id[k] = static_cast<std::uint8_t>(k);
        bufA.label[k] = static_cast<std::uint8_t>(k);
    }
    bufA.n = 4;
    const int ku = axis == 2 ? 0 : axis + 1, kv = axis == 0 ? 2 : axis - 1;
    // A side plane that every point is inside would hand the polygon on unchanged: such passes are skipped (in a
    // resting stack most are), the others clip into the spare buffer.
    ClipPolygon* cur = &bufA;
    ClipPolygon* spare = &bufB;
    auto clip = [&](int k, float sg, float h, int plane) {
        float dist[kClipCapacity];
        bool inside = true;
        for (int e = 0; e < cur->n; ++e) {
            dist[e] = sg * cur->p[k][e] - h;
            inside &= dist[e] <= 0;
        }
        if (inside) return;
        clipSide(*cur, dist, *spare, k, sg, h, plane);
        ClipPolygon* emptied = cur;
        cur = spare;
        spare = emptied;
    };
    clip(ku, 1.0f, hr[ku], 0);
    clip(ku, -1.0f, hr[ku], 1);
    clip(kv, 1.0f, hr[kv], 2);
    clip(kv, -1.0f, hr[kv], 3);
    const int n = cur->n;
    const auto& poly = cur->p;

    // Keep points below the reference face plus margin.
    float depth[kClipCapacity];
    int keep[kClipCapacity];
    int m = 0;
    for (int k = 0; k < n; ++k) {
        const float d = hr[axis] - s * poly[axis][k];
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
        // The box frame's coordinates (ku, kv) are the contact plane's: no projection needed (copying the points
        // out for reduceContactPoints made box-box 9% slower).
        chooseFourPoints(
            m, depth, [&](int k) { return poly[ku][keep[k]]; }, [&](int k) { return poly[kv][keep[k]]; }, chosen);
        count = 4;
    }
    for (int k = 0; k < count; ++k) {
        const int point = keep[chosen[k]];
        for (int q = 0; q < 3; ++q) outP[k][q] = poly[q][point];
        outDepth[k] = depth[chosen[k]];
        outId[k] = cur->id[point];
    }
    return count;
}

/// What the separating-axis test of a pair leaves for its clipping: both rotation matrices, B in A's frame, and
/// the winning axes. Axis indices are held as floats so that every field is a lane of the same type.
template <class F>
struct BoxSat {
    F ra[3][3], rb[3][3];  ///< rotation matrices of A and B (m[r][c], column c = rotated basis vector c)
    F r[3][3], t[3];       ///< B's axes (columns) and centre in A's frame
    F sepA, sepB, tbBest, sepE;
    F axisA, axisB, edgeI, edgeJ;
    MaskOf<F> separated, useB, useEdge;
};

/// Calls fn on every float field of s, in one fixed order (lanes are stored and read back with it).
template <class F, class Fn>
void forEachValue(BoxSat<F>& s, Fn&& fn) {
    for (auto* m : {&s.ra, &s.rb, &s.r})
        for (auto& row : *m)
            for (F& v : row) fn(v);
    for (F& v : s.t) fn(v);
    for (F* v : {&s.sepA, &s.sepB, &s.tbBest, &s.sepE, &s.axisA, &s.axisB, &s.edgeI, &s.edgeJ}) fn(*v);
}

template <class F>
void toRotation(const QuatW<F>& q, F m[3][3]) {
    const F one(1.0f), two(2.0f);
    const F xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    const F xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    const F wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    m[0][0] = one - two * (yy + zz), m[0][1] = two * (xy - wz), m[0][2] = two * (xz + wy);
    m[1][0] = two * (xy + wz), m[1][1] = one - two * (xx + zz), m[1][2] = two * (yz - wx);
    m[2][0] = two * (xz - wy), m[2][1] = two * (yz + wx), m[2][2] = one - two * (xx + yy);
}

/// The 15-axis test, written once for a lane type: float runs one pair (and stops at the first separating group of
/// axes), FloatW runs 16 pairs with selects where the scalar form branches, so both give the same bits.
template <class F>
[[gnu::flatten]] void boxSat(const Vec3W<F>& pa, const QuatW<F>& qa, const Vec3W<F>& halfA, const Vec3W<F>& pb,
                             const QuatW<F>& qb, const Vec3W<F>& halfB, const F& margin, BoxSat<F>& s) {
    using simd::abs;
    const F ha[3] = {halfA.x, halfA.y, halfA.z}, hb[3] = {halfB.x, halfB.y, halfB.z};
    // B in A's frame: r (columns = B's axes), t (B's centre). Only the centre difference is taken in world space.
    toRotation(qa, s.ra);
    toRotation(qb, s.rb);
    const Vec3W<F> d = pb - pa;
    F ar[3][3];
    for (int i = 0; i < 3; ++i) {
        s.t[i] = s.ra[0][i] * d.x + s.ra[1][i] * d.y + s.ra[2][i] * d.z;
        for (int j = 0; j < 3; ++j) {
            s.r[i][j] = s.ra[0][i] * s.rb[0][j] + s.ra[1][i] * s.rb[1][j] + s.ra[2][i] * s.rb[2][j];
            ar[i][j] = abs(s.r[i][j]);
        }
    }
    const auto& r = s.r;
    const auto& t = s.t;
    const F maxA = simd::max(ha[0], simd::max(ha[1], ha[2])), maxB = simd::max(hb[0], simd::max(hb[1], hb[2]));
    const F absTol = F(kBoxAxisAbsoluteTolerance) * simd::max(maxA, maxB);
    const F relTol(kBoxAxisRelativeTolerance);
    auto clearlyBetter = [&](const F& candidate, const F& current) {
        return candidate > current + relTol * abs(current) + absTol;
    };

    // Face axes of A.
    s.sepA = F(-INFINITY);
    s.axisA = F(0.0f);
    for (int i = 0; i < 3; ++i) {
        const F sep = abs(t[i]) - (ha[i] + hb[0] * ar[i][0] + hb[1] * ar[i][1] + hb[2] * ar[i][2]);
        const auto better = sep > s.sepA;
        s.sepA = simd::select(better, sep, s.sepA);
        s.axisA = simd::select(better, F(static_cast<float>(i)), s.axisA);
    }
    s.separated = s.sepA > margin;
    if (simd::all(s.separated)) return;

    // Face axes of B.
    s.sepB = F(-INFINITY);
    s.tbBest = F(0.0f);
    s.axisB = F(0.0f);
    for (int j = 0; j < 3; ++j) {
        const F tb = t[0] * r[0][j] + t[1] * r[1][j] + t[2] * r[2][j];
        const F sep = abs(tb) - (ha[0] * ar[0][j] + ha[1] * ar[1][j] + ha[2] * ar[2][j] + hb[j]);
        const auto better = sep > s.sepB;
        s.sepB = simd::select(better, sep, s.sepB);
        s.axisB = simd::select(better, F(static_cast<float>(j)), s.axisB);
        s.tbBest = simd::select(better, tb, s.tbBest);
    }
    s.separated = simd::orMask(s.separated, s.sepB > margin);
    if (simd::all(s.separated)) return;

    // Axis choice with hysteresis: A's faces, then B's faces, then edges, each only if clearly better.
    s.useB = clearlyBetter(s.sepB, s.sepA);
    const F sepFace = simd::select(s.useB, s.sepB, s.sepA);

    // Edge axes e_i x B_j (in A's frame: component i is 0, i1 is -r[i2][j], i2 is r[i1][j]). An edge axis matters
    // only if its separation exceeds `limit` (it would separate the boxes or beat the face axis); since the axis
    // length is at most 1, separation = num / len > limit needs num > limit * len, which is tested first without
    // the square root and the division, so most axes of a resting or deep contact cost a few multiplies (and a
    // batch whose lanes all fail the test skips them).
    const F limit = simd::min(margin, sepFace + relTol * abs(sepFace) + absTol);
    const auto limitPositive = limit > F(0.0f);
    const F limit2 = limit * limit;
    const F zero(0.0f);
    s.sepE = F(-INFINITY);
    s.edgeI = zero;
    s.edgeJ = zero;
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
        const int i1 = i == 2 ? 0 : i + 1, i2 = i == 0 ? 2 : i - 1;
#pragma GCC unroll 3
        for (int j = 0; j < 3; ++j) {
            const int j1 = j == 2 ? 0 : j + 1, j2 = j == 0 ? 2 : j - 1;
            const F len2 = r[i1][j] * r[i1][j] + r[i2][j] * r[i2][j];
            const F tl = t[i2] * r[i1][j] - t[i1] * r[i2][j];
            const F ra_ = ha[i1] * ar[i2][j] + ha[i2] * ar[i1][j];
            const F rb_ = hb[j1] * ar[i][j2] + hb[j2] * ar[i][j1];
            const F num = abs(tl) - ra_ - rb_;
            const auto candidate =
                simd::orMask(simd::andMask(limitPositive, simd::andMask(num > zero, num * num > limit2 * len2)),
                             simd::andMask(simd::notMask(limitPositive), num > limit));
            const auto take =
                simd::andMask(candidate, simd::notMask(len2 < F(kBoxEdgeParallelEpsilon * kBoxEdgeParallelEpsilon)));
            if (simd::none(take)) continue;
            const F sep = num / simd::sqrt(len2);
            const auto better = simd::andMask(take, sep > s.sepE);
            s.sepE = simd::select(better, sep, s.sepE);
            s.edgeI = simd::select(better, F(static_cast<float>(i)), s.edgeI);
            s.edgeJ = simd::select(better, F(static_cast<float>(j)), s.edgeJ);
        }
    }
    s.separated = simd::orMask(s.separated, s.sepE > margin);
    s.useEdge = clearlyBetter(s.sepE, sepFace);
}

Vec3 mul(const float m[3][3], const float v[3]) {
    return {m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2], m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2]};
}

/// The contact of one pair that no axis separates (lane s of the test): a single edge-edge point or the clipped
/// reference face.
bool finishBoxes(const BoxSat<float>& sat, Vec3 posA, Vec3 halfA, Vec3 posB, Vec3 halfB, float margin, Manifold& out) {
    out.pointCount = 0;
    const float ha[3] = {halfA.x, halfA.y, halfA.z}, hb[3] = {halfB.x, halfB.y, halfB.z};
    const auto& r = sat.r;
    const auto& t = sat.t;
    const auto& ra = sat.ra;
    const auto& rb = sat.rb;
    const bool useB = sat.useB;
    const int axisA = static_cast<int>(sat.axisA), axisB = static_cast<int>(sat.axisB);
    const float tbBest = sat.tbBest;

    if (sat.useEdge) {
        // Edge-edge: one point at the closest points of the two supporting edges.
        const int i = static_cast<int>(sat.edgeI), j = static_cast<int>(sat.edgeJ);
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
        out.points[0].position = posA + mul(ra, cb);
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
        for (int k = 0; k < count; ++k) out.points[k].position = posA + mul(ra, p[k]);
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
            out.points[k].position = posB + mul(rb, p[k]);
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

Vec3W<float> wide1(Vec3 v) { return {v.x, v.y, v.z}; }
QuatW<float> wide1(Quat q) { return {q.x, q.y, q.z, q.w}; }

/// Pair i of a batch, one lane.
bool collideAt(const BoxPairs& in, std::size_t i, Manifold& out) {
    const Vec3 pa{in.ax[i], in.ay[i], in.az[i]}, pb{in.bx[i], in.by[i], in.bz[i]};
    const Vec3 ha{in.ahx[i], in.ahy[i], in.ahz[i]}, hb{in.bhx[i], in.bhy[i], in.bhz[i]};
    BoxSat<float> sat;
    boxSat<float>(wide1(pa), {in.aqx[i], in.aqy[i], in.aqz[i], in.aqw[i]}, wide1(ha), wide1(pb),
                  {in.bqx[i], in.bqy[i], in.bqz[i], in.bqw[i]}, wide1(hb), in.margin[i], sat);
    if (sat.separated) {
        out.pointCount = 0;
        return false;
    }
    return finishBoxes(sat, pa, ha, pb, hb, in.margin[i], out);
}

/// Pairs [i, i + kLanes): the axis tests in SIMD lanes, then each touching pair's clipping on its own.
void collideWideAt(const BoxPairs& in, std::size_t i, Manifold* out, const std::uint32_t* outIndex) {
    BoxSat<FloatW> sat;
    boxSat<FloatW>(Vec3W<FloatW>::load(in.ax, in.ay, in.az, i), QuatW<FloatW>::load(in.aqx, in.aqy, in.aqz, in.aqw, i),
                   Vec3W<FloatW>::load(in.ahx, in.ahy, in.ahz, i), Vec3W<FloatW>::load(in.bx, in.by, in.bz, i),
                   QuatW<FloatW>::load(in.bqx, in.bqy, in.bqz, in.bqw, i),
                   Vec3W<FloatW>::load(in.bhx, in.bhy, in.bhz, i), simd::load<FloatW>(in.margin + i), sat);
    if (simd::all(sat.separated)) {
        for (std::size_t k = 0; k < simd::kLanes; ++k) out[outIndex ? outIndex[i + k] : i + k].pointCount = 0;
        return;
    }
    constexpr int kValues = 3 * 9 + 3 + 8;
    alignas(64) float values[kValues][simd::kLanes];
    bool separated[simd::kLanes], useB[simd::kLanes], useEdge[simd::kLanes];
    int f = 0;
    forEachValue(sat, [&](FloatW& v) { simd::store(values[f++], v); });
    simd::storeMask(separated, sat.separated);
    simd::storeMask(useB, sat.useB);
    simd::storeMask(useEdge, sat.useEdge);
    for (std::size_t k = 0; k < simd::kLanes; ++k) {
        const std::size_t p = i + k;
        Manifold& m = out[outIndex ? outIndex[p] : p];
        if (separated[k]) {
            m.pointCount = 0;
            continue;
        }
        BoxSat<float> one;
        f = 0;
        forEachValue(one, [&](float& v) { v = values[f++][k]; });
        one.separated = false;
        one.useB = useB[k];
        one.useEdge = useEdge[k];
        finishBoxes(one, {in.ax[p], in.ay[p], in.az[p]}, {in.ahx[p], in.ahy[p], in.ahz[p]},
                    {in.bx[p], in.by[p], in.bz[p]}, {in.bhx[p], in.bhy[p], in.bhz[p]}, in.margin[p], m);
    }
}

}  // namespace

bool collideBoxes(const Transform& a, Vec3 halfA, const Transform& b, Vec3 halfB, float margin, Manifold& out) {
    BoxSat<float> sat;
    boxSat<float>(wide1(a.position), wide1(a.rotation), wide1(halfA), wide1(b.position), wide1(b.rotation),
                  wide1(halfB), margin, sat);
    if (sat.separated) {
        out.pointCount = 0;
        return false;
    }
    return finishBoxes(sat, a.position, halfA, b.position, halfB, margin, out);
}

void collideBoxesBatch(const BoxPairs& in, std::size_t n, Manifold* out, const std::uint32_t* outIndex) {
    std::size_t i = 0;
    for (const std::size_t end = simd::roundDownToLanes<FloatW>(n); i < end; i += simd::kLanes)
        collideWideAt(in, i, out, outIndex);
    for (; i < n; ++i) collideAt(in, i, out[outIndex ? outIndex[i] : i]);
}

void collideBoxesBatchScalar(const BoxPairs& in, std::size_t n, Manifold* out, const std::uint32_t* outIndex) {
    for (std::size_t i = 0; i < n; ++i) collideAt(in, i, out[outIndex ? outIndex[i] : i]);
}

}  // namespace rubble::detail
