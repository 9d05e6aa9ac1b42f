#pragma once
// What `rubble accuracy` writes: a CSV of every run, one plot per scene (error against ms per step, log-log, the
// Pareto front drawn and the defaults marked, drawn by gnuplot), and the Markdown report (docs/ACCURACY.md) with a
// table per scene, the plots, the recommended settings and the effects' costs.
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "effect_costs.h"
#include "measurement.h"
#include "sweeps.h"

namespace rubble::accuracy {

struct RunResult {
    PlannedRun run;
    Measured measured;
    std::string failure;  ///< why the run could not be measured (empty when it was)

    bool usable() const;  ///< measured, with a finite error
};

struct SceneResults {
    MeasurementScene scene;
    std::vector<RunResult> runs;  ///< runs[0] is the defaults
    double seconds = 0;           ///< wall time the scene's runs took
};

/// Indices of the points (ms, error) on the Pareto front, by increasing ms: no other point is at least as fast and at
/// least as accurate while better in one of the two. Points with a non-finite coordinate are never on it.
std::vector<std::size_t> paretoFront(const std::vector<std::pair<double, double>>& points);

/// The report's advice for one scene: the cheapest run that meets the scene's target, and the most accurate run
/// within a time budget of the defaults' ms per step times each factor.
struct Recommendation {
    std::optional<std::size_t> cheapestMeetingTarget;
    std::vector<std::pair<double, std::optional<std::size_t>>> bestWithinBudget;  ///< (factor, run)
};
Recommendation recommend(const SceneResults& results, const std::vector<double>& budgetFactors);

/// Where and how the report was made, for its header.
struct ReportContext {
    std::string command;
    std::string machine;
    std::string build;
    std::string date;
    double seconds = 0;  ///< wall time of the whole report
    Length length = Length::Full;
};

void writeCsv(const std::string& path, const std::vector<SceneResults>& results);
/// Writes `dir`/<scene>.dat, .gp and .svg; throws rubble::Error when gnuplot fails.
void writePlots(const std::string& dir, const std::vector<SceneResults>& results);
/// `plotDir` is the plots' directory relative to the Markdown file.
void writeMarkdown(const std::string& path, const std::string& plotDir, const std::vector<SceneResults>& results,
                   const EffectCosts& effects, const ReportContext& context);

}  // namespace rubble::accuracy
