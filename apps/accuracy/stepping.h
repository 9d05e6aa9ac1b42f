#pragma once
// What the measurement scenes share: how many copies a scene builds, and stepping a world while timing each step.
#include <algorithm>
#include <cmath>
#include <vector>

#include "measurement.h"
#include "rubble/world.h"

namespace rubble::accuracy {

/// Copies of the measured system in a scene: enough that a step's time is mostly the bodies' own work.
inline int copiesFor(Length length, int full) { return length == Length::Full ? full : std::max(1, full / 4); }

/// Steps of `dt` that cover `seconds` (rounded to the nearest whole step).
inline long stepsFor(double seconds, float dt) { return std::lround(seconds / static_cast<double>(dt)); }

/// The sweep's settings with the scene's own effects; continuous collision stays as the sweep set it.
inline WorldSettings withSceneEffects(WorldSettings settings, EffectSet effects) {
    const bool ccd = settings.effects.has(Effect::ContinuousCollision);
    settings.effects = ccd ? effects.with(Effect::ContinuousCollision) : effects.without(Effect::ContinuousCollision);
    return settings;
}

/// A static box whose top face is the plane y = 0, spanning [-halfX, halfX] x [-halfZ, halfZ].
inline BodyId addGround(World& world, float halfX, float halfZ, const Material& material = {}) {
    BodyDef def;
    def.type = BodyType::Static;
    def.shape = world.createShape(BoxDef{{halfX, 0.5f, halfZ}});
    def.position = {0, -0.5f, 0};
    def.material = material;
    return world.createBody(def);
}

/// Steps the world `steps` times at its settings' time step, calling `afterStep(stepIndex)` after each; fills in
/// the run's step count, median step time and final state hash.
template <class AfterStep>
void stepTimed(World& world, long steps, Measured& out, AfterStep&& afterStep) {
    std::vector<double> ms;
    ms.reserve(static_cast<std::size_t>(steps));
    const float dt = world.settings().timeStep;
    for (long s = 0; s < steps; ++s) {
        world.step(dt);
        ms.push_back(world.lastProfile().stepMs);
        afterStep(s);
    }
    out.steps = steps;
    out.timeStep = dt;
    out.msPerStep = median(std::move(ms));
    out.stateHash = world.stateHash();
}

inline void stepTimed(World& world, long steps, Measured& out) {
    stepTimed(world, steps, out, [](long) {});
}

}  // namespace rubble::accuracy
