#include "runtime/kinematic_moves.h"

#include <algorithm>
#include <cmath>

#include "rubble/error.h"

namespace rubble::detail {

void KinematicMoves::start(World& world, const MoveKinematicCommand& move, float stepSeconds) {
    const double steps = std::round(static_cast<double>(move.duration) / stepSeconds);
    const auto stepsLeft = static_cast<std::uint32_t>(std::clamp(steps, 1.0, 1e9));
    world.moveKinematic(move.body, move.position, move.orientation, static_cast<float>(stepsLeft) * stepSeconds);
    const auto same = [&](const Move& m) { return m.target.body == move.body; };
    moves_.erase(std::remove_if(moves_.begin(), moves_.end(), same), moves_.end());
    moves_.push_back({move, stepsLeft});
}

void KinematicMoves::beforeStep(World& world, float stepSeconds, std::vector<std::string>& errors) {
    const auto refused = [&](const Move& m) {
        try {
            world.moveKinematic(m.target.body, m.target.position, m.target.orientation,
                                static_cast<float>(m.stepsLeft) * stepSeconds);
            return false;
        } catch (const Error& e) {
            errors.emplace_back(e.what());
            return true;
        }
    };
    moves_.erase(std::remove_if(moves_.begin(), moves_.end(), refused), moves_.end());
}

void KinematicMoves::afterStep(World& world) {
    const auto arrived = [&](Move& m) {
        if (--m.stepsLeft > 0) return false;
        if (world.isValid(m.target.body)) {
            world.setLinearVelocity(m.target.body, {});
            world.setAngularVelocity(m.target.body, {});
        }
        return true;
    };
    moves_.erase(std::remove_if(moves_.begin(), moves_.end(), arrived), moves_.end());
}

}  // namespace rubble::detail
