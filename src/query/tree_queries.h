#pragma once
// Queries over the four-wide trees of StaticBvh: the broad phase's static tree (read as it is, never edited) and the
// queries' own tree over the moving bodies, which is built by the same code and refitted here.
//  - sweepTree: a box swept along a ray (a ray is a box of zero extent), children visited nearest entry first and
//    pruned against a range that the caller shrinks as it finds hits, so a closest-hit query stops early;
//  - overlapTree: every primitive whose box overlaps a query box.
// Float boxes are not exact: corners are rounded when they are computed and the slab test rounds again. A pad of a
// few ulps of the coordinates involved (boxPad) makes every test conservative; the exact shape tests decide.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "broadphase/broadphase.h"
#include "broadphase/static_bvh.h"
#include "rubble/math.h"

namespace rubble::detail {

/// Largest finite |coordinate| of the tree's root box (0 for an empty tree): the scale its float boxes round at.
float treeScale(const StaticBvh::Tree& tree);

/// Pad for boxes around coordinates up to `scale`: about eight float ulps.
/// Finite whatever the scale: an infinite pad would turn an unused lane's empty box (+inf..-inf) into NaN and let the
/// walk enter it (a query from 1e38 m did).
inline float boxPad(float scale) { return std::min(1e-6f * scale + 1e-30f, std::numeric_limits<float>::max()); }

/// A box of half extents `extent` swept from `origin` along the unit direction `dir`, with `pad` added to every box
/// it is tested against.
class TreeSweep {
public:
    TreeSweep(Vec3 origin, Vec3 dir, Vec3 extent, float pad);

    /// Bit k set when child k of `node` is entered within [0, maxT]; enter[k] is where.
    unsigned test(const StaticBvh::Node& node, float maxT, float (&enter)[4]) const {
        unsigned mask = 0;
        for (int k = 0; k < 4; ++k) {
            float tEnter = 0, tExit = maxT;
            for (int a = 0; a < 3; ++a) {
                const float lo = node.lo[4 * a + k] - extent_[a], hi = node.hi[4 * a + k] + extent_[a];
                // Near and far sides picked by the sign of the direction, not by min/max of the two: an empty lane
                // (lo = +inf, hi = -inf) then gives an entry of +inf and an exit of -inf and is never entered.
                const float nearSide = negative_[a] ? hi : lo, farSide = negative_[a] ? lo : hi;
                tEnter = std::max(tEnter, (nearSide - origin_[a]) * inverse_[a]);
                tExit = std::min(tExit, (farSide - origin_[a]) * inverse_[a]);
            }
            enter[k] = tEnter;
            mask |= unsigned(tEnter <= tExit) << k;
        }
        return mask;
    }

private:
    float origin_[3], inverse_[3], extent_[3];
    bool negative_[3];
};

/// A stack that lives on the call stack for trees of sane depth and on the heap beyond, so that concurrent queries
/// share no scratch and the common case allocates nothing.
template <class T, std::size_t N>
class ScratchStack {
public:
    explicit ScratchStack(std::size_t capacity) {
        if (capacity > N) {
            heap_.resize(capacity);
            data_ = heap_.data();
        }
    }
    ScratchStack(const ScratchStack&) = delete;
    ScratchStack& operator=(const ScratchStack&) = delete;
    T& operator[](std::size_t i) { return data_[i]; }

private:
    T inline_[N];
    std::vector<T> heap_;
    T* data_ = inline_;
};

/// Calls onPrimitive(ref, enter) for every primitive whose box the sweep enters within [0, maxT], nearest entry
/// first within each node, subtrees nearest first. onPrimitive may lower maxT (through the reference the caller
/// passed in); subtrees and primitives entered beyond it are skipped.
template <class OnPrimitive>
void sweepTree(const StaticBvh::Tree& tree, const TreeSweep& sweep, const float& maxT, OnPrimitive&& onPrimitive) {
    if (tree.nodes.empty()) return;
    struct Entry {
        std::uint32_t node;
        float t;
    };
    // Each visit pops one node and pushes at most four.
    ScratchStack<Entry, 192> stack(3 * std::size_t(tree.depth) + 2);
    std::size_t top = 0;
    stack[top++] = {0, 0.0f};
    while (top > 0) {
        const Entry e = stack[--top];
        if (e.t > maxT) continue;
        const StaticBvh::Node& node = tree.nodes[e.node];
        float enter[4];
        unsigned mask = sweep.test(node, maxT, enter);
        int order[4], count = 0;
        for (; mask != 0; mask &= mask - 1) {
            const int k = __builtin_ctz(mask);
            int i = count++;
            for (; i > 0 && enter[order[i - 1]] > enter[k]; --i) order[i] = order[i - 1];
            order[i] = k;
        }
        for (int i = 0; i < count; ++i) {
            const std::uint32_t c = node.child(order[i]);
            if ((c & StaticBvh::kPrimitiveBit) != 0 && enter[order[i]] <= maxT)
                onPrimitive(tree.primitives[c & ~StaticBvh::kPrimitiveBit], enter[order[i]]);
        }
        for (int i = count - 1; i >= 0; --i) {
            const std::uint32_t c = node.child(order[i]);
            if ((c & StaticBvh::kPrimitiveBit) == 0) stack[top++] = {c, enter[order[i]]};
        }
    }
}

/// Calls onPrimitive(ref) for every primitive whose box overlaps [lo, hi] (closed intervals).
template <class OnPrimitive>
void overlapTree(const StaticBvh::Tree& tree, Vec3 lo, Vec3 hi, OnPrimitive&& onPrimitive) {
    if (tree.nodes.empty()) return;
    ScratchStack<std::uint32_t, 192> stack(3 * std::size_t(tree.depth) + 2);
    std::size_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const StaticBvh::Node& node = tree.nodes[stack[--top]];
        for (int k = 0; k < 4; ++k) {
            const bool hit = lo.x <= node.hi[k] && node.lo[k] <= hi.x && lo.y <= node.hi[4 + k] &&
                             node.lo[4 + k] <= hi.y && lo.z <= node.hi[8 + k] && node.lo[8 + k] <= hi.z;
            if (!hit) continue;  // empty lanes (lo = +inf) never pass
            const std::uint32_t c = node.child(k);
            if ((c & StaticBvh::kPrimitiveBit) != 0)
                onPrimitive(tree.primitives[c & ~StaticBvh::kPrimitiveBit]);
            else
                stack[top++] = c;
        }
    }
}

/// Recomputes every box of `tree` bottom-up, primitive lanes from boxes[primitive body], and an empty box for bodies
/// past boxes.size() (removed since the build). The topology stays; the builder numbers every child after its
/// parent, so one backward pass sees children first. Returns sahCost().
double refitTree(StaticBvh::Tree& tree, const Bounds& boxes);

/// Expected cost of a small random query under the surface area heuristic, as StaticBvhStats::sahCost: 1 for the
/// root plus every lane's area relative to the root's. A refitted tree whose cost grew much is worth rebuilding.
double sahCost(const StaticBvh::Tree& tree);

}  // namespace rubble::detail
