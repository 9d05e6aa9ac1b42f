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
    chooseFourPoints(
        count, depth, [&](int k) { return coordU[k]; }, [&](int k) { return coordV[k]; }, chosen);
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
