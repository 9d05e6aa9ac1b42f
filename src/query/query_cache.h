#pragma once
// What the scene queries read: the broad phase's static BVH (static bodies and the triangles of static meshes and
// heightfields), with the static edits made since the last step applied, and a tree over the moving bodies' boxes
// at their current poses. Both are brought up to date by the first query after the world changed (a step, or a
// body created, removed or moved through the API) and only read by the queries after it, so const queries can run
// on several threads at once.
//
// The moving bodies' tree is built by StaticBvh's SAH builder over their dense indices and then refitted, not
// rebuilt: bodies move little between steps, and a refit (boxes from the SIMD bounds kernel, then one backward pass
// over the nodes) costs a small fraction of a build. Bodies that come and go are absorbed the way the static BVH
// absorbs edits: a removal swaps the last body into the hole, so the tree's leaves of indices past the end get
// empty boxes; indices added past the built count go into a small extra tree, rebuilt on each update. A full
// rebuild follows when the extras exceed 1/8 of the built count, the empty leaves 1/4 of it, or the refitted tree's
// SAH cost has grown by half over the fresh build's. So a game that spawns a body every frame pays a refit and a
// tiny build per frame, and a full build every n/8 spawns.
#include <atomic>
#include <cstdint>
#include <mutex>
#include <span>

#include "broadphase/broadphase.h"
#include "broadphase/static_bvh.h"
#include "rubble/world.h"

namespace rubble::detail {

/// The trees a query walks. Valid until the next non-const World call.
struct QueryTrees {
    /// The static BVH's parts; primitives name static bodies by slot.
    std::span<const StaticBvh::Tree* const> statics;
    float staticScale = 0;  ///< StaticBvh::scale()
    /// Trees over the moving bodies' current boxes (the refitted one and the extra one of bodies added since it was
    /// built); primitives name moving bodies by dense index.
    const StaticBvh::Tree* moving[2] = {nullptr, nullptr};
    float movingScale = 0;
};

class QueryCache {
public:
    /// World calls that add, remove or move a body between steps call this; the next query brings the trees up to
    /// date. (Steps are noticed through the world's step count.)
    void bodiesChanged() { ++edits_; }

    /// The trees, up to date with `world`. The first caller after a change does the work under a lock; every other
    /// caller only reads.
    const QueryTrees& prepare(World::Impl& world);

private:
    void update(World::Impl& world);
    /// Builds `tree` over the boxes of dense indices [begin, boxes_.size()).
    void build(StaticBvh::Tree& tree, std::uint32_t begin, World::Impl& world);

    std::mutex mutex_;
    std::atomic<std::uint64_t> builtVersion_{~std::uint64_t{0}};
    std::uint64_t edits_ = 0;  ///< written by non-const World calls only, never during a query
    QueryTrees trees_;
    StaticBvh::Tree moving_;  ///< over dense indices [0, builtCount_)
    StaticBvh::Tree extra_;   ///< over dense indices [builtCount_, moving body count)
    Bounds boxes_;            ///< moving bodies' boxes at their current poses, dense order
    std::uint32_t builtCount_ = 0;
    double builtCost_ = 0;
};

}  // namespace rubble::detail
