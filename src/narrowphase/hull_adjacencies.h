#pragma once
// The edge-face adjacency of every hull the narrow phase has met (the hull kernels' Gauss-map pruning needs it),
// built before the parallel work so that the kernels only read it.
#include <memory>
#include <unordered_map>
#include <vector>

#include "shapes/shape.h"

namespace rubble::detail {

struct HullAdjacency;

class HullAdjacencies {
public:
    HullAdjacencies();
    ~HullAdjacencies();
    HullAdjacencies(const HullAdjacencies&) = delete;
    HullAdjacencies& operator=(const HullAdjacencies&) = delete;

    /// Builds the adjacency of every hull a shape holds (a compound's children's included) that has none yet.
    void prepare(const std::vector<Shape>& shapes);
    /// The adjacency of a hull that prepare() has seen.
    const HullAdjacency& of(const ConvexHull& hull) const { return *entries_.at(&hull).adjacency; }

private:
    void ensure(const std::shared_ptr<const ConvexHull>& hull);

    /// Per shape slot: the hull whose adjacency is known to be here, so that the common case (hull seen before) is
    /// one comparison. A hull in the map is kept alive by it, so an equal address is the same hull.
    std::vector<const ConvexHull*> known_;
    /// Each entry keeps its hull alive, so a hull's address cannot be reused by another while it is a key.
    struct Entry {
        std::shared_ptr<const ConvexHull> hull;
        std::unique_ptr<HullAdjacency> adjacency;
    };
    std::unordered_map<const ConvexHull*, Entry> entries_;
};

}  // namespace rubble::detail
