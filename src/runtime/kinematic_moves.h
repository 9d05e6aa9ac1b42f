#pragma once
// Kinematic moves of the runtime (MoveKinematicCommand): a body sent to a pose over some time is steered there step
// by step (World::moveKinematic with the time left, so the steps in between share the way and rounding does not add
// up) and stops when it arrives, however many physics steps a game frame holds.
#include <cstdint>
#include <string>
#include <vector>

#include "rubble/runtime.h"
#include "rubble/world.h"

namespace rubble::detail {

class KinematicMoves {
public:
    /// Starts (or replaces) the body's move; throws rubble::Error when the world refuses it (not kinematic, stale).
    void start(World& world, const MoveKinematicCommand& move, float stepSeconds);
    /// Before a step: each body's velocities for the time it has left. A body the world now refuses (destroyed
    /// since) is dropped, its message added to `errors`.
    void beforeStep(World& world, float stepSeconds, std::vector<std::string>& errors);
    /// After a step: bodies that arrived stop.
    void afterStep(World& world);

private:
    struct Move {
        MoveKinematicCommand target;
        std::uint32_t stepsLeft = 1;
    };
    std::vector<Move> moves_;
};

}  // namespace rubble::detail
