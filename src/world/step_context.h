#pragma once
// What one step carries through its stages: the time step and substep, the settings, the effects this step
// simulates, the task pool and the profile, and the decisions taken once at its start (which stages run).
// World::step (src/world/step.cpp) makes one and hands it to every stage in turn.
#include <atomic>
#include <cstddef>

#include "core/parallel.h"
#include "core/profile.h"
#include "integrate/integrate.h"
#include "rubble/settings.h"

namespace rubble::detail {

struct StepContext {
    StepContext(const WorldSettings& s, EffectSet e, TaskPool& p, Profile& pr, Clock::time_point o)
        : settings(s), effects(e), pool(p), profile(pr), origin(o) {}
    StepContext(const StepContext&) = delete;
    StepContext& operator=(const StepContext&) = delete;

    const WorldSettings& settings;
    const EffectSet effects;
    TaskPool& pool;
    Profile& profile;
    const Clock::time_point origin;  ///< the world's clock origin, for the profile's begin times

    float dt = 0;  ///< the whole step
    int substeps = 1;
    int substep = 0;  ///< the substep being run
    bool lastSubstep() const { return substep == substeps - 1; }
    /// The integration stage's parameters; its dt is the substep's.
    IntegrationParams integration;

    // Decided at the start of the step.
    bool sleeping = false;          ///< Effect::Sleeping: islands fall asleep and wake
    bool joints = false;            ///< a joint acts: the joint solver runs
    bool continuous = false;        ///< continuous collision sweeps the fast bodies
    bool velocitiesChange = false;  ///< gravity, a force, damping or rotation: integrate_velocities runs
    bool contactEvents = false;     ///< a body asks for contact events, or a pair is still reported
    bool sensors = false;  ///< a sensor or a body without contact response exists, or an overlap is still reported
    std::size_t brokenJointsBefore = 0;

    // Decided in the first substep.
    bool collided = false;  ///< the collision stages ran: the contacts and the solver's rows are this step's
    bool solve = false;     ///< the solver has rows (contacts or joints) to solve in every substep

    /// Time in the joints' passes summed over the threads that ran them (blocks run their joints in their tasks).
    std::atomic<Clock::rep> jointNs{0};

    StageTimer time(Stage stage) const { return StageTimer(profile, stage, origin); }
};

}  // namespace rubble::detail
