// Keeps the queries' trees current: see query_cache.h.
#include "query/query_cache.h"

#include <algorithm>
#include <utility>
#include <vector>

#include "query/tree_queries.h"
#include "world/world_impl.h"

namespace rubble::detail {
namespace {

/// A refitted tree is rebuilt once its SAH cost exceeds the fresh build's by this factor: queries then visit about
/// half as many nodes again as they would in a fresh tree, which costs more over a step's queries than a rebuild.
constexpr double kRebuildCostRatio = 1.5;

}  // namespace

const QueryTrees& QueryCache::prepare(World::Impl& world) {
    // Steps and edits only grow, so their sum names the world's state; it changes only in non-const calls, which
    // never run during a query.
    const std::uint64_t version = world.steps + edits_;
    if (builtVersion_.load(std::memory_order_acquire) == version) return trees_;
    const std::lock_guard<std::mutex> lock(mutex_);
    if (builtVersion_.load(std::memory_order_relaxed) != version) {
        update(world);
        builtVersion_.store(version, std::memory_order_release);
    }
    return trees_;
}

void QueryCache::update(World::Impl& world) {
    const StaticBvh& bvh = world.broadPhase.staticBvh(*world.pool);
    trees_.statics = bvh.trees();
    trees_.staticScale = bvh.scale();

    const std::uint32_t n = world.bodies.moving.size();
    if (n == 0) {
        moving_ = StaticBvh::Tree{};
        extra_ = StaticBvh::Tree{};
        builtCount_ = 0;
    } else {
        // Exact boxes at the current poses: the step's boxes are swept and were computed before the bodies moved.
        updateBounds(world.bodies.moving, world.shapeBounds, BoundsParams{0.0f, 0.0f}, *world.pool, boxes_);
        bool rebuild = moving_.nodes.empty() || n > builtCount_ + builtCount_ / 8 || n + builtCount_ / 4 < builtCount_;
        if (!rebuild) rebuild = refitTree(moving_, boxes_) > kRebuildCostRatio * builtCost_;
        if (rebuild) {
            build(moving_, 0, world);
            builtCount_ = n;
            builtCost_ = sahCost(moving_);
            extra_ = StaticBvh::Tree{};
        } else if (n > builtCount_) {
            build(extra_, builtCount_, world);
        } else {
            extra_ = StaticBvh::Tree{};
        }
    }
    trees_.moving[0] = &moving_;
    trees_.moving[1] = &extra_;
    trees_.movingScale = std::max(treeScale(moving_), treeScale(extra_));
}

void QueryCache::build(StaticBvh::Tree& tree, std::uint32_t begin, World::Impl& world) {
    const std::uint32_t end = boxes_.size();
    std::vector<StaticPrimitive> primitives;
    primitives.reserve(end - begin);
    for (std::uint32_t i = begin; i < end; ++i)
        primitives.push_back(
            {{{boxes_.minX[i], boxes_.minY[i], boxes_.minZ[i]}, {boxes_.maxX[i], boxes_.maxY[i], boxes_.maxZ[i]}},
             i,
             kWholeBody});
    StaticBvh::buildTree(tree, primitives, world.pool.get());
}

}  // namespace rubble::detail
