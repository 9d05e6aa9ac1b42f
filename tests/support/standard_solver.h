#pragma once
// The solver SCENES.md names for S1-S4 (8 + 2 iterations, one substep: Baumgarte in Rubble), which tests that measure
// it rather than the defaults pin.
#include "rubble/settings.h"

namespace rubble::test {

inline WorldSettings withStandardScenesSolver(WorldSettings s) {
    s.substeps = 1;
    s.velocityIterations = 8;
    s.positionIterations = 2;
    s.solver.positionCorrection = PositionCorrection::Baumgarte;
    return s;
}

}  // namespace rubble::test
