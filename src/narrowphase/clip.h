#pragma once
// Polygon clipping and contact reduction shared by the polytope kernels (hull-hull, box-hull, capsule-hull):
// Sutherland-Hodgman clipping of an incident polygon against the side planes of a reference face, and reduction of
// the clipped polygon to at most four contact points (deepest point first, then the points that span the largest
// area). box_box.cpp keeps its own axis-aligned specialisation of the same steps.
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

/// Chooses at most four of `count` contact points (positions, depths) that keep the deepest point and span the
/// largest area in the plane of the orthonormal pair (u, v). Writes the chosen indices in increasing order (so
/// the order follows the clipped polygon and stays stable from step to step) and returns their number.
int reduceContactPoints(const Vec3* points, const float* depth, int count, Vec3 u, Vec3 v, int chosen[4]);

/// Orthonormal u, v with (u, v, n) right-handed, for unit n.
void planeBasis(Vec3 n, Vec3& u, Vec3& v);

}  // namespace rubble::detail
