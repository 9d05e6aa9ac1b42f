#pragma once
#include <string>
#include <vector>

#include "measurement.h"

namespace rubble::accuracy {

/// Scenes with closed-form answers (analytic_scenes.cpp).
std::vector<MeasurementScene> analyticScenes();
/// Scenes measured against the statics of what should stand, a joint's length, or a conserved quantity, and the
/// stability suite's hard cases read from `scenesDir`/hard (reference_scenes.cpp).
std::vector<MeasurementScene> referenceScenes(const std::string& scenesDir);

}  // namespace rubble::accuracy
