#pragma once
// Contact cache: manifolds persist across steps. Each step's manifolds are matched with last step's by body pair
// (stable slots and generations, the compound children and the mesh triangle) and, within a manifold, points by
// feature id, or failing that by position (a point within kContactMatchDistance of where an unmatched old point
// was: the kernels may describe the same corner by other features when the reference face flips between two
// equal boxes, and a stack that lost its impulses there would drop). Matched points carry their accumulated
// impulses so that the solver can warm start. Pairs that separate are simply not matched again and are forgotten.
#include <cstdint>
#include <span>
#include <vector>

#include "contacts/contacts.h"
#include "storage/body_storage.h"

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
    /// The two bodies, A and B as the kernel saw them.
    BodyId bodyA() const { return {static_cast<unsigned>(slots >> 32), static_cast<unsigned>(generations >> 32)}; }
    BodyId bodyB() const { return {static_cast<unsigned>(slots), static_cast<unsigned>(generations)}; }
    friend bool operator==(const ContactKey& x, const ContactKey& y) {
        return x.slots == y.slots && x.generations == y.generations && x.parts == y.parts;
    }
};

/// How far a contact point may have moved in one step and still be the same point, m.
inline constexpr float kContactMatchDistance = 0.02f;

/// A manifold kept out of the step while its island sleeps (islands_sleep.h), with the impulses it ended with. Its
/// bodies are named by slot, not dense index: dense indices move when other bodies are removed.
struct KeptManifold {
    ContactKey key;
    ContactPair pair;  ///< a and b are slots
    Manifold manifold;
    PointImpulse impulses[kMaxManifoldPoints];
};

class ContactCache {
public:
    /// Impulses for this step's manifolds: kMaxManifoldPoints per manifold, in `contacts` order, carried over from
    /// last step where the manifold and the point's feature id match, zero elsewhere.
    void warmStart(const Contacts& contacts, const BodyStorage& storage, TaskPool& pool,
                   std::vector<PointImpulse>& impulses);
    /// Keeps this step's manifolds and their final impulses for the next step (call after the solver).
    void remember(const Contacts& contacts, const std::vector<PointImpulse>& impulses, TaskPool& pool);

    /// Key of manifold m of the contacts last passed to warmStart.
    const ContactKey& currentKey(std::size_t m) const { return currentKeys_[m]; }
    /// Appends kept manifolds to this step's contacts (after warmStart, before the solver): they start from their
    /// kept impulses and are remembered with the rest. For an island woken by a touch, whose own pairs the broad
    /// phase skipped this step.
    void restoreIntoStep(std::span<const KeptManifold> kept, const BodyStorage& storage, Contacts& contacts,
                         std::vector<PointImpulse>& impulses);
    /// Adds kept manifolds to last step's, so that next step's manifolds of the same pairs warm-start from them.
    /// For an island woken between steps, whose pairs the next step finds again.
    void restoreForWarmStart(std::span<const KeptManifold> kept);
    /// Calls fn(slot of A, slot of B) for every manifold of the last step.
    template <class Fn>
    void forEachPair(Fn&& fn) const {
        for (const Entry& e : previous_)
            fn(static_cast<std::uint32_t>(e.key.slots >> 32), static_cast<std::uint32_t>(e.key.slots));
    }

    /// Per manifold of the contacts last passed to warmStart: 1 where at least one point carried last step's impulses.
    std::span<const std::uint8_t> carried() const { return carried_; }
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
    struct Matches {
        std::uint32_t manifolds = 0, points = 0;
    };
    /// Hashes every entry of previous_ into table_ (in parallel).
    void rebuildTable(TaskPool& pool);
    /// Writes the impulses of the points of `now` that match a point of `old` (by feature, then by position).
    static void carry(const Manifold& now, const Entry& old, PointImpulse* out, std::uint8_t& carried,
                      Matches& matches);

    std::vector<ContactKey> currentKeys_;  ///< keys of the manifolds passed to warmStart, for remember
    std::vector<std::uint8_t> carried_;
    std::vector<Entry> previous_;
    std::vector<std::uint32_t> table_;  ///< open addressing over previous_: index + 1, 0 = empty
    bool tableValid_ = false;           ///< table_ indexes previous_ as it is now
    std::vector<Matches> chunkMatches_;
    std::vector<std::vector<std::uint32_t>> chunkMisses_;  ///< per chunk: manifolds the in-order guess missed
    std::vector<std::uint8_t> previousMatched_;            ///< per entry of previous_: taken by the in-order guess
    std::vector<std::uint32_t> unmatched_;                 ///< entries of previous_ the in-order guess left
    std::uint32_t matchedManifolds_ = 0, matchedPoints_ = 0;
};

}  // namespace rubble::detail
