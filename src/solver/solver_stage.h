#pragma once
// The solver stage's sequence within a step: set up once (joint coupling, contact rows), then in every substep the
// velocity solve before positions are integrated and the relax and bounce passes after. The passes themselves are
// ContactSolver's and JointSolver's; this is the order they run in (docs/architecture.md, "The step").
#include <vector>

#include "contacts/contact_cache.h"
#include "islands/islands.h"
#include "solver/contact_solver.h"
#include "solver/joint_solver.h"
#include "storage/body_storage.h"
#include "storage/joint_storage.h"
#include "world/step_context.h"

namespace rubble::detail {

/// The solver's parts and the world state they work on.
struct SolverParts {
    ContactSolver& contacts;
    JointSolver& joints;
    JointStore& jointStore;
    JointCoupling& coupling;
    BodyStorage& bodies;
    const Islands& islands;
};

/// First substep, after the islands (which couple the joints: JointSolver::couple): prepares the contact rows from
/// this step's manifolds and warm-start impulses, then the joints' rows.
void prepareSolver(SolverParts& solver, const Contacts& contacts, const std::vector<PointImpulse>& impulses,
                   StepContext& step);

/// Every substep, between the two integration halves: the joints' rows, the velocity passes (pass 0 warm starts),
/// shock propagation and, for split impulse, the position passes.
void solveVelocities(SolverParts& solver, StepContext& step);

/// Every substep, after positions moved: split impulse's pseudo-velocities leave, the soft step relaxes its push,
/// the last substep bounces (restitution), and broken joints are settled.
void relaxAndBounce(SolverParts& solver, StepContext& step);

}  // namespace rubble::detail
