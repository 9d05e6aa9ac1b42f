#include "narrowphase/hull_adjacencies.h"

#include "narrowphase/hull_pairs.h"

namespace rubble::detail {

HullAdjacencies::HullAdjacencies() = default;
HullAdjacencies::~HullAdjacencies() = default;

void HullAdjacencies::ensure(const std::shared_ptr<const ConvexHull>& hull) {
    Entry& entry = entries_[hull.get()];
    if (!entry.adjacency) {
        entry.hull = hull;
        entry.adjacency = std::make_unique<HullAdjacency>(buildHullAdjacency(*hull));
    }
}

void HullAdjacencies::prepare(const std::vector<Shape>& shapes) {
    known_.resize(shapes.size(), nullptr);
    for (std::size_t s = 0; s < shapes.size(); ++s) {
        const Shape& shape = shapes[s];
        if (shape.kind == ShapeKind::ConvexHull && shape.hull && known_[s] != shape.hull.get()) {
            ensure(shape.hull);
            known_[s] = shape.hull.get();
        } else if (shape.kind == ShapeKind::Compound) {
            for (const CompoundChild& child : shape.children)
                if (child.shape->kind == ShapeKind::ConvexHull) ensure(child.shape->hull);
        }
    }
}

}  // namespace rubble::detail
