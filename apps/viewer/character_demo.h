#pragma once
// The character demo: a walkable level of meshes and boxes (a corridor with a pillar, stairs, a landing, a ramp down,
// a lift up to a ledge), crates to push and coins to pick up (sensors), and a character (the Runtime's
// CharacterController) walked with the keys or by an autopilot along the course. Built without OpenGL so tests run it.
#include <cstdint>
#include <vector>

#include "rubble/id.h"
#include "rubble/math.h"
#include "rubble/runtime.h"

namespace rubble {
class World;
}

namespace rubble::viewer {

struct CharacterDemo {
    static constexpr float kWalkSpeed = 3.0f;                   ///< m/s
    static constexpr float kJumpSpeed = 5.0f;                   ///< m/s, up
    static constexpr float kLiftLow = 0.05f, kLiftHigh = 2.0f;  ///< heights of the lift's top, m
    static constexpr float kLiftSpeed = 1.0f;                   ///< m/s
    static constexpr float kEndX = 31.0f;                       ///< the ledge's far end

    BodyId floor, lift, ledge;
    std::vector<BodyId> crates, coins;
    Vec3 start{-2, 0.02f, 0};  ///< the character's feet at the start
    std::vector<Vec3> path;    ///< the autopilot's waypoints (feet; y unused)
    std::size_t nextWaypoint = 0;
    float liftHeight = kLiftLow;
    int coinsCollected = 0;

    /// A world for the demo: gravity, rotation, friction and sleeping; one thread.
    static World makeWorld();
    /// Creates the level, the crates and the coins in `world`.
    void build(World& world);
    /// Walk velocity for key input (right, forward in [-1, 1]) relative to a camera looking along `cameraForward`.
    Vec3 walkVelocity(float right, float forward, Vec3 cameraForward) const;
    /// The autopilot's walk from where the character is: towards the next waypoint, waiting on the lift until it is up.
    Vec3 autopilotWalk(const CharacterState& character);
    /// Moves the lift for a frame of `dt`: up while the character rides it, down when it has left; returns the
    /// command that does it (sent to the Runtime).
    MoveKinematicCommand moveLift(const CharacterState& character, float dt);
    /// Coins the character touched in `events` (sensor begins): counts them and returns the coins to remove.
    std::vector<BodyId> collect(const std::vector<StepEvents>& events, BodyId characterBody);
    bool atEnd(Vec3 feet) const { return feet.x > kEndX - 0.5f && feet.y > kLiftHigh - 0.1f; }
};

}  // namespace rubble::viewer
