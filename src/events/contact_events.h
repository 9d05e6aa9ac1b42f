#pragma once
// Contact events (include/rubble/events.h): which pairs began and stopped touching in a step, and which hit hard.
// Only manifolds with a body that asks (kFlagContactEvents) are looked at, so a world pays per listened contact, not
// per contact. Touch is read from the step's final manifolds; a hit needs the approach speed before the solve (taken
// in the first substep, right after the narrow phase) and the impulse the contact applied over the whole step, which
// the solver keeps only per substep: the impulses of the manifolds that may hit or that do not touch yet (they
// touch if they push) are summed at the end of every substep. A resting contact is neither, so a settled pile that
// listens pays for its contacts once a step, not once a substep.
#include <cstdint>
#include <vector>

#include "broadphase/radix_sort.h"
#include "contacts/contact_cache.h"
#include "contacts/contacts.h"
#include "events/event_pairs.h"
#include "rubble/events.h"
#include "solver/contact_solver.h"
#include "storage/body_storage.h"

namespace rubble::detail {

class TaskPool;

class ContactEventStage {
public:
    /// False when no body asks for events and no pair is held: then none of the calls below need run.
    bool active(std::uint32_t listeningBodies) const { return listeningBodies > 0 || !touching_.empty(); }

    /// First substep, after the narrow phase: the manifolds of a listening body whose push the report will need
    /// (those that approach at `hitSpeed` or more, and those not yet within `touchSlop`), and each point's approach
    /// speed now.
    void listen(const Contacts& contacts, const BodyStorage& storage, float touchSlop, float hitSpeed, TaskPool& pool);
    /// After the solver's prepare(): where the listened manifolds sit in the solver (none without a solve).
    void findLanes(const ContactSolver* solver, const Contacts& contacts);
    /// At the end of every substep: the listened manifolds' impulses of that substep (in lane order, so that the
    /// solver's batches are read in memory order; the chunks in parallel).
    void addSubstepImpulses(const ContactSolver& solver, TaskPool& pool);
    /// After the step: begin and end from the step's manifolds (`contacts`, null when the collision stages did not
    /// run), whose bodies `cache` names; hits from what listen() and the substeps gathered. Appends to `out`.
    void report(const Contacts* contacts, const ContactCache& cache, const BodyStorage& storage, float touchSlop,
                float hitSpeed, TaskPool& pool, ContactEvents& out);

private:
    /// A listened manifold's place in the solver.
    struct Lane {
        std::uint32_t lane = 0;      ///< batch * kBatchLanes + lane
        std::uint32_t listened = 0;  ///< index into listened_
        std::int32_t points = 0;
    };
    std::vector<std::uint32_t> listened_;    ///< manifolds followed through the substeps (see listen()), ascending
    std::vector<float> approach_;            ///< kMaxManifoldPoints per listened manifold, m/s
    std::vector<float> impulses_;            ///< kMaxManifoldPoints per listened manifold: summed over the substeps
    std::vector<float> laneImpulses_;        ///< the same sums as the substeps add them, per entry of lanes_
    std::vector<std::uint32_t> listenedOf_;  ///< per manifold of the step: its index in listened_, or ~0u
    std::vector<Lane> lanes_;                ///< the listened manifolds the solver has, in lane order
    std::vector<std::uint32_t> touchingManifolds_;
    std::vector<std::uint64_t> touchingSlots_;  ///< slot << 32 | slot of each touching pair, lower first
    RadixSortScratch sortScratch_;
    std::vector<std::vector<std::uint32_t>> chunkLists_;
    std::vector<EventPair> now_;
    struct Hit {
        EventPair pair;
        ContactHitEvent event;
    };
    std::vector<Hit> hits_;
    HeldPairs touching_;
};

}  // namespace rubble::detail
