// Tree queries: the sweep set-up, the refit of the moving bodies' tree and its quality measure.
#include "query/tree_queries.h"

#include <cmath>
#include <limits>
#include <vector>

namespace rubble::detail {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

double halfArea(const Aabb& b) {
    const double dx = double(b.max.x) - b.min.x, dy = double(b.max.y) - b.min.y, dz = double(b.max.z) - b.min.z;
    if (!(dx >= 0 && dy >= 0 && dz >= 0)) return 0;  // empty lanes and tombstones cost nothing
    return dx * dy + dy * dz + dz * dx;
}

}  // namespace

TreeSweep::TreeSweep(Vec3 origin, Vec3 dir, Vec3 extent, float pad) {
    const float o[3] = {origin.x, origin.y, origin.z}, d[3] = {dir.x, dir.y, dir.z},
                e[3] = {extent.x, extent.y, extent.z};
    for (int a = 0; a < 3; ++a) {
        origin_[a] = o[a];
        extent_[a] = e[a] + pad;
        negative_[a] = std::signbit(d[a]);
        // A zero component would make 0 * inf = NaN on a slab through the origin; 1e-30 behaves as zero for any
        // distance a float can hold and keeps every product a number.
        const float safe = std::fabs(d[a]) < 1e-30f ? std::copysign(1e-30f, d[a]) : d[a];
        inverse_[a] = 1.0f / safe;
    }
}

float treeScale(const StaticBvh::Tree& tree) {
    if (tree.nodes.empty()) return 0;
    float scale = 0;
    const StaticBvh::Node& root = tree.nodes[0];
    for (int i = 0; i < 12; ++i) {
        if (std::isfinite(root.lo[i])) scale = std::max(scale, std::fabs(root.lo[i]));
        if (std::isfinite(root.hi[i])) scale = std::max(scale, std::fabs(root.hi[i]));
    }
    return scale;
}

double refitTree(StaticBvh::Tree& tree, const Bounds& boxes) {
    // Leaves name bodies in spatial order, not memory order: packing each box into one record first makes every
    // random read below one cache miss instead of six.
    std::vector<Aabb> packed(boxes.size());
    for (std::uint32_t b = 0; b < boxes.size(); ++b)
        packed[b] = {{boxes.minX[b], boxes.minY[b], boxes.minZ[b]}, {boxes.maxX[b], boxes.maxY[b], boxes.maxZ[b]}};
    for (std::size_t i = tree.nodes.size(); i-- > 0;) {
        StaticBvh::Node& node = tree.nodes[i];
        for (int k = 0; k < 4; ++k) {
            const std::uint32_t c = node.child(k);
            if (c == StaticBvh::kUnusedLane) continue;
            Aabb box{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};
            if ((c & StaticBvh::kPrimitiveBit) != 0) {
                const std::uint32_t body = tree.primitives[c & ~StaticBvh::kPrimitiveBit].body;
                if (body < packed.size()) box = packed[body];
            } else {
                const StaticBvh::Node& child = tree.nodes[c];
                for (int j = 0; j < 4; ++j) {
                    box.min = {std::min(box.min.x, child.lo[j]), std::min(box.min.y, child.lo[4 + j]),
                               std::min(box.min.z, child.lo[8 + j])};
                    box.max = {std::max(box.max.x, child.hi[j]), std::max(box.max.y, child.hi[4 + j]),
                               std::max(box.max.z, child.hi[8 + j])};
                }
            }
            node.setBox(k, box);
        }
    }
    return sahCost(tree);
}

double sahCost(const StaticBvh::Tree& tree) {
    if (tree.nodes.empty()) return 0;
    Aabb root{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};
    for (int k = 0; k < 4; ++k) {
        const Aabb b = tree.nodes[0].box(k);
        if (!(b.min.x <= b.max.x)) continue;
        root.min = {std::min(root.min.x, b.min.x), std::min(root.min.y, b.min.y), std::min(root.min.z, b.min.z)};
        root.max = {std::max(root.max.x, b.max.x), std::max(root.max.y, b.max.y), std::max(root.max.z, b.max.z)};
    }
    double rootArea = halfArea(root);
    if (!(rootArea > 0)) rootArea = 1;
    double cost = 1;
    for (const StaticBvh::Node& n : tree.nodes)
        for (int k = 0; k < 4; ++k)
            if (n.child(k) != StaticBvh::kUnusedLane) cost += halfArea(n.box(k)) / rootArea;
    return cost;
}

}  // namespace rubble::detail
