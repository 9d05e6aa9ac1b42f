#pragma once
// The accuracy report's spinning rods (its "tunnelling" scene), also what the solver's spinning-rod test holds it to
// (tests/accuracy/spinning_rods_test.cpp): one definition of the scene and of a rod that passed its wall.
#include <cstddef>
#include <vector>

#include "rubble/world.h"

namespace rubble::accuracy {

struct SpinningRods {
    std::vector<BodyId> rods;
    std::vector<float> walls;  ///< x of each rod's wall's near face

    /// Whether a tip of rod i is beyond its wall's far face at a point inside the face: a tip that swung round the
    /// wall's edge, or ended beside it, did not pass through it.
    bool tipPassedWall(const World& world, std::size_t i) const;
};

/// `copies` rods 2 m long and 2 cm thick spinning at 60-120 rad/s about their centres, 0.3-0.9 m in front of 2 cm
/// walls 4 m high and 1 m wide, one every 2 m along z: their tips sweep up to 2 m of arc a step, through where the
/// wall is.
SpinningRods buildSpinningRods(World& world, int copies);

}  // namespace rubble::accuracy
