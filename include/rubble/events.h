#pragma once
// What a game hears from a step: bodies that began or stopped touching, hard hits (for sounds and damage), bodies
// entering and leaving sensors, and the contacts of one body now. Events are gathered after each step into arrays
// that World::contactEvents() and World::sensorEvents() hand out until the next step, never through callbacks from
// the step's worker threads; their order is by body slots, the same on any thread count. Only bodies that ask for
// them (BodyDef::contactEvents, BodyDef::sensor) cost anything: a world where none does runs no event code.
#include <cstdint>
#include <vector>

#include "rubble/id.h"
#include "rubble/math.h"
#include "rubble/query.h"

namespace rubble {

/// Two bodies began touching in the last step: at its start some point of their contact was within the solver's
/// linear slop (SolverSettings::linearSlop) of touching or deeper, or their contact pushed during the step (they met
/// within it). `a` has the lower slot (BodyId::index).
struct ContactBeginEvent {
    BodyId a, b;
};

/// Two bodies that touched stopped touching in the last step, or one of them was destroyed since (its handle is then
/// stale). A pair whose bodies fall asleep touching does not end: it ends when they wake and part.
struct ContactEndEvent {
    BodyId a, b;
};

/// Two bodies met at an approach speed of at least WorldSettings::hitEventSpeed in the last step, and the contact
/// pushed: one event per pair and step.
struct ContactHitEvent {
    BodyId a, b;
    Vec3 point;           ///< world point of the fastest approaching contact point
    Vec3 normal;          ///< unit, from a towards b
    float approachSpeed;  ///< normal speed of b towards a at that point before the step's solve, m/s (> 0)
    /// Normal impulse the contact applied over the whole step (every substep, every point, and every part of the pair
    /// that met in the step: compound children, mesh triangles; a part already resting in contact and approaching
    /// slower than hitEventSpeed is not counted), N s; b received it along the normal, a the opposite.
    float impulse;
};

struct ContactEvents {
    std::vector<ContactBeginEvent> begins;
    std::vector<ContactEndEvent> ends;
    std::vector<ContactHitEvent> hits;
};

/// A body began overlapping a sensor (its shape went into the sensor's, any depth) in the last step.
struct SensorBeginEvent {
    BodyId sensor, visitor;
};

/// A body stopped overlapping a sensor, or one of the two was destroyed (its handle is then stale). A sleeping
/// visitor stays inside.
struct SensorEndEvent {
    BodyId sensor, visitor;
};

struct SensorEvents {
    std::vector<SensorBeginEvent> begins;
    std::vector<SensorEndEvent> ends;
};

/// One contact of a body with another, as the last step solved it (World::contactsOf).
struct BodyContact {
    BodyId other;
    Vec3 normal;  ///< unit, from the body asked about towards `other`
    int pointCount = 0;
    struct Point {
        Vec3 position;    ///< world, on the surface of one of the two bodies
        float depth = 0;  ///< > 0: overlap; <= 0: a speculative point still -depth apart, m
        /// Impulses the solver applied in the last substep of the step (N s; divided by the substep's length, the
        /// force): along the normal, pushing the two bodies apart, and along the two friction directions.
        float normalImpulse = 0;
        float frictionImpulse = 0;  ///< magnitude of the friction impulse
    } points[4];
    /// The parts of the two shapes that touch: compound children (CompoundDef order) and the mesh or heightfield
    /// triangle (RayHit::triangle's numbering), kNoIndex where the shape has none.
    std::uint32_t child = kNoIndex, otherChild = kNoIndex, triangle = kNoIndex;
};

}  // namespace rubble
