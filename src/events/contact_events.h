#pragma once
// Contact events (include/rubble/events.h): which pairs began and stopped touching in a step, and which hit hard.
// Only manifolds with a body that asks (kFlagContactEvents) are looked at, so a world pays per listened contact, not
// per contact. Touch is read from the step's final manifolds; a hit needs the approach speed before the solve (taken
// in the first substep, right after the narrow phase) and the impulse the contact applied over the whole step, which
// the solver keeps only per substep: the listened manifolds' impulses are summed at the end of every substep.
#include <cstdint>
#include <vector>

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

    /// First substep, after the narrow phase: the manifolds a listening body takes part in, and each point's approach
    /// speed now.
    void listen(const Contacts& contacts, const BodyStorage& storage, TaskPool& pool);
    /// After the solver's prepare(): where the listened manifolds sit in the solver (none without a solve).
    void findLanes(const ContactSolver* solver);
    /// At the end of every substep: the listened manifolds' impulses of that substep.
    void addSubstepImpulses(const ContactSolver& solver, const Contacts& contacts);
    /// After the step: begin and end from the step's manifolds (`contacts`, null when the collision stages did not
    /// run), whose bodies `cache` names; hits from what listen() and the substeps gathered. Appends to `out`.
    void report(const Contacts* contacts, const ContactCache& cache, const BodyStorage& storage, float touchSlop,
                float hitSpeed, TaskPool& pool, ContactEvents& out);

private:
    std::vector<std::uint32_t> listened_;  ///< manifold indices, ascending
    std::vector<float> approach_;          ///< kMaxManifoldPoints per listened manifold, m/s
    std::vector<std::uint32_t> lanes_;     ///< per listened manifold: its solver lane, or ~0u
    std::vector<float> impulses_;          ///< kMaxManifoldPoints per listened manifold: summed over the substeps
    std::vector<std::uint32_t> touchingManifolds_;
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
