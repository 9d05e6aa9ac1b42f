#include "solver/solver_stage.h"

namespace rubble::detail {

namespace {

template <class Work>
void timeJoints(StepContext& step, Work&& work) {
    const auto begin = Clock::now();
    work();
    step.jointNs.fetch_add((Clock::now() - begin).count(), std::memory_order_relaxed);
}

}  // namespace

void prepareSolver(SolverParts& solver, const Contacts& contacts, const std::vector<PointImpulse>& impulses,
                   StepContext& step) {
    const auto timer = step.time(Stage::Solver);
    solver.contacts.prepare(contacts, impulses, solver.bodies, step.settings, step.effects, step.integration.dt,
                            step.pool, step.joints ? &solver.coupling : nullptr, &solver.islands);
    if (step.joints) {
        JointTimer jointTimer(step.profile);
        solver.joints.prepare(solver.jointStore, solver.bodies, solver.contacts, solver.coupling, step.settings,
                              step.integration.dt, step.pool, &solver.islands);
    }
}

namespace {

/// The large islands' joints may run their colours across the threads: their segment's pass runs on the calling
/// thread, a block's inside its own task.
TaskPool* poolFor(const ContactSolver& contacts, std::uint32_t segment, TaskPool& pool) {
    return segment == contacts.blocks().size() ? &pool : nullptr;
}

}  // namespace

void solveVelocities(SolverParts& solver, StepContext& step) {
    const auto timer = step.time(Stage::Solver);
    ContactSolver& cs = solver.contacts;
    JointSolver& js = solver.joints;
    const SolverSettings& settings = step.settings.solver;
    cs.loadBodies(solver.bodies.moving, step.pool);
    // Each segment of the solve (a block of small islands in its own task, or the large islands) runs its joints,
    // then its contact colours, in every pass; pass 0 starts the joints' substep, and with warm starting it is the
    // warm start.
    const bool warm = settings.warmStarting;
    auto velocityJoints = [&](std::uint32_t segment, int pass) {
        timeJoints(step, [&] {
            TaskPool* pool = poolFor(cs, segment, step.pool);
            if (pass == 0) js.beginSubstep(cs.bodies(), warm, segment, pool);
            if (!warm || pass > 0) js.solve(cs.bodies(), true, segment, pool);
        });
    };
    const JointPass velocityPass = velocityJoints;
    cs.solveVelocities(true, step.pool, step.settings.velocityIterations, warm, step.joints ? &velocityPass : nullptr);
    const PositionCorrection correction = settings.positionCorrection;
    if (settings.shockPropagation && correction != PositionCorrection::SoftStep) cs.propagateShock();
    if (correction == PositionCorrection::SplitImpulse) cs.solvePositions(step.pool, step.settings.positionIterations);
    cs.storeVelocities(solver.bodies.moving, step.pool);
}

void relaxAndBounce(SolverParts& solver, StepContext& step) {
    const auto timer = step.time(Stage::Solver);
    ContactSolver& cs = solver.contacts;
    const PositionCorrection correction = step.settings.solver.positionCorrection;
    if (correction == PositionCorrection::SplitImpulse) cs.applyPseudoVelocities(solver.bodies.moving, step.pool);
    const bool relax = correction == PositionCorrection::SoftStep && step.settings.positionIterations > 0;
    const bool bounce = step.lastSubstep() && step.effects.has(Effect::Restitution);
    if (relax || bounce) {
        cs.loadBodies(solver.bodies.moving, step.pool);
        auto relaxJoints = [&](std::uint32_t segment, int) {
            timeJoints(step,
                       [&] { solver.joints.solve(cs.bodies(), false, segment, poolFor(cs, segment, step.pool)); });
        };
        const JointPass relaxPass = relaxJoints;
        if (relax)
            cs.solveVelocities(false, step.pool, step.settings.positionIterations, false,
                               step.joints ? &relaxPass : nullptr);
        if (bounce) cs.applyRestitution(step.pool);
        cs.storeVelocities(solver.bodies.moving, step.pool);
    }
    if (step.joints && step.lastSubstep()) {
        JointTimer jointTimer(step.profile);
        solver.joints.finish(solver.jointStore, step.pool);
    }
}

}  // namespace rubble::detail
