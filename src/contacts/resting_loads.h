#pragma once
// Warm start for new contacts: the normal impulses that would hold each body at rest under gravity.
//
// Warm starting carries last step's impulses, so a stack that settled once keeps its loads. A contact new this step
// starts from nothing, and the iterations must then build the load of everything above it. In a stack that pass
// takes about one iteration per layer it crosses, and the iterations cannot keep up with tall piles that appear at
// once (a scene's first step, a wall of a hundred rows): the upper layers fall through their unloaded contacts.
// Here each body at rest with a new contact under it gets, top down, the contact forces that balance its weight and
// what rests on it (force and torque), least-norm among its new support points, pushing only. The iterations then
// correct this guess; they can take any of it back, so a wrong guess costs iterations. It must never cost energy: a
// body still landing is left to the iterations (it is not at rest, and what stopped it is no load), and the guess is
// bounded by the load it balances.
#include <cstdint>
#include <span>
#include <vector>

#include "contacts/contact_cache.h"
#include "contacts/contacts.h"
#include "storage/body_storage.h"

namespace rubble::detail {

class TaskPool;

struct RestingLoadParams {
    Vec3 gravity;
    float h = 0;  ///< time over which an impulse acts (the substep), s
    /// Points at most this far apart count as touching (the linear slop); farther speculative points carry nothing.
    float touchDistance = 0;
};

class RestingLoads {
public:
    /// Writes normal impulses for the touching points of every manifold that carried nothing from last step
    /// (`carried[m] == 0`) and through which a dynamic body rests on something lower, along gravity, unless the body
    /// is still landing (approaches a support faster than a body at rest would). Other manifolds keep their impulses
    /// and count as they are for the loads they pass down and the loads they hold up. A jump from one new manifold
    /// to the next, a parallel scan of all manifolds for the supports of the bodies found, then only those bodies,
    /// top down, on one thread. Returns the number of manifolds it wrote.
    std::uint32_t seed(const Contacts& contacts, std::span<const std::uint8_t> carried, const MovingBodies& bodies,
                       const RestingLoadParams& params, TaskPool& pool, std::vector<PointImpulse>& impulses);

private:
    /// A manifold through which `upper` rests on `lower` (~0u: a static or kinematic body), both dense indices.
    struct Support {
        std::uint32_t manifold;
        std::uint32_t upper;
        std::uint32_t lower;
        bool upperIsB;
    };
    struct Link {
        std::uint32_t body;     ///< index into resting_
        std::uint32_t support;  ///< index into supports_
        bool above;             ///< the body is the support's lower side (the load comes from above)
    };
    std::vector<std::uint32_t> restingOf_;  ///< per moving body: index into resting_, or ~0u
    std::vector<std::uint32_t> resting_;    ///< bodies resting on a new contact, top down
    std::vector<Support> supports_;
    std::vector<std::vector<Support>> chunkSupports_;  ///< the parallel scan's finds, per chunk of manifolds
    std::vector<Link> links_, grouped_;                ///< links by body: links_[linkStart_[k], linkStart_[k + 1])
    std::vector<std::uint32_t> linkStart_, linkFill_;
    /// A touching point of the body being balanced: the direction its force pushes along and that force's torque
    /// about the centre of mass, and the force found (>= 0).
    struct SupportPoint {
        float column[6];
        float force = 0;
        bool active = true;
    };
    std::vector<SupportPoint> points_;
};

}  // namespace rubble::detail
