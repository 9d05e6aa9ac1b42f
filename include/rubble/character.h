#pragma once
// A character controller: a capsule that walks where the game tells it, moved by collide-and-slide with the world's
// shape casts rather than by the solver, as game characters are (Fauerby's collide-and-slide; Jolt's
// CharacterVirtual and Box3D's character mover do the same). It slides along walls, climbs steps up to a set
// height, walks slopes up to a set angle and slides down steeper ones, sticks to the ground walking down ramps and
// stairs, rides what it stands on (platforms, lifts), and pushes dynamic bodies with a set force instead of
// shoving them aside with the infinite strength of a kinematic body. Its sweeps never pass through a wall, however
// thin, or a mesh, however fast it runs.
//
// The character owns a kinematic capsule body (contactResponse false: it pushes nothing and nothing pushes it, but
// sensors see it and queries hit it), which each update sends to the character's new pose over the next step.
// Call update() once per step, after moving the world's kinematic bodies for that step and before World::step.
#include <cstdint>

#include "rubble/body.h"
#include "rubble/id.h"
#include "rubble/math.h"

namespace rubble {

class World;

struct CharacterSettings {
    float radius = 0.3f;  ///< of the capsule, m
    float height = 1.8f;  ///< of the capsule from the bottom of its feet to the top of its head, m (> 2 radius)
    /// Steepest ground it stands and walks on, rad (below pi / 2); steeper ground is a wall to walk into and a slope
    /// to slide down.
    float maxSlope = 0.7854f;
    float stepHeight = 0.35f;  ///< highest step it walks up without jumping, m (< height - 2 radius)
    /// Walking down steps and ramps it stays on the ground while the ground is within this below its feet, m.
    float groundSnap = 0.3f;
    /// Gap it keeps from every surface, so that sweeps start clear of what it touches, m (> 0).
    float skin = 0.01f;
    float mass = 80;         ///< kg: the weight it puts on dynamic bodies it stands on
    float pushForce = 600;   ///< largest force it pushes dynamic bodies with, N (0: they block it like walls)
    CollisionFilter filter;  ///< of its body; it collides with the bodies this filter accepts
};

/// What one update did.
struct CharacterMove {
    int sweeps = 0;                  ///< shape casts it took
    bool climbedStep = false;        ///< it walked up a step
    std::uint32_t pushedBodies = 0;  ///< dynamic bodies it pushed
};

class CharacterController {
public:
    /// Makes the character's capsule and body in `world`, its feet at `feet`. Throws rubble::Error for settings out
    /// of range (naming the field) or a start inside other bodies.
    CharacterController(World& world, Vec3 feet, const CharacterSettings& settings = {});
    /// Removes its body and shape from the world.
    ~CharacterController();
    CharacterController(const CharacterController&) = delete;
    CharacterController& operator=(const CharacterController&) = delete;

    /// Moves the character for the next step of `dt` seconds: walks at `walkVelocity` (m/s; its vertical part is
    /// ignored), falls under the world's gravity when not on the ground, and rides the ground's motion.
    CharacterMove update(float dt, Vec3 walkVelocity);
    /// Takes off at `speed` (m/s, up) at the next update if it is on the ground; returns whether it will.
    bool jump(float speed);
    /// Puts the character at `feet` at once (no sweep), in the air until the next update finds ground.
    void teleport(Vec3 feet);

    Vec3 position() const { return feet_; }      ///< the bottom of its feet
    Vec3 velocity() const { return velocity_; }  ///< over the last update, ground motion included, m/s
    bool grounded() const { return grounded_; }
    BodyId ground() const { return ground_; }  ///< what it stands on; null in the air
    Vec3 groundNormal() const { return groundNormal_; }
    BodyId body() const { return body_; }
    const CharacterSettings& settings() const { return settings_; }

private:
    struct Sweep;
    Vec3 center() const;
    /// The capsule swept from `center` along `direction` (unit) up to `distance`; false if it hits nothing.
    bool cast(Vec3 center, Vec3 direction, float distance, Sweep& hit, CharacterMove& move) const;
    /// Collide and slide of `displacement` from `center`; returns where it ends.
    Vec3 slide(Vec3 center, Vec3 displacement, float dt, CharacterMove& move);
    /// Up a step in front of it: up, along `horizontal`, down onto walkable ground. Returns whether it did.
    bool stepUp(Vec3& center, Vec3 horizontal, CharacterMove& move);
    void push(const Sweep& hit, Vec3 velocity, float dt, CharacterMove& move);
    /// Ground under `center` within `distance`; snaps down onto it when `snap`.
    void findGround(Vec3& center, float distance, bool snap, CharacterMove& move);

    World& world_;
    CharacterSettings settings_;
    ShapeId shape_;
    BodyId body_;
    Vec3 feet_;
    Vec3 velocity_;
    float verticalSpeed_ = 0;
    float jumpSpeed_ = 0;
    bool grounded_ = false;
    BodyId ground_;
    Vec3 groundNormal_{0, 1, 0};
    Vec3 groundPoint_;
};

}  // namespace rubble
