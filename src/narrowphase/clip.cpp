// Sutherland-Hodgman clipping and four-point contact reduction; see clip.h.
#include "narrowphase/clip.h"

#include <cmath>

namespace rubble::detail {

int clipPolygon(const ClipVertex* in, int n, ClipVertex* out, Vec3 normal, float offset, int plane) {
    int m = 0;
    for (int e = 0; e < n && m + 2 <= kClipCapacity; ++e) {
        const ClipVertex& c = in[e];
        const ClipVertex& d = in[e + 1 == n ? 0 : e + 1];
        const float dc = dot(normal, c.p) - offset, dd = dot(normal, d.p) - offset;
        const bool cIn = dc <= 0, dIn = dd <= 0;
        if (cIn) out[m++] = c;
        if (cIn != dIn) {
            // dc and dd have opposite signs (one may be zero only when cIn), so the division is safe.
            const float s = dc / (dc - dd);
            ClipVertex& x = out[m++];
            x.p = c.p + (d.p - c.p) * s;
            x.id = clipPointId(c.label, plane);
            x.label = cIn ? sidePlaneLabel(plane) : c.label;
        }
    }
    return m;
}

int reduceContactPoints(const Vec3* points, const float* depth, int count, Vec3 u, Vec3 v, int chosen[4]) {
    if (count <= 4) {
        for (int k = 0; k < count; ++k) chosen[k] = k;
        return count;
    }
    // Each point projected once: the selection below reads these coordinates many times.
    float coordU[kClipCapacity], coordV[kClipCapacity];
    count = count < kClipCapacity ? count : kClipCapacity;
    for (int k = 0; k < count; ++k) coordU[k] = dot(points[k], u), coordV[k] = dot(points[k], v);
    auto pu = [&](int k) { return coordU[k]; };
    auto pv = [&](int k) { return coordV[k]; };
    // Deepest point first: it carries the most important constraint.
    int i0 = 0;
    for (int k = 1; k < count; ++k) i0 = depth[k] > depth[i0] ? k : i0;
    // Second: farthest from the first in the plane.
    int i1 = i0 == 0 ? 1 : 0;
    float best = -1;
    for (int k = 0; k < count; ++k) {
        const float du = pu(k) - pu(i0), dv = pv(k) - pv(i0);
        const float d2 = du * du + dv * dv;
        if (k != i0 && d2 > best) best = d2, i1 = k;
    }
    // Third: largest triangle with the first two (either side of their line).
    const float eu = pu(i1) - pu(i0), ev = pv(i1) - pv(i0);
    int i2 = -1;
    float bestArea = -1, orient = 1;
    for (int k = 0; k < count; ++k) {
        if (k == i0 || k == i1) continue;
        const float area = eu * (pv(k) - pv(i0)) - ev * (pu(k) - pu(i0));
        if (std::fabs(area) > bestArea) bestArea = std::fabs(area), i2 = k, orient = area < 0 ? -1.0f : 1.0f;
    }
    // Fourth: the point adding the most area, i.e. farthest outside one of the triangle's edges.
    const int tri[3] = {i0, i1, i2};
    int i3 = -1;
    float bestAdd = -INFINITY;
    for (int k = 0; k < count; ++k) {
        if (k == i0 || k == i1 || k == i2) continue;
        float add = -INFINITY;
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
    return 4;
}

void planeBasis(Vec3 n, Vec3& u, Vec3& v) {
    // Branch on the smallest component so that the cross product is well conditioned.
    const Vec3 t = std::fabs(n.x) < 0.57f ? Vec3{1, 0, 0} : (std::fabs(n.y) < 0.57f ? Vec3{0, 1, 0} : Vec3{0, 0, 1});
    u = cross(t, n);
    u = u / length(u);
    v = cross(n, u);
}

}  // namespace rubble::detail
