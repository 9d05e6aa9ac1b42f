#pragma once
// The contacts of a step: what the narrow phase finds (one manifold per touching or nearly touching pair), and what
// the contact cache, the islands and the solver read after it.
#include <cstdint>
#include <vector>

#include "narrowphase/manifold.h"

namespace rubble::detail {

/// In ContactPair::childA / childB: the side is not a compound.
inline constexpr std::uint16_t kNoChild = 0xFFFF;

/// The two bodies of a manifold, in the order the kernel saw them: A has the lower ShapeKind, so the normal
/// points from A to B. Each side is a dense index into MovingBodies, or into StaticBodies when flagged static;
/// for a compound, `childA` / `childB` name the child whose shape made the contact.
struct ContactPair {
    std::uint32_t a = 0;
    std::uint32_t b = 0;
    bool aStatic = false;
    bool bStatic = false;
    /// For a body against a static mesh or heightfield (B): the triangle; ~0u otherwise.
    std::uint32_t triangle = ~0u;
    std::uint16_t childA = kNoChild;
    std::uint16_t childB = kNoChild;
};

/// The stage's output: one manifold (with at least one point) per touching or nearly touching pair.
struct Contacts {
    std::vector<ContactPair> pairs;
    std::vector<Manifold> manifolds;
    std::uint32_t pointCount = 0;

    void clear() {
        pairs.clear();
        manifolds.clear();
        pointCount = 0;
    }
};

}  // namespace rubble::detail
