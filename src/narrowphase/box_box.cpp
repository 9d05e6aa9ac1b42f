// Box-box contact: SAT over 15 axes in A's frame, then face clipping in the reference box's frame or a single
// edge-edge point. See box_box.h for the robustness choices and the feature-id encoding.
#include "narrowphase/box_box.h"

#include <cmath>
#include <cstdint>
#include <type_traits>

#include "narrowphase/clip.h"
#include "narrowphase/closest_points_contact.h"
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
[[gnu::always_inline]] inline void forEachValue(BoxSat<F>& s, Fn&& fn) {
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
RUBBLE_FLATTEN void boxSat(const Vec3W<F>& pa, const QuatW<F>& qa, const Vec3W<F>& halfA, const Vec3W<F>& pb,
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

/// Candidate points of a face contact: the clipped incident face is the part of a parallelogram (the incident box
/// face) inside a rectangle (the reference face's side planes), so its vertices are among a fixed set of slots:
/// the 4 incident vertices, the 16 crossings of an incident edge with a side plane and the 4 reference-face corners,
/// each valid where it lies inside every side plane (and, for a corner, inside the incident face). Fixed slots need
/// no compaction, so 16 pairs are clipped at once in SIMD lanes; the slot order is the order of the points, and the
/// ids are those Sutherland-Hodgman clipping would give them (box_box.h).
constexpr int kFaceSlots = 24;
constexpr int kCrossingSlot = 4;  ///< slot of incident edge e crossing side plane p: 4 + 4 e + p
constexpr int kCornerSlot = 20;   ///< slot of the corner of side planes p1 (0, 1) and p2 (2, 3): 20 + 2 p1 + p2 - 2

/// Point part of the feature id of a slot (bits 0-7).
std::uint8_t slotId(int slot) {
    if (slot < kCrossingSlot) return static_cast<std::uint8_t>(slot);
    if (slot < kCornerSlot)
        return static_cast<std::uint8_t>(0x20 | ((slot - kCrossingSlot) / 4) << 2 | (slot - kCrossingSlot) % 4);
    const int p1 = (slot - kCornerSlot) / 2, p2 = 2 + (slot - kCornerSlot) % 2;
    return static_cast<std::uint8_t>(0x20 | (4 + p1) << 2 | p2);
}

/// The face contact of every lane, in reference-frame coordinates permuted so that the reference normal axis is w:
/// (u, v, w) = (x[ku], x[kv], x[axis]) with ku, kv the axes after `axis` in cyclic order.
template <class F>
struct FaceSlots {
    F u[kFaceSlots], v[kFaceSlots], w[kFaceSlots], depth[kFaceSlots];
    MaskOf<F> valid[kFaceSlots];
    F chosen[4];  ///< the slots of the points, in increasing order (count of them are used)
    F count;      ///< valid slots, at most 4 used
    F axis, s;    ///< reference axis (0, 1, 2 as a float) and the sign of its face normal
    F incidentFace;
};

/// v[i] for a per-lane index i in 0..2 (held as a float).
template <class F>
F pick(const F& v0, const F& v1, const F& v2, const F& i) {
    return simd::select(i == F(0.0f), v0, simd::select(i == F(1.0f), v1, v2));
}

/// The face contacts of the lanes (those whose SAT chose a face axis; other lanes compute unused values). In the
/// reference box's frame: A's when !useB, else B's (A seen from B: transpose of r, centre -r^T t).
template <class F>
RUBBLE_FLATTEN void faceSlots(const BoxSat<F>& sat, const Vec3W<F>& halfA, const Vec3W<F>& halfB, const F& margin,
                              FaceSlots<F>& out) {
    using simd::abs;
    using simd::select;
    const F zero(0.0f), one(1.0f);
    const auto useB = sat.useB;
    F m[3][3], c[3];  // incident axes (columns) and centre in the reference frame
    for (int i = 0; i < 3; ++i) {
        const F tt = -(sat.t[0] * sat.r[0][i] + sat.t[1] * sat.r[1][i] + sat.t[2] * sat.r[2][i]);
        c[i] = select(useB, tt, sat.t[i]);
        for (int j = 0; j < 3; ++j) m[i][j] = select(useB, sat.r[j][i], sat.r[i][j]);
    }
    const F hr[3] = {select(useB, halfB.x, halfA.x), select(useB, halfB.y, halfA.y), select(useB, halfB.z, halfA.z)};
    const F hi[3] = {select(useB, halfA.x, halfB.x), select(useB, halfA.y, halfB.y), select(useB, halfA.z, halfB.z)};
    const F axis = select(useB, sat.axisB, sat.axisA);
    const F ku = select(axis == F(2.0f), zero, axis + one), kv = select(axis == zero, F(2.0f), axis - one);
    const F cw = pick(c[0], c[1], c[2], axis);
    // Sign of the reference normal: towards the incident box (A's face: sign of t; B's face: towards A, -tb).
    const F s = select(select(useB, -sat.tbBest, cw) < zero, F(-1.0f), one);
    out.axis = axis, out.s = s;
    // Incident axes permuted to (u, v, w).
    F mu[3], mv[3], mw[3];
    for (int j = 0; j < 3; ++j) {
        mu[j] = pick(m[0][j], m[1][j], m[2][j], ku);
        mv[j] = pick(m[0][j], m[1][j], m[2][j], kv);
        mw[j] = pick(m[0][j], m[1][j], m[2][j], axis);
    }
    const F cu = pick(c[0], c[1], c[2], ku), cv = pick(c[0], c[1], c[2], kv);
    const F Hu = pick(hr[0], hr[1], hr[2], ku), Hv = pick(hr[0], hr[1], hr[2], kv),
            Hw = pick(hr[0], hr[1], hr[2], axis);
    // Incident face: the face of the other box most anti-parallel to the reference normal.
    const F a0 = abs(mw[0]), a1 = abs(mw[1]), a2 = abs(mw[2]);
    const F j = select(simd::andMask(a0 >= a1, a0 >= a2), zero, select(a1 >= a2, one, F(2.0f)));
    const F j1 = select(j == F(2.0f), zero, j + one), j2 = select(j == zero, F(2.0f), j - one);
    const F sj = select(s * pick(mw[0], mw[1], mw[2], j) > zero, F(-1.0f), one);
    out.incidentFace = F(2.0f) * j + select(sj < zero, one, zero);
    const F hj = sj * pick(hi[0], hi[1], hi[2], j), h1 = pick(hi[0], hi[1], hi[2], j1),
            h2 = pick(hi[0], hi[1], hi[2], j2);
    const F ccu = cu + hj * pick(mu[0], mu[1], mu[2], j), ccv = cv + hj * pick(mv[0], mv[1], mv[2], j),
            ccw = cw + hj * pick(mw[0], mw[1], mw[2], j);
    const F uu = h1 * pick(mu[0], mu[1], mu[2], j1), uv = h1 * pick(mv[0], mv[1], mv[2], j1),
            uw = h1 * pick(mw[0], mw[1], mw[2], j1);
    const F vu = h2 * pick(mu[0], mu[1], mu[2], j2), vv = h2 * pick(mv[0], mv[1], mv[2], j2),
            vw = h2 * pick(mw[0], mw[1], mw[2], j2);
    static constexpr float kSu[4] = {1, -1, -1, 1}, kSv[4] = {1, 1, -1, -1};
    F px[4], py[4], pz[4];
    F dist[4][4];  // [vertex][side plane]: +u, -u, +v, -v
    for (int i = 0; i < 4; ++i) {
        px[i] = ccu + F(kSu[i]) * uu + F(kSv[i]) * vu;
        py[i] = ccv + F(kSu[i]) * uv + F(kSv[i]) * vv;
        pz[i] = ccw + F(kSu[i]) * uw + F(kSv[i]) * vw;
        dist[i][0] = px[i] - Hu, dist[i][1] = -px[i] - Hu, dist[i][2] = py[i] - Hv, dist[i][3] = -py[i] - Hv;
        out.u[i] = px[i], out.v[i] = py[i], out.w[i] = pz[i];
        out.valid[i] = simd::andMask(simd::andMask(dist[i][0] <= zero, dist[i][1] <= zero),
                                     simd::andMask(dist[i][2] <= zero, dist[i][3] <= zero));
    }
    for (int e = 0; e < 4; ++e) {
        const int f = e == 3 ? 0 : e + 1;
        for (int p = 0; p < 4; ++p) {
            const F dc = dist[e][p], dd = dist[f][p];
            const auto crosses = simd::notMask((dc <= zero) == (dd <= zero));
            const int slot = kCrossingSlot + 4 * e + p;
            if (simd::none(crosses)) {  // the common case: most edges cross no side plane
                out.u[slot] = out.v[slot] = out.w[slot] = zero, out.valid[slot] = crosses;
                continue;
            }
            const F frac = dc / select(crosses, dc - dd, one);
            F x = px[e] + frac * (px[f] - px[e]), y = py[e] + frac * (py[f] - py[e]);
            const F z = pz[e] + frac * (pz[f] - pz[e]);
            auto inside = crosses;
            if (p < 2) {
                x = p == 0 ? Hu : -Hu;  // exactly on the plane
                inside = simd::andMask(inside, simd::andMask(y - Hv <= zero, -y - Hv <= zero));
            } else {
                y = p == 2 ? Hv : -Hv;
                inside = simd::andMask(inside, simd::andMask(x - Hu <= zero, -x - Hu <= zero));
            }
            out.u[slot] = x, out.v[slot] = y, out.w[slot] = z, out.valid[slot] = inside;
        }
    }
    // Corners of the reference face inside the incident face: (u, v) = cc + a U + b V with |a|, |b| <= 1.
    const F det = uu * vv - vu * uv;
    const F invDet = one / select(det == zero, one, det);
    for (int p1 = 0; p1 < 2; ++p1)
        for (int p2 = 2; p2 < 4; ++p2) {
            const F x = p1 == 0 ? Hu : -Hu, y = p2 == 2 ? Hv : -Hv;
            const F du = x - ccu, dv = y - ccv;
            const F a = (du * vv - vu * dv) * invDet, b = (uu * dv - du * uv) * invDet;
            const int slot = kCornerSlot + 2 * p1 + p2 - 2;
            out.u[slot] = x, out.v[slot] = y, out.w[slot] = ccw + a * uw + b * vw;
            out.valid[slot] = simd::andMask(det != zero, simd::andMask(abs(a) <= one, abs(b) <= one));
        }
    // Points below the reference face plus the margin. A slot that no lane uses is skipped from here on (most are:
    // a clipped quadrilateral has at most 8 vertices).
    F count = zero;
    int used[kFaceSlots];
    int usedCount = 0;
    for (int k = 0; k < kFaceSlots; ++k) {
        out.depth[k] = Hw - s * out.w[k];
        out.valid[k] = simd::andMask(out.valid[k], out.depth[k] >= -margin);
        count = count + select(out.valid[k], one, zero);
        if (simd::any(out.valid[k])) used[usedCount++] = k;
    }
    out.count = count;
    // Up to four: the first four valid slots, else the reduction of clip.h (chooseFourPoints) over the valid ones.
    F firstFour[4] = {zero, zero, zero, zero};
    {
        F seen = zero;
        for (int x = 0; x < usedCount; ++x) {
            const int k = used[x];
            for (int o = 0; o < 4; ++o)
                firstFour[o] = select(simd::andMask(out.valid[k], seen == F(float(o))), F(float(k)), firstFour[o]);
            seen = seen + select(out.valid[k], one, zero);
        }
    }
    for (int o = 0; o < 4; ++o) out.chosen[o] = firstFour[o];
    const auto reduce = count > F(4.0f);
    if (simd::none(reduce)) return;
    // The reduction is a few arg-max scans over the used slots: the first slot (in slot order) with the largest value
    // among the eligible ones, if it beats `start`. One pair at a time that is a branchy scan. In lanes the same
    // scan's compare-and-select chain through the running best was most of the clipping's time, so there the
    // candidates are set aside (independent per slot), then a running max, then the first slot that reaches it:
    // the same answer.
    constexpr bool kInLanes = !std::is_same_v<F, float>;
    F candidate[kInLanes ? kFaceSlots : 1];
    const F none(-1.0f);
    F scanBest = zero, scanIndex = none;
    const auto begin = [&](const F& start) { scanBest = start, scanIndex = none; };
    // Invalid slots, and values that are not numbers, never win.
    const auto offer = [&](int x, MaskOf<F> eligible, const F& value, const F& start) {
        if constexpr (kInLanes) {
            candidate[x] = select(simd::andMask(eligible, value == value), value, start);
        } else if (eligible && value > scanBest) {
            scanBest = value, scanIndex = float(used[x]);
        }
    };
    const auto firstLargest = [&](const F& start, F& index) {
        if constexpr (kInLanes) {
            F best = start;
            for (int x = 0; x < usedCount; ++x) best = simd::max(best, candidate[x]);
            index = none;
            for (int x = usedCount - 1; x >= 0; --x)
                index = select(simd::andMask(candidate[x] == best, candidate[x] > start), F(float(used[x])), index);
            return best;
        } else {
            index = scanIndex;
            return scanBest;
        }
    };
    F deepest(-INFINITY), su = zero, sv = zero;
    begin(deepest);
    for (int x = 0; x < usedCount; ++x) {
        const int k = used[x];
        offer(x, out.valid[k], out.depth[k], deepest);
        su = su + select(out.valid[k], out.u[k], zero), sv = sv + select(out.valid[k], out.v[k], zero);
    }
    {
        F unused;
        deepest = firstLargest(deepest, unused);
    }
    const F mu0 = su / count, mv0 = sv / count;
    F i0;
    begin(none);
    for (int x = 0; x < usedCount; ++x) {
        const int k = used[x];
        const F du = out.u[k] - mu0, dv = out.v[k] - mv0, d2 = du * du + dv * dv;
        offer(x, simd::andMask(out.valid[k], out.depth[k] >= deepest - F(kReductionDepthTie)), d2, none);
    }
    firstLargest(none, i0);
    // The plane coordinates of the slot chosen in each lane.
    const auto coordinatesOf = [&](const F& chosen, F& u, F& v) {
        u = zero, v = zero;
        for (int x = 0; x < usedCount; ++x) {
            const int k = used[x];
            const auto at = chosen == F(float(k));
            u = select(at, out.u[k], u), v = select(at, out.v[k], v);
        }
    };
    F u0, v0;
    coordinatesOf(i0, u0, v0);
    F i1;
    begin(none);
    for (int x = 0; x < usedCount; ++x) {
        const int k = used[x];
        const F du = out.u[k] - u0, dv = out.v[k] - v0, d2 = du * du + dv * dv;
        offer(x, simd::andMask(out.valid[k], i0 != F(float(k))), d2, none);
    }
    firstLargest(none, i1);
    F u1, v1;
    coordinatesOf(i1, u1, v1);
    const F eu = u1 - u0, ev = v1 - v0;
    F i2, orient = one;
    F areas[kFaceSlots];
    begin(none);
    for (int x = 0; x < usedCount; ++x) {
        const int k = used[x];
        areas[x] = eu * (out.v[k] - v0) - ev * (out.u[k] - u0);
        offer(x, simd::andMask(out.valid[k], simd::andMask(i0 != F(float(k)), i1 != F(float(k)))), abs(areas[x]), none);
    }
    firstLargest(none, i2);
    for (int x = 0; x < usedCount; ++x)
        orient = select(i2 == F(float(used[x])), select(areas[x] < zero, F(-1.0f), one), orient);
    F u2, v2;
    coordinatesOf(i2, u2, v2);
    const F tu[3] = {u0, u1, u2}, tv[3] = {v0, v1, v2};
    F i3;
    const F lowest(-3.4e38f);
    begin(lowest);
    for (int x = 0; x < usedCount; ++x) {
        const int k = used[x];
        F add(-3.4e38f);
        for (int e = 0; e < 3; ++e) {
            const int a = e, b = e == 2 ? 0 : e + 1;
            const F area = -orient * ((tu[b] - tu[a]) * (out.v[k] - tv[a]) - (tv[b] - tv[a]) * (out.u[k] - tu[a]));
            add = select(area > add, area, add);
        }
        const auto other = simd::andMask(i0 != F(float(k)), simd::andMask(i1 != F(float(k)), i2 != F(float(k))));
        offer(x, simd::andMask(out.valid[k], other), add, lowest);
    }
    firstLargest(lowest, i3);
    // Increasing order (a sorting network on the four).
    F sel[4] = {i0, i1, i2, i3};
    auto order = [&](int x, int y) {
        const F low = simd::min(sel[x], sel[y]), high = simd::max(sel[x], sel[y]);
        sel[x] = low, sel[y] = high;
    };
    order(0, 1), order(2, 3), order(0, 2), order(1, 3), order(1, 2);
    for (int o = 0; o < 4; ++o) out.chosen[o] = select(reduce, sel[o], firstFour[o]);
}

/// FaceSlots stored lane by lane ([slot][lane]) for reading one pair at a time.
template <std::size_t L>
struct FaceLanes {
    float u[kFaceSlots][L], v[kFaceSlots][L], w[kFaceSlots][L], depth[kFaceSlots][L];
    float chosen[4][L], count[L], axis[L], s[L], incidentFace[L];
};

template <class F>
void storeFace(const FaceSlots<F>& f, FaceLanes<simd::lanesOf<F>>& out) {
    for (int k = 0; k < kFaceSlots; ++k) {
        simd::store(out.u[k], f.u[k]), simd::store(out.v[k], f.v[k]), simd::store(out.w[k], f.w[k]);
        simd::store(out.depth[k], f.depth[k]);
    }
    for (int o = 0; o < 4; ++o) simd::store(out.chosen[o], f.chosen[o]);
    simd::store(out.count, f.count), simd::store(out.axis, f.axis), simd::store(out.s, f.s);
    simd::store(out.incidentFace, f.incidentFace);
}

/// The chosen points of the face contacts, moved from the reference frame to the world (onto B's surface when B's
/// face is the reference), and the normals, in lanes: the slots' values are gathered from the stored FaceLanes.
template <class F>
struct FacePoints {
    F x[4], y[4], z[4], depth[4], slot[4];
    F nx, ny, nz;
};

template <class F>
void facePoints(const FaceLanes<simd::lanesOf<F>>& f, const BoxSat<F>& sat, const Vec3W<F>& posA, const Vec3W<F>& posB,
                FacePoints<F>& out) {
    using simd::select;
    using I = simd::IntOf<F>;
    const F zero(0.0f), one(1.0f), two(2.0f);
    const auto useB = sat.useB;
    const F axis = simd::load<F>(f.axis), s = simd::load<F>(f.s);
    const F ku = select(axis == two, zero, axis + one);
    F R[3][3];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) R[r][c] = select(useB, sat.rb[r][c], sat.ra[r][c]);
    const F nl[3] = {select(axis == zero, s, zero), select(axis == one, s, zero), select(axis == two, s, zero)};
    F n[3];
    for (int r = 0; r < 3; ++r) {
        n[r] = R[r][0] * nl[0] + R[r][1] * nl[1] + R[r][2] * nl[2];
        n[r] = select(useB, -n[r], n[r]);
    }
    out.nx = n[0], out.ny = n[1], out.nz = n[2];
    const F origin[3] = {select(useB, posB.x, posA.x), select(useB, posB.y, posA.y), select(useB, posB.z, posA.z)};
    const I lanes(static_cast<std::int32_t>(simd::lanesOf<F>));
    const I lane = simd::toInt(simd::laneIndices<F>());
    const F count = simd::load<F>(f.count);
    for (int o = 0; o < 4; ++o) {
        if (simd::none(count > F(static_cast<float>(o)))) {  // no lane has an o-th point (or any later one)
            for (; o < 4; ++o) out.x[o] = out.y[o] = out.z[o] = out.depth[o] = out.slot[o] = zero;
            break;
        }
        const F slot = simd::load<F>(f.chosen[o]);
        const I index = simd::toInt(slot) * lanes + lane;
        const F u = simd::gather(&f.u[0][0], index), v = simd::gather(&f.v[0][0], index);
        const F depth = simd::gather(&f.depth[0][0], index);
        F w = simd::gather(&f.w[0][0], index);
        w = select(useB, w + s * depth, w);  // onto B's reference face (B's surface)
        F p[3];
        for (int c = 0; c < 3; ++c) {
            const F cf(static_cast<float>(c));
            p[c] = select(axis == cf, w, select(ku == cf, u, v));
        }
        out.x[o] = origin[0] + (R[0][0] * p[0] + R[0][1] * p[1] + R[0][2] * p[2]);
        out.y[o] = origin[1] + (R[1][0] * p[0] + R[1][1] * p[1] + R[1][2] * p[2]);
        out.z[o] = origin[2] + (R[2][0] * p[0] + R[2][1] * p[1] + R[2][2] * p[2]);
        out.depth[o] = depth, out.slot[o] = slot;
    }
}

/// FacePoints stored lane by lane.
template <std::size_t L>
struct FacePointLanes {
    float x[4][L], y[4][L], z[4][L], depth[4][L], slot[4][L];
    float nx[L], ny[L], nz[L];
};

template <class F>
void storePoints(const FacePoints<F>& p, FacePointLanes<simd::lanesOf<F>>& out) {
    for (int o = 0; o < 4; ++o) {
        simd::store(out.x[o], p.x[o]), simd::store(out.y[o], p.y[o]), simd::store(out.z[o], p.z[o]);
        simd::store(out.depth[o], p.depth[o]), simd::store(out.slot[o], p.slot[o]);
    }
    simd::store(out.nx, p.nx), simd::store(out.ny, p.ny), simd::store(out.nz, p.nz);
}

/// Lane k of the face contacts into a manifold.
template <std::size_t L>
bool emitFace(const FaceLanes<L>& f, const FacePointLanes<L>& p, std::size_t k, bool useB, Manifold& out) {
    const int axis = static_cast<int>(f.axis[k]);
    const int count = std::min(static_cast<int>(f.count[k]), 4);
    const std::uint32_t refFace = 2u * static_cast<std::uint32_t>(axis) + (f.s[k] < 0 ? 1u : 0u);
    const std::uint32_t base = ((useB ? kBoxFeatureFaceB : kBoxFeatureFaceA) << kBoxFeatureKindShift) |
                               (refFace << 16) | (static_cast<std::uint32_t>(f.incidentFace[k]) << 8);
    out.normal = {p.nx[k], p.ny[k], p.nz[k]};
    for (int o = 0; o < count; ++o) {
        out.points[o].position = {p.x[o][k], p.y[o][k], p.z[o][k]};
        out.points[o].depth = p.depth[o][k];
        out.points[o].feature = base | slotId(static_cast<int>(p.slot[o][k]));
    }
    out.pointCount = count;
    return count > 0;
}

/// The edge-edge contact of one pair whose SAT chose an edge axis: a single point.
bool finishEdge(const BoxSat<float>& sat, Vec3 posA, Vec3 halfA, Vec3 halfB, float margin, Manifold& out) {
    out.pointCount = 0;
    const float ha[3] = {halfA.x, halfA.y, halfA.z}, hb[3] = {halfB.x, halfB.y, halfB.z};
    const auto& r = sat.r;
    const auto& t = sat.t;
    const auto& ra = sat.ra;
    {
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
        float cb[3], depth = 0, apart2 = 0;
        for (int q = 0; q < 3; ++q) {
            cb[q] = pb[q] + w * r[q][j];
            const float ca = pa[q] + (q == i ? s : 0.0f);
            depth += (ca - cb[q]) * n[q];
            apart2 += (ca - cb[q]) * (ca - cb[q]);
        }
        // Apart, the depth is minus the distance of the closest points found: where an edge's end is closest it
        // exceeds the separation along the axis, and keepDistanceExact sees that the axis misstates the distance.
        if (depth < 0) depth = -std::sqrt(apart2);
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
    return false;
}

Vec3W<float> wide1(Vec3 v) { return {v.x, v.y, v.z}; }
QuatW<float> wide1(Quat q) { return {q.x, q.y, q.z, q.w}; }

/// The corner of a box nearest a point in its frame: bit 0 for +x, 1 for +y, 2 for +z.
std::uint32_t cornerNear(Vec3 local) {
    return (local.x > 0 ? 1u : 0u) | (local.y > 0 ? 2u : 0u) | (local.z > 0 ? 4u : 0u);
}

/// Boxes apart whose clipped contact misstates their distance (closest_points_contact.h) get the contact at their
/// closest points instead.
void keepDistanceExact(float bestSeparation, const Transform& a, Vec3 halfA, const Transform& b, Vec3 halfB,
                       float margin, Manifold& out) {
    const float size = maxf(maxf(maxf(halfA.x, halfA.y), maxf(halfA.z, halfB.x)), maxf(halfB.y, halfB.z));
    if (!misstatesDistance(out, bestSeparation, size)) return;
    GjkShape ga, gb;
    ga.core = gb.core = GjkShape::Core::Box;
    ga.halfExtents = halfA, gb.halfExtents = halfB;
    ga.pose = a, gb.pose = b;
    Vec3 localA, localB;
    if (!contactAtClosestPoints(ga, gb, margin, out, localA, localB)) return;
    out.points[0].feature =
        (kClosestPointsFeatureKind << kBoxFeatureKindShift) | (cornerNear(localA) << 8) | cornerNear(localB);
}

/// The contact of one pair (lane 0 of a float SAT): its edge-edge point or its clipped reference face.
bool finishOne(const BoxSat<float>& sat, const Transform& a, Vec3 halfA, const Transform& b, Vec3 halfB, float margin,
               Manifold& out) {
    if (sat.separated) {
        out.pointCount = 0;
        return false;
    }
    const Vec3 posA = a.position, posB = b.position;
    if (sat.useEdge) {
        finishEdge(sat, posA, halfA, halfB, margin, out);
    } else {
        FaceSlots<float> face;
        faceSlots<float>(sat, wide1(halfA), wide1(halfB), margin, face);
        FaceLanes<1> stored;
        storeFace(face, stored);
        FacePoints<float> points;
        facePoints<float>(stored, sat, wide1(posA), wide1(posB), points);
        FacePointLanes<1> storedPoints;
        storePoints(points, storedPoints);
        emitFace(stored, storedPoints, 0, sat.useB, out);
    }
    keepDistanceExact(maxf(sat.sepA, maxf(sat.sepB, sat.sepE)), a, halfA, b, halfB, margin, out);
    return out.pointCount > 0;
}

Transform poseA(const BoxPairs& in, std::size_t i) {
    return {{in.ax[i], in.ay[i], in.az[i]}, {in.aqx[i], in.aqy[i], in.aqz[i], in.aqw[i]}};
}
Transform poseB(const BoxPairs& in, std::size_t i) {
    return {{in.bx[i], in.by[i], in.bz[i]}, {in.bqx[i], in.bqy[i], in.bqz[i], in.bqw[i]}};
}

/// Pair i of a batch, one lane.
bool collideAt(const BoxPairs& in, std::size_t i, Manifold& out) {
    const Transform a = poseA(in, i), b = poseB(in, i);
    const Vec3 ha{in.ahx[i], in.ahy[i], in.ahz[i]}, hb{in.bhx[i], in.bhy[i], in.bhz[i]};
    BoxSat<float> sat;
    boxSat<float>(wide1(a.position), wide1(a.rotation), wide1(ha), wide1(b.position), wide1(b.rotation), wide1(hb),
                  in.margin[i], sat);
    return finishOne(sat, a, ha, b, hb, in.margin[i], out);
}

/// Pairs [i, i + kLanes): the axis tests and the face clipping in SIMD lanes, then each pair's manifold (an
/// edge-edge pair's single point on its own).
void collideWideAt(const BoxPairs& in, std::size_t i, std::size_t lanes, Manifold* out, const std::uint32_t* outIndex) {
    BoxSat<FloatW> sat;
    const Vec3W<FloatW> halfA = Vec3W<FloatW>::load(in.ahx, in.ahy, in.ahz, i);
    const Vec3W<FloatW> halfB = Vec3W<FloatW>::load(in.bhx, in.bhy, in.bhz, i);
    const FloatW margin = simd::load<FloatW>(in.margin + i);
    boxSat<FloatW>(Vec3W<FloatW>::load(in.ax, in.ay, in.az, i), QuatW<FloatW>::load(in.aqx, in.aqy, in.aqz, in.aqw, i),
                   halfA, Vec3W<FloatW>::load(in.bx, in.by, in.bz, i),
                   QuatW<FloatW>::load(in.bqx, in.bqy, in.bqz, in.bqw, i), halfB, margin, sat);
    if (simd::all(sat.separated)) {
        for (std::size_t k = 0; k < lanes; ++k) out[outIndex ? outIndex[i + k] : i + k].pointCount = 0;
        return;
    }
    constexpr int kValues = 3 * 9 + 3 + 8;
    alignas(64) float values[kValues][simd::kLanes];
    bool separated[simd::kLanes], useB[simd::kLanes], useEdge[simd::kLanes];
    alignas(64) float bestSeparation[simd::kLanes];
    simd::store(bestSeparation, simd::max(sat.sepA, simd::max(sat.sepB, sat.sepE)));
    int f = 0;
    if (simd::any(simd::andMask(sat.useEdge, simd::notMask(sat.separated))))  // only edge-edge pairs read them back
        forEachValue(sat, [&](FloatW& v) { simd::store(values[f++], v); });
    simd::storeMask(separated, sat.separated);
    simd::storeMask(useB, sat.useB);
    simd::storeMask(useEdge, sat.useEdge);
    alignas(64) FaceLanes<simd::kLanes> face;
    alignas(64) FacePointLanes<simd::kLanes> points;
    if (simd::any(simd::notMask(simd::orMask(sat.separated, sat.useEdge)))) {
        FaceSlots<FloatW> slots;
        faceSlots<FloatW>(sat, halfA, halfB, margin, slots);
        storeFace(slots, face);
        FacePoints<FloatW> wide;
        facePoints<FloatW>(face, sat, Vec3W<FloatW>::load(in.ax, in.ay, in.az, i),
                           Vec3W<FloatW>::load(in.bx, in.by, in.bz, i), wide);
        storePoints(wide, points);
    }
    for (std::size_t k = 0; k < lanes; ++k) {
        const std::size_t p = i + k;
        Manifold& m = out[outIndex ? outIndex[p] : p];
        if (separated[k]) {
            m.pointCount = 0;
            continue;
        }
        const Vec3 ha{in.ahx[p], in.ahy[p], in.ahz[p]}, hb{in.bhx[p], in.bhy[p], in.bhz[p]};
        if (!useEdge[k]) {
            emitFace(face, points, k, useB[k], m);
        } else {
            BoxSat<float> one;
            f = 0;
            forEachValue(one, [&](float& v) { v = values[f++][k]; });
            one.separated = false;
            one.useB = useB[k];
            one.useEdge = true;
            finishEdge(one, {in.ax[p], in.ay[p], in.az[p]}, ha, hb, in.margin[p], m);
        }
        keepDistanceExact(bestSeparation[k], poseA(in, p), ha, poseB(in, p), hb, in.margin[p], m);
    }
}

}  // namespace

bool collideBoxes(const Transform& a, Vec3 halfA, const Transform& b, Vec3 halfB, float margin, Manifold& out) {
    BoxSat<float> sat;
    boxSat<float>(wide1(a.position), wide1(a.rotation), wide1(halfA), wide1(b.position), wide1(b.rotation),
                  wide1(halfB), margin, sat);
    return finishOne(sat, a, halfA, b, halfB, margin, out);
}

void collideBoxesBatch(const BoxPairs& in, std::size_t n, Manifold* out, const std::uint32_t* outIndex, bool padded) {
    std::size_t i = 0;
    for (const std::size_t end = simd::roundDownToLanes<FloatW>(n); i < end; i += simd::kLanes)
        collideWideAt(in, i, simd::kLanes, out, outIndex);
    if (padded && i < n) {
        collideWideAt(in, i, n - i, out, outIndex);
        return;
    }
    for (; i < n; ++i) collideAt(in, i, out[outIndex ? outIndex[i] : i]);
}

void collideBoxesBatchScalar(const BoxPairs& in, std::size_t n, Manifold* out, const std::uint32_t* outIndex) {
    for (std::size_t i = 0; i < n; ++i) collideAt(in, i, out[outIndex ? outIndex[i] : i]);
}

}  // namespace rubble::detail
