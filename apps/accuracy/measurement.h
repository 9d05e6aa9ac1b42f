#pragma once
// The accuracy report's measurement scenes (`rubble accuracy`, docs/ACCURACY.md): each builds a small world through
// the public API with the settings a sweep hands it, steps it, and returns its error against an answer that does not
// come from the engine (a closed form, or the statics of a structure that should stand) next to the median time a
// step took. Scenes are built of several independent copies of the measured system side by side, so that the time
// per step is the cost of real work rather than of the step's fixed overhead; the error is the worst copy's.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rubble/settings.h"

namespace rubble::accuracy {

/// The settings a measurement scene is swept across (sweeps.h says over which values).
enum class Knob : std::uint8_t {
    TimeStep,
    Substeps,
    VelocityIterations,
    PositionIterations,
    PositionCorrection,
    Integrator,
    WarmStarting,
    SeedRestingLoads,
    ContinuousCollision,
    ManifoldReuse,
    BroadPhase,  ///< time only: every choice must give the same state
    Threads,     ///< time only: every count must give the same state
};
inline constexpr int kKnobCount = 12;

/// How long a measurement runs: the full report, or the short one CI runs so that the command cannot rot.
enum class Length : std::uint8_t { Full, Quick };

/// One measured run of a scene.
struct Measured {
    double error = 0;             ///< the scene's main error, in its unit
    double secondaryError = 0;    ///< the scene's second error (0 when it has none)
    double msPerStep = 0;         ///< median wall time of a step
    long steps = 0;               ///< steps taken
    float timeStep = 0;           ///< of each step, s
    std::uint64_t stateHash = 0;  ///< World::stateHash at the end: time-only knobs must not change it

    /// What the run's settings cost per 1/60 s of simulated time: its median step time times the steps that cover a
    /// 60 Hz frame. Runs at different time steps are compared by this, not by their time per step.
    double msPerFrame() const { return timeStep > 0 ? msPerStep / (60.0 * static_cast<double>(timeStep)) : 0.0; }
};

struct MeasurementScene {
    std::string id;                            ///< file-name friendly: "free_fall"
    std::string title;                         ///< "Free fall"
    std::string description;                   ///< what is built and what it is compared with
    std::string errorName;                     ///< "height error after 2 s"
    std::string unit;                          ///< "m", "deg", "%", "bodies", ...
    std::string secondaryName, secondaryUnit;  ///< empty when the scene measures one error
    /// Error a user would call good enough here, in `unit` (the report's recommendation finds the cheapest setting
    /// that meets it).
    double target = 0;
    std::vector<Knob> knobs;  ///< the knobs that change what this scene measures (or, time-only, what it costs)
    bool sweepPairs = false;  ///< also run the pairs (time step x substeps, iterations x position correction)
    /// Builds, steps and measures the scene with these settings (their effects are the scene's own business).
    std::function<Measured(const WorldSettings&, Length)> measure;
};

/// Every measurement scene, analytic ones first; the stability suite's cases are read from `scenesDir`/hard.
std::vector<MeasurementScene> measurementScenes(const std::string& scenesDir);

/// Median of the samples (the mean of the two middle ones for an even count); 0 for none.
double median(std::vector<double> samples);

}  // namespace rubble::accuracy
