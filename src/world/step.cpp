// The step. World::step is the table of contents of the engine (DESIGN.md, "One step"; docs/architecture.md,
// "The step"): one line per stage, in the order data flows, each handed the world's state and the step's context.
#include <chrono>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "rubble/limits.h"
#include "simd/float_mode.h"
#include "solver/solver_stage.h"
#include "world/step_context.h"
#include "world/world_impl.h"

namespace rubble {

namespace {

using detail::StepContext;

/// Decides once what this step runs, from the effects it simulates and the world's state.
void planStep(World::Impl& w, StepContext& step, float dt) {
    Profile& profile = step.profile;
    profile.effects = step.effects;
    step.sleeping = step.effects.has(Effect::Sleeping);
    if (!step.sleeping && w.sleeping.sleepingBodies() > 0) w.sleeping.wakeAll(w.bodies);

    step.dt = dt;
    step.substeps = w.settings.substeps;
    detail::IntegrationParams& params = step.integration;
    params.dt = dt / static_cast<float>(step.substeps);
    params.gravity = step.effects.has(Effect::Gravity) ? w.settings.gravity : Vec3{};
    params.rotation = step.effects.has(Effect::Rotation);
    params.integrator = w.settings.integrator;
    params.skipAsleep = w.sleeping.sleepingBodies() > 0;
    // Nothing changes velocities when there is no gravity, force, damping or rotation: the stage is not run.
    step.velocitiesChange = step.effects.has(Effect::Gravity) || params.rotation || w.forcesPending || w.anyDamping ||
                            params.integrator != Integrator::SemiImplicitEuler;

    // Joints join the solve only when one acts (Effect::Joints is inferred from the joint store); else no joint code
    // runs. Joints that break in this step stop acting at once but keep their rows until the step ends.
    step.joints = step.effects.has(Effect::Joints);
    step.brokenJointsBefore = w.joints.brokenReports().size();
    if (step.joints) profile.joints = w.joints.activeCount();
    step.continuous = step.effects.has(Effect::ContinuousCollision) && w.bodies.moving.size() > 0;
    step.contactEvents = w.contactEventStage.active(w.listeningBodies);
    step.sensors = w.sensorEventStage.active(w.separatedBodies);
    w.contactEvents.begins.clear(), w.contactEvents.ends.clear(), w.contactEvents.hits.clear();
    w.sensorEvents.begins.clear(), w.sensorEvents.ends.clear();
}

detail::SolverParts solverParts(World::Impl& w) {
    return {w.contactSolver, w.jointSolver, w.joints, w.jointCoupling, w.bodies, w.islands};
}

/// Large worlds keep their moving bodies in the grid's cell order of the last step, renewed every period: the
/// order only decides where rows live, so it costs one pass over the storage and saves cache misses in every stage
/// after it. Runs before anything of this step reads a dense index; a result depends on it only through the order
/// of pairs, which is the same on every thread count. Its time counts in the broad phase's.
void keepBodiesInSpatialOrder(World::Impl& w, StepContext& step) {
    if (w.bodies.moving.size() < w.spatialOrderFrom) return;
    if (w.spatiallyOrdered && ++w.stepsSinceSpatialOrder < w.spatialOrderPeriod) return;
    const std::uint32_t* order = w.broadPhase.movingInCellOrder(w.bodies);
    if (order == nullptr) return;
    const auto timer = step.time(Stage::BroadPhase);
    w.bodies.reorderMoving(order, step.pool);
    w.broadPhase.movingPutInCellOrder(w.bodies);
    w.stepsSinceSpatialOrder = 0;
    w.spatiallyOrdered = true;
}

/// Continuous collision sweeps each fast body from where it starts the step to where the substeps leave it.
void startContinuousCollision(World::Impl& w, StepContext& step) {
    if (!step.continuous) return;
    const auto timer = step.time(Stage::Ccd);
    w.ccd.begin(w.bodies.moving, step.pool);
}

void integrateVelocities(World::Impl& w, StepContext& step) {
    step.integration.forces = w.forcesPending;
    step.integration.clearForces = step.lastSubstep();
    if (step.velocitiesChange) {
        const auto timer = step.time(Stage::IntegrateVelocities);
        detail::integrateVelocities(w.bodies.moving, step.integration, w.integrationScratch, step.pool, w.nonFinite);
    }
    w.freezeReported();
}

/// The islands stage before the solver: union-find over this step's manifolds, the joints and the links that hold
/// each sleeping island together; with sleeping, islands that a sleeping body shares with an awake one (or with a
/// moving kinematic body) wake whole.
void buildIslands(World::Impl& w, StepContext& step) {
    {
        const auto timer = step.time(Stage::Islands);
        w.islandEdges.clear();
        if (step.joints || w.joints.size() > 0) {
            // The joints' bodies, for the islands now and the solver's rows after (listed again when the last joint
            // is gone, or its pair would still not collide). Joints hold their islands together even when they do
            // not act (Effect::Joints off): the bodies sleep and wake as one.
            const auto couple = [&] { w.jointSolver.couple(w.joints, w.bodies, w.jointCoupling, step.pool); };
            if (step.joints) {
                detail::JointTimer jointTimer(step.profile);
                couple();
            } else {
                couple();
            }
            w.jointCoupling.appendEdges(w.islandEdges);
        }
        w.sleeping.linkSleepingIslands(w.bodies, w.contacts, step.pool, w.islandEdges);
        w.islandBuilder.build(w.contacts, w.islandEdges, w.bodies.moving, step.pool, w.islands);
        if (step.sleeping && w.sleeping.wakeTouched(w.islands, w.bodies, w.integrationScratch, w.contacts, w.impulses,
                                                    w.contactCache, step.pool))
            w.islandBuilder.assignManifolds(w.contacts, w.islands);
    }
    step.profile.islands = w.islands.count();
    step.profile.largestIsland = w.islands.largest;
}

/// Bounds, pairs, manifolds, warm-start impulses, islands and the solver's rows: once per step, in the first
/// substep, with boxes that cover the motion of the whole step. Pairs exist only where a moving body can meet
/// another body.
void findContacts(World::Impl& w, StepContext& step) {
    Profile& profile = step.profile;
    const std::uint32_t moving = w.bodies.moving.size();
    if (!(moving > 1 || (moving == 1 && w.bodies.statics.size() > 0) || step.joints)) {
        if (step.sleeping) {
            // No pairs can exist, but a lone body still rests and falls asleep.
            w.contacts.clear();
            w.impulses.clear();
            buildIslands(w, step);
        }
        return;
    }
    step.collided = true;
    {
        const auto timer = step.time(Stage::UpdateBounds);
        const detail::BoundsParams params{step.dt, w.settings.contactMargin};
        // The sleepers' boxes hold while their rows and the parameters stay as they were at the last call; those
        // that fell asleep since are computed anew (velocity zero), those that woke are computed with the awake.
        const detail::SleepChanges changes = w.sleeping.sleepChanges();
        // (Past an eighth of the rows, one wide pass beats recomputing the changed rows one by one.)
        const bool keepSleepers = w.sleeping.sleepingBodies() > 0 && !changes.all &&
                                  changes.slots.size() <= w.bodies.moving.size() / 8 &&
                                  w.boundsRowMoves == w.bodies.movingRowMoves() && w.boundsParams.dt == params.dt &&
                                  w.boundsParams.margin == params.margin;
        detail::updateBounds(w.bodies.moving, w.shapeBounds, params, step.pool, w.movingBounds, keepSleepers);
        if (keepSleepers) {
            w.fellAsleepRows.clear();
            for (const std::uint32_t slot : changes.slots)
                if (const std::uint32_t row = w.bodies.sleepingRow(slot); row != ~0u) w.fellAsleepRows.push_back(row);
            detail::updateBoundsOf(w.bodies.moving, w.shapeBounds, params, w.fellAsleepRows, w.movingBounds);
        }
        w.boundsRowMoves = w.bodies.movingRowMoves();
        w.boundsParams = params;
    }
    {
        const auto timer = step.time(Stage::BroadPhase);
        w.broadPhase.findPairs(w.movingBounds, w.bodies, w.settings.broadPhase, w.sleeping.sleepChanges(), step.pool,
                               w.pairs);
        w.sleeping.clearSleepChanges();
    }
    profile.broadPhase = w.broadPhase.lastKind();
    profile.movingPairs = static_cast<std::uint32_t>(w.pairs.moving.size());
    profile.droppedPairs = w.pairs.droppedMoving;
    profile.droppedStaticHits = w.pairs.droppedStatic;
    profile.staticPairs = static_cast<std::uint32_t>(w.pairs.statics.size());
    profile.meshPairs = static_cast<std::uint32_t>(w.pairs.meshes.size());
    profile.meshTriangles = static_cast<std::uint32_t>(w.pairs.meshTriangles.size());
    {
        const auto timer = step.time(Stage::NarrowPhase);
        w.narrowPhase.run(
            w.pairs, w.bodies, w.shapes,
            {w.settings.contactMargin, step.dt, w.settings.manifoldReuseDistance, w.settings.contactFeatureDrift},
            step.pool, w.contacts);
    }
    profile.reusedManifolds = w.narrowPhase.reusedManifolds();
    if (step.sensors || step.contactEvents) {
        const auto timer = step.time(Stage::Events);
        if (step.sensors) profile.sensorPairs = w.sensorEventStage.separate(w.contacts, w.bodies);
        if (step.contactEvents)
            w.contactEventStage.listen(w.contacts, w.bodies, w.settings.solver.linearSlop, w.settings.hitEventSpeed,
                                       step.pool);
    }
    profile.manifolds = static_cast<std::uint32_t>(w.contacts.manifolds.size());
    profile.contactPoints = w.contacts.pointCount;
    {
        const auto timer = step.time(Stage::ContactCache);
        const SolverSettings& solver = w.settings.solver;
        w.sleeping.flushWarmStarts(w.contactCache);
        w.contactCache.warmStart(w.contacts, w.bodies, step.pool, w.impulses);
        if (solver.warmStarting && solver.seedRestingLoads && step.effects.has(Effect::Gravity))
            profile.seededManifolds = w.restingLoads.seed(w.contacts, w.contactCache.carried(), w.bodies.moving,
                                                          {w.settings.gravity, step.integration.dt, solver.linearSlop},
                                                          step.pool, w.impulses);
    }
    profile.matchedManifolds = w.contactCache.matchedManifolds();
    profile.warmStartedPoints = w.contactCache.matchedPoints();
    buildIslands(w, step);
    detail::SolverParts solver = solverParts(w);
    detail::prepareSolver(solver, w.contacts, w.impulses, step);
    const detail::ContactSolverStats& stats = w.contactSolver.stats();
    profile.constraints = stats.constraints;
    profile.colors = stats.colors;
    profile.solverBlocks = stats.blocks;
    profile.largeIslandConstraints = stats.largeIslandConstraints;
    profile.laneOccupancy = stats.laneOccupancy;
    if (step.joints) {
        profile.jointColours = w.jointSolver.colourCount();
        profile.batchedJoints = w.jointSolver.batchedJoints();
    }
    step.solve = !w.contactSolver.empty() || step.joints;
    if (step.contactEvents) {
        const auto timer = step.time(Stage::Events);
        w.contactEventStage.findLanes(w.contactSolver.empty() ? nullptr : &w.contactSolver, w.contacts);
    }
}

void solveVelocities(World::Impl& w, StepContext& step) {
    if (!step.solve) return;
    detail::SolverParts solver = solverParts(w);
    detail::solveVelocities(solver, step);
}

void integratePositions(World::Impl& w, StepContext& step) {
    {
        const auto timer = step.time(Stage::IntegratePositions);
        detail::integratePositions(w.bodies.moving, step.integration, w.integrationScratch, step.pool, w.nonFinite);
    }
    w.freezeReported();
}

void relaxAndBounce(World::Impl& w, StepContext& step) {
    if (!step.solve) return;
    detail::SolverParts solver = solverParts(w);
    detail::relaxAndBounce(solver, step);
    if (step.contactEvents && !w.contactSolver.empty()) {
        const auto timer = step.time(Stage::Events);
        w.contactEventStage.addSubstepImpulses(w.contactSolver, step.pool);
    }
}

void finishContinuousCollision(World::Impl& w, StepContext& step) {
    if (!step.continuous) return;
    const auto timer = step.time(Stage::Ccd);
    static const std::vector<detail::BodyPair> kNoPairs;
    w.ccd.run(w.bodies, w.shapes, w.shapeBounds, w.broadPhase.staticBvh(step.pool),
              step.collided ? w.pairs.moving : kNoPairs, w.settings.solver.linearSlop, step.pool);
    step.profile.ccdBodies = w.ccd.stats().fastBodies;
    step.profile.ccdHits = w.ccd.stats().hits;
}

/// The solved impulses go back to the contact cache, to warm-start the next step.
void rememberContacts(World::Impl& w, StepContext& step) {
    if (!step.collided) return;
    const auto timer = step.time(Stage::ContactCache);
    w.contactSolver.storeImpulses(w.impulses, step.pool);
    w.contactCache.remember(w.contacts, w.impulses, step.pool);
}

void fallAsleep(World::Impl& w, StepContext& step) {
    if (step.sleeping) {
        const auto timer = step.time(Stage::Islands);
        w.sleeping.fallAsleep(w.islands, w.contacts, w.impulses, w.contactCache, w.bodies, w.shapeBounds,
                              w.settings.sleep, step.dt, step.pool);
    }
    step.profile.sleepingBodies = w.sleeping.sleepingBodies();
}

/// Contact and sensor events of the step, from its final contacts and the bodies' sleep.
void reportEvents(World::Impl& w, StepContext& step) {
    w.contactsOfLastStep = step.collided;
    if (!step.contactEvents && !step.sensors) return;
    const auto timer = step.time(Stage::Events);
    if (step.contactEvents)
        w.contactEventStage.report(step.collided ? &w.contacts : nullptr, w.contactCache, w.bodies,
                                   w.settings.solver.linearSlop, w.settings.hitEventSpeed, step.pool, w.contactEvents);
    if (step.sensors) w.sensorEventStage.report(w.bodies, w.sensorEvents);
    step.profile.events = static_cast<std::uint32_t>(w.contactEvents.begins.size() + w.contactEvents.ends.size() +
                                                     w.contactEvents.hits.size() + w.sensorEvents.begins.size() +
                                                     w.sensorEvents.ends.size());
}

void finishStep(World::Impl& w, StepContext& step, detail::Clock::time_point begin) {
    Profile& profile = step.profile;
    w.forcesPending = false;
    if (step.joints) {
        profile.jointMs +=
            std::chrono::duration<double, std::milli>(detail::Clock::duration(step.jointNs.load())).count();
        profile.brokenJoints = static_cast<std::uint32_t>(w.joints.brokenReports().size() - step.brokenJointsBefore);
        if (profile.brokenJoints > 0) w.effectsDirty = true;
    }
#if RUBBLE_VALIDATE
    if (const std::string problem = w.bodies.checkInvariants(); !problem.empty())
        fail("World::step (RUBBLE_VALIDATE)", "body storage is inconsistent: " + problem);
#endif
    profile.bodyCount = w.bodies.count();
    profile.movingCount = w.bodies.moving.size();
    profile.stepMs = std::chrono::duration<double, std::milli>(detail::Clock::now() - begin).count();
    w.steps += 1;
}

}  // namespace

void World::step(float dt) {
    requireWithin("World::step", "dt", dt, limits::kMinTimeStep, limits::kMaxTimeStep, "s");
    Impl& w = *impl_;
    static const int cores = static_cast<int>(std::thread::hardware_concurrency());  // a system call: once
    const detail::BroadPhaseStage::StepInProgress stepInProgress(w.broadPhase, w.pool->threadCount() >= cores);
    // The pool's workers set the same mode for each chunk they run (parallel.cpp).
    const simd::FlushSubnormals flushSubnormals;
    const auto begin = detail::Clock::now();
    w.profile = Profile{};
    w.profile.stepIndex = w.steps;
    w.profile.beginUs = detail::microsecondsSince(w.origin, begin);
    w.resolveEffectsIfDirty();
    StepContext step(w.settings, w.effects, *w.pool, w.profile, w.origin);
    planStep(w, step, dt);

    keepBodiesInSpatialOrder(w, step);
    startContinuousCollision(w, step);
    for (step.substep = 0; step.substep < step.substeps; ++step.substep) {
        integrateVelocities(w, step);
        if (step.substep == 0) findContacts(w, step);
        solveVelocities(w, step);
        integratePositions(w, step);
        relaxAndBounce(w, step);
    }
    finishContinuousCollision(w, step);
    rememberContacts(w, step);
    fallAsleep(w, step);
    reportEvents(w, step);
    finishStep(w, step, begin);
}

}  // namespace rubble
