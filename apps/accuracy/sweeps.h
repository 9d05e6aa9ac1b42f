#pragma once
// Which settings each measurement scene is run with: the defaults, every knob the scene responds to swept one at a
// time from them, and (for scenes that ask) the main pairs swept together: time step x substeps and velocity
// iterations x position correction.
#include <string>
#include <string_view>
#include <vector>

#include "measurement.h"

namespace rubble::accuracy {

std::string_view knobName(Knob knob);  ///< "time step", "substeps", ...

/// One run of a plan: the settings, the sweep it belongs to ("defaults", "time step", "time step x substeps") and
/// the value(s) that sweep gave it ("1/120 s", "1/120 s, 2 substeps").
struct PlannedRun {
    WorldSettings settings;
    std::string sweep;
    std::string value;
    bool timeOnly = false;  ///< a time-only knob's run: its state must equal the defaults' run
};

/// The runs of `scene` from `defaults`. --quick keeps each knob's default and its two extremes, and the pairs'
/// extremes. Runs whose settings are equal (the defaults appear in every sweep) are listed once per sweep; `key`
/// tells which ones to measure only once.
std::vector<PlannedRun> planRuns(const MeasurementScene& scene, const WorldSettings& defaults, Length length);

/// Text that is equal for two settings exactly when every knob has the same value.
std::string settingsKey(const WorldSettings& settings);

/// The settings in a few words, as the report's tables show them ("1/60 s x 4, 2+1 soft_step, ...").
std::string describeSettings(const WorldSettings& settings);

}  // namespace rubble::accuracy
