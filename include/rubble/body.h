#pragma once
#include <cstdint>

#include "rubble/id.h"
#include "rubble/math.h"

namespace rubble {

/// Static bodies never move; kinematic bodies move by their velocity and are not pushed; dynamic bodies obey forces.
enum class BodyType : std::uint8_t { Static, Kinematic, Dynamic };

/// Surface and bulk properties of a body.
struct Material {
    float friction = 0.6f;     ///< Coulomb coefficient, >= 0
    float restitution = 0.0f;  ///< 0 (no bounce) .. 1 (elastic)
    float density = 1000.0f;   ///< kg/m^3, > 0; used for the mass of dynamic bodies
};

/// Two bodies may touch when each one's category is in the other's mask.
struct CollisionFilter {
    std::uint32_t category = 1;
    std::uint32_t mask = 0xFFFFFFFFu;
};

/// Everything needed to create a body. Defaults give a resting dynamic body at the origin.
struct BodyDef {
    BodyType type = BodyType::Dynamic;
    ShapeId shape;         ///< required
    Vec3 position;         ///< of the shape's local origin, in the world
    Quat orientation;      ///< unit quaternion (normalised on creation if within 1e-3 of unit length)
    Vec3 linearVelocity;   ///< of the centre of mass, m/s
    Vec3 angularVelocity;  ///< rad/s, world frame
    Material material;
    CollisionFilter filter;
    float linearDamping = 0.0f;   ///< 1/s, >= 0
    float angularDamping = 0.0f;  ///< 1/s, >= 0
    float gravityScale = 1.0f;
    /// May fall asleep with its island when the scene declares Effect::Sleeping. A body that may not keeps its
    /// whole island awake.
    bool allowSleep = true;
    /// With Effect::ContinuousCollision: swept against dynamic bodies as well as static geometry (for projectiles;
    /// every fast body is swept against static geometry). Costs a sweep against each body near its path.
    bool bullet = false;
    /// Report this body's contacts as events (World::contactEvents: begin and end of touch, hits): pairs are reported
    /// when either body asks. Bodies that do not ask cost the events nothing.
    bool contactEvents = false;
    /// A sensor reports the bodies that overlap it (World::sensorEvents) and pushes nothing: its contacts never reach
    /// the solver, continuous collision passes through it, and queries skip it unless QueryFilter::includeSensors.
    /// It sees the dynamic and kinematic bodies its collision filter accepts (static ones from a moving sensor too),
    /// but not other sensors. A dynamic sensor still falls under gravity: make it kinematic to place it.
    bool sensor = false;
    /// False: the body's contacts are never solved. It passes through everything and pushes nothing, but sensors see
    /// it and queries hit it: the body of a character whose controller does its own collision (CharacterController),
    /// or a ghost. Continuous collision neither stops it nor stops at it.
    bool contactResponse = true;
    std::uint64_t userData = 0;
};

}  // namespace rubble
