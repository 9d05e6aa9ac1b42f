#pragma once
// Contact cache: manifolds persist across steps. Each step's manifolds are matched with last step's by body pair
// (stable slots and generations, the compound children and the mesh triangle) and, within a manifold, points by
// feature id, or failing that by position (a point within kContactMatchDistance of where an unmatched old point
// was: the kernels may describe the same corner by other features when the reference face flips between two
// equal boxes, and a stack that lost its impulses there would drop). Matched points carry their accumulated
// impulses so that the solver can warm start. Pairs that separate are simply not matched again and are forgotten.
#include <cstdint>
#include <vector>

#include "body_storage.h"
#include "narrowphase/narrowphase_stage.h"

namespace rubble::detail {

class TaskPool;

/// Accumulated impulses of one contact point (normal, and the two friction directions of the contact basis).
struct PointImpulse {
    float normal = 0;
    float tangent1 = 0;
    float tangent2 = 0;
};

/// Identity of a manifold across steps.
struct ContactKey {
    std::uint64_t slots = 0;        ///< slot of A << 32 | slot of B (one slot map covers moving and static bodies)
    std::uint64_t generations = 0;  ///< so that a body reusing a slot does not inherit another's contacts
    std::uint64_t parts = 0;        ///< triangle << 32 | child of A << 16 | child of B
    friend bool operator==(const ContactKey& x, const ContactKey& y) {
        return x.slots == y.slots && x.generations == y.generations && x.parts == y.parts;
    }
};

/// How far a contact point may have moved in one step and still be the same point, m.
inline constexpr float kContactMatchDistance = 0.02f;

class ContactCache {
public:
    /// Impulses for this step's manifolds: kMaxManifoldPoints per manifold, in `contacts` order, carried over from
    /// last step where the manifold and the point's feature id match, zero elsewhere.
    void warmStart(const Contacts& contacts, const BodyStorage& storage, TaskPool& pool,
                   std::vector<PointImpulse>& impulses);
    /// Keeps this step's manifolds and their final impulses for the next step (call after the solver).
    void remember(const Contacts& contacts, const std::vector<PointImpulse>& impulses, TaskPool& pool);

    std::uint32_t matchedManifolds() const { return matchedManifolds_; }
    std::uint32_t matchedPoints() const { return matchedPoints_; }
    std::uint32_t size() const { return static_cast<std::uint32_t>(previous_.size()); }

private:
    struct Entry {
        ContactKey key;
        std::uint32_t features[kMaxManifoldPoints] = {};
        Vec3 positions[kMaxManifoldPoints];
        PointImpulse impulses[kMaxManifoldPoints];
        int pointCount = 0;
    };
    std::vector<ContactKey> currentKeys_;  ///< keys of the manifolds passed to warmStart, for remember
    std::vector<Entry> previous_;
    std::vector<std::uint32_t> table_;  ///< open addressing over previous_: index + 1, 0 = empty
    std::uint32_t matchedManifolds_ = 0, matchedPoints_ = 0;
};

}  // namespace rubble::detail
