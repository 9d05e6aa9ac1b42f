#pragma once
// Polygon clipping and contact reduction shared by the polytope kernels (hull-hull, box-hull, capsule-hull):
// Sutherland-Hodgman clipping of an incident polygon against the side planes of a reference face, and reduction of
// the clipped polygon to at most four contact points (deepest point first, then the points that span the largest
// area; box_box.cpp runs the same selection, written for SIMD lanes, on its box-frame coordinates).
#include <cstdint>

#include "rubble/math.h"

namespace rubble::detail {

/// A vertex of a polygon being clipped. `id` names the point for feature ids; `label` names the polygon edge that
/// starts at this vertex (so that a point created on that edge can say which edge and which plane made it).
struct ClipVertex {
    Vec3 p;
    std::uint16_t id = 0;
    std::uint16_t label = 0;
};

/// Largest polygon the clipper keeps; vertices beyond it are dropped (only for faces with dozens of sides).
inline constexpr int kClipCapacity = 64;

/// Id of a point made where polygon edge `label` crosses side plane `plane`: bit 15 set, label in bits 6-14 ...
inline constexpr std::uint16_t clipPointId(int label, int plane) {
    return static_cast<std::uint16_t>(0x8000u | ((static_cast<unsigned>(label) & 0x1FFu) << 6) |
                                      (static_cast<unsigned>(plane) & 0x3Fu));
}
/// ... and the label of a polygon edge that runs along side plane `plane` (after the incident labels).
inline constexpr std::uint16_t sidePlaneLabel(int plane) { return static_cast<std::uint16_t>(0x100 | (plane & 0xFF)); }

/// Keeps the part of polygon `in` (n vertices, any winding) with dot(normal, p) <= offset; writes to `out`
/// (capacity kClipCapacity) and returns the new count. `normal` need not be unit length. New points lie exactly
/// on the plane up to rounding and get id clipPointId(edge label, plane); the new edge along the plane gets
/// sidePlaneLabel(plane).
int clipPolygon(const ClipVertex* in, int n, ClipVertex* out, Vec3 normal, float offset, int plane);

/// Depths this close to the deepest count as tied for the first reduced point, m: between faces resting flat on
/// each other every point is equally deep, and the first point must then be a corner of the polygon, not a point in
/// the middle of an edge, or the four points cover only part of the face and the body rocks.
inline constexpr float kReductionDepthTie = 1e-3f;

/// Chooses four of `count` (> 4) contact points, given their depths and their coordinates (pu(k), pv(k)) in the
/// contact plane: the deepest point (of those tied for deepest, the one farthest from the points' centroid), the
/// point farthest from it, then the two points that add the most area. Writes the indices in increasing order, so
/// that the order follows the clipped polygon and stays stable from step to step.
template <class U, class V>
void chooseFourPoints(int count, const float* depth, U pu, V pv, int chosen[4]) {
    float deepest = depth[0], cu = 0, cv = 0;
    for (int k = 0; k < count; ++k) deepest = depth[k] > deepest ? depth[k] : deepest, cu += pu(k), cv += pv(k);
    cu /= static_cast<float>(count), cv /= static_cast<float>(count);
    int i0 = -1;
    float best = -1;
    for (int k = 0; k < count; ++k) {
        if (depth[k] < deepest - kReductionDepthTie) continue;
        const float du = pu(k) - cu, dv = pv(k) - cv;
        if (du * du + dv * dv > best) best = du * du + dv * dv, i0 = k;
    }
    int i1 = i0 == 0 ? 1 : 0;
    best = -1;
    for (int k = 0; k < count; ++k) {
        const float du = pu(k) - pu(i0), dv = pv(k) - pv(i0);
        const float d2 = du * du + dv * dv;
        if (k != i0 && d2 > best) best = d2, i1 = k;
    }
    // Third: largest triangle with the first two (either side of their line); orient it counter-clockwise.
    const float eu = pu(i1) - pu(i0), ev = pv(i1) - pv(i0);
    int i2 = -1;
    float bestArea = -1, orient = 1;
    for (int k = 0; k < count; ++k) {
        if (k == i0 || k == i1) continue;
        const float area = eu * (pv(k) - pv(i0)) - ev * (pu(k) - pu(i0));
        const float size = area < 0 ? -area : area;
        if (size > bestArea) bestArea = size, i2 = k, orient = area < 0 ? -1.0f : 1.0f;
    }
    // Fourth: the point farthest outside one of the triangle's edges, i.e. adding the most area.
    const int tri[3] = {i0, i1, i2};
    int i3 = -1;
    float bestAdd = -3.4e38f;
    for (int k = 0; k < count; ++k) {
        if (k == i0 || k == i1 || k == i2) continue;
        float add = -3.4e38f;
        for (int e = 0; e < 3; ++e) {
            const int pa = tri[e], pb = tri[e == 2 ? 0 : e + 1];
            const float area = -orient * ((pu(pb) - pu(pa)) * (pv(k) - pv(pa)) - (pv(pb) - pv(pa)) * (pu(k) - pu(pa)));
            add = area > add ? area : add;
        }
        if (add > bestAdd) bestAdd = add, i3 = k;
    }
    int sel[4] = {i0, i1, i2, i3};
    for (int x = 1; x < 4; ++x)
        for (int y = x; y > 0 && sel[y] < sel[y - 1]; --y) {
            const int tmp = sel[y];
            sel[y] = sel[y - 1];
            sel[y - 1] = tmp;
        }
    for (int k = 0; k < 4; ++k) chosen[k] = sel[k];
}

/// Chooses at most four of `count` contact points (positions, depths) with chooseFourPoints, measuring in the plane
/// of the orthonormal pair (u, v), and returns their number.
int reduceContactPoints(const Vec3* points, const float* depth, int count, Vec3 u, Vec3 v, int chosen[4]);

/// Orthonormal u, v with (u, v, n) right-handed, for unit n.
void planeBasis(Vec3 n, Vec3& u, Vec3& v);

}  // namespace rubble::detail
