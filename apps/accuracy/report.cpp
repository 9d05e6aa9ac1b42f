#include "report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>

#include "rubble/error.h"

namespace rubble::accuracy {
namespace {

std::string format(const char* pattern, double value) {
    char text[64];
    std::snprintf(text, sizeof text, pattern, value);
    return text;
}

std::string formatError(double value) {
    if (std::isnan(value)) return "nan";
    if (value == 0) return "0";
    return format("%.3g", value);
}

std::string formatMs(double ms) { return format(ms < 0.1 ? "%.4f" : ms < 10 ? "%.3f" : "%.1f", ms); }

std::ofstream openForWriting(const std::string& path) {
    std::ofstream out(path);
    if (!out) throw Error("accuracy: cannot write '" + path + "'");
    return out;
}

/// CSV field: quoted when it holds a comma or a quote.
std::string csvField(const std::string& text) {
    if (text.find_first_of(",\"") == std::string::npos) return text;
    std::string out = "\"";
    for (const char c : text) {
        if (c == '"') out.push_back('"');
        out.push_back(c);
    }
    return out + "\"";
}

std::string quoted(const std::string& text) {
    std::string out = "\"";
    for (const char c : text) {
        if (c == '"' || c == '\\') out.push_back('\\');
        out.push_back(c);
    }
    return out + "\"";
}

std::vector<std::pair<double, double>> points(const SceneResults& results) {
    std::vector<std::pair<double, double>> p;
    for (const RunResult& r : results.runs)
        p.emplace_back(r.usable() ? r.measured.msPerFrame() : std::nan(""),
                       r.usable() ? r.measured.error : std::nan(""));
    return p;
}

std::string errorLabel(const MeasurementScene& scene) { return scene.errorName + " (" + scene.unit + ")"; }

std::string valueWithUnit(double value, const std::string& unit) { return formatError(value) + " " + unit; }

/// Runs of the scene measured once each (the same settings in several sweeps are one run): indices of the first.
std::vector<std::size_t> distinctRuns(const SceneResults& results) {
    std::vector<std::size_t> out;
    std::map<std::string, bool> seen;
    for (std::size_t i = 0; i < results.runs.size(); ++i)
        if (seen.emplace(settingsKey(results.runs[i].run.settings), true).second) out.push_back(i);
    return out;
}

}  // namespace

bool RunResult::usable() const { return failure.empty() && std::isfinite(measured.error); }

std::vector<std::size_t> paretoFront(const std::vector<std::pair<double, double>>& points) {
    std::vector<std::size_t> order;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (std::isfinite(points[i].first) && std::isfinite(points[i].second)) order.push_back(i);
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return points[a] != points[b] ? points[a] < points[b] : a < b; });
    std::vector<std::size_t> front;
    double best = std::numeric_limits<double>::infinity();
    for (const std::size_t i : order) {
        // Sorted by ms, then error: a point is on the front when it is more accurate than every faster one (and the
        // first of equal points stands for them).
        if (points[i].second < best) {
            front.push_back(i);
            best = points[i].second;
        }
    }
    return front;
}

Recommendation recommend(const SceneResults& results, const std::vector<double>& budgetFactors) {
    Recommendation advice;
    const std::vector<std::size_t> distinct = distinctRuns(results);
    const auto better = [&](std::optional<std::size_t> current, std::size_t candidate, bool byTime) {
        if (!current) return true;
        const Measured& a = results.runs[candidate].measured;
        const Measured& b = results.runs[*current].measured;
        return byTime ? a.msPerFrame() < b.msPerFrame()
                      : a.error < b.error || (a.error == b.error && a.msPerFrame() < b.msPerFrame());
    };
    for (const std::size_t i : distinct) {
        const RunResult& r = results.runs[i];
        if (r.usable() && r.measured.error <= results.scene.target && better(advice.cheapestMeetingTarget, i, true))
            advice.cheapestMeetingTarget = i;
    }
    const RunResult& defaults = results.runs.front();
    for (const double factor : budgetFactors) {
        std::optional<std::size_t> best;
        if (defaults.usable())
            for (const std::size_t i : distinct) {
                const RunResult& r = results.runs[i];
                if (r.usable() && r.measured.msPerFrame() <= factor * defaults.measured.msPerFrame() &&
                    better(best, i, false))
                    best = i;
            }
        advice.bestWithinBudget.emplace_back(factor, best);
    }
    return advice;
}

void writeCsv(const std::string& path, const std::vector<SceneResults>& results) {
    std::ofstream out = openForWriting(path);
    out << "scene,sweep,value,time_step_s,substeps,velocity_iterations,position_iterations,position_correction,"
           "integrator,warm_starting,seed_resting_loads,continuous_collision,manifold_reuse_m,broad_phase,threads,"
           "steps,ms_per_step,ms_per_60hz_frame,error,error_name,error_unit,secondary_error,secondary_name,secondary_"
           "unit,state_hash,"
           "failure\n";
    for (const SceneResults& scene : results)
        for (const RunResult& r : scene.runs) {
            const WorldSettings& s = r.run.settings;
            char hash[20];
            std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(r.measured.stateHash));
            out << scene.scene.id << ',' << csvField(r.run.sweep) << ',' << csvField(r.run.value) << ','
                << format("%.9g", static_cast<double>(s.timeStep)) << ',' << s.substeps << ',' << s.velocityIterations
                << ',' << s.positionIterations << ',' << positionCorrectionName(s.solver.positionCorrection) << ','
                << integratorName(s.integrator) << ',' << s.solver.warmStarting << ',' << s.solver.seedRestingLoads
                << ',' << s.effects.has(Effect::ContinuousCollision) << ','
                << format("%g", static_cast<double>(s.manifoldReuseDistance)) << ',' << broadPhaseName(s.broadPhase)
                << ',' << s.threads << ',' << r.measured.steps << ',' << format("%.6g", r.measured.msPerStep) << ','
                << format("%.6g", r.measured.msPerFrame()) << ',' << format("%.9g", r.measured.error) << ','
                << csvField(scene.scene.errorName) << ',' << scene.scene.unit << ','
                << format("%.9g", r.measured.secondaryError) << ',' << csvField(scene.scene.secondaryName) << ','
                << scene.scene.secondaryUnit << ',' << hash << ',' << csvField(r.failure) << '\n';
        }
    if (!out) throw Error("accuracy: writing '" + path + "' failed");
}

void writePlots(const std::string& dir, const std::vector<SceneResults>& results) {
    for (const SceneResults& scene : results) {
        const std::vector<std::pair<double, double>> p = points(scene);
        // Log axes cannot show 0: errors of 0 are drawn a decade under the smallest error measured.
        double smallest = std::numeric_limits<double>::infinity();
        for (const auto& [ms, error] : p)
            if (error > 0 && std::isfinite(error)) smallest = std::min(smallest, error);
        const double zeroAt = std::isfinite(smallest) ? smallest / 10 : 1e-9;
        bool anyZero = false;
        const auto y = [&](double error) {
            anyZero |= error <= 0;
            return error > 0 ? error : zeroAt;
        };
        const std::string base = dir + "/" + scene.scene.id;
        std::vector<std::string> sweeps;
        {
            std::ofstream data = openForWriting(base + ".dat");
            for (const RunResult& r : scene.runs) {
                if (std::find(sweeps.begin(), sweeps.end(), r.run.sweep) != sweeps.end()) continue;
                sweeps.push_back(r.run.sweep);
                if (sweeps.size() > 1) data << "\n\n";
                for (std::size_t i = 0; i < scene.runs.size(); ++i)
                    if (scene.runs[i].run.sweep == r.run.sweep && scene.runs[i].usable())
                        data << format("%.6g", p[i].first) << ' ' << format("%.6g", y(p[i].second)) << ' '
                             << quoted(scene.runs[i].run.value) << '\n';
            }
            data << "\n\n";  // the front
            for (const std::size_t i : paretoFront(p))
                data << format("%.6g", p[i].first) << ' ' << format("%.6g", y(p[i].second)) << ' '
                     << quoted(scene.runs[i].run.value) << '\n';
            data << "\n\n";  // the defaults
            if (scene.runs.front().usable())
                data << format("%.6g", p[0].first) << ' ' << format("%.6g", y(p[0].second)) << " \"defaults\"\n";
        }
        {
            std::ofstream script = openForWriting(base + ".gp");
            const int threads = scene.runs.front().run.settings.threads;
            script << "set terminal svg size 1000,620 dynamic font 'sans,11' background rgb 'white'\n"
                   << "set output " << quoted(base + ".svg") << "\n"
                   << "set encoding utf8\n"
                   << "set title "
                   << quoted(scene.scene.title + (anyZero ? " (errors of 0 drawn at " + formatError(zeroAt) + ")" : ""))
                   << " noenhanced\n"
                   << "set logscale xy\nset grid xtics ytics lc rgb '#dddddd'\n"
                   << "set xlabel "
                   << quoted("ms per 1/60 s simulated (median step time x steps per 1/60 s), " +
                             std::to_string(threads) + (threads == 1 ? " thread" : " threads"))
                   << "\n"
                   << "set ylabel " << quoted(errorLabel(scene.scene)) << " noenhanced\n"
                   << "set key outside right top Left reverse noenhanced\nset offsets graph 0.05, graph 0.05, graph "
                      "0.1, graph 0.1\n"
                   << "plot ";
            const std::string data = quoted(base + ".dat");
            for (std::size_t k = 0; k < sweeps.size(); ++k) {
                if (sweeps[k] == "defaults") continue;
                script << data << " index " << k << " using 1:2 with points pt " << (k % 13) + 1 << " ps 1.1 title "
                       << quoted(sweeps[k]) << ", \\\n     ";
            }
            const std::size_t front = sweeps.size(), defaults = sweeps.size() + 1;
            script << data << " index " << front
                   << " using 1:2 with lines lw 2 lc rgb '#333333' title 'Pareto front', \\\n     " << data << " index "
                   << front
                   << " using 1:2:3 with labels font ',8' left offset char 0.6,0.4 tc rgb '#333333' notitle, \\\n     "
                   << data << " index " << defaults << " using 1:2 with points pt 6 ps 3 lw 2 lc rgb 'red' title "
                   << "'defaults'\n";
        }
        const std::string command = "gnuplot " + quoted(base + ".gp") + " 2> " + quoted(base + ".log");
        if (std::system(command.c_str()) != 0) {
            std::ifstream log(base + ".log");
            std::stringstream text;
            text << log.rdbuf();
            throw Error("accuracy: gnuplot could not draw " + base + ".svg:\n" + text.str());
        }
        for (const char* ext : {".dat", ".gp", ".log"}) std::remove((base + ext).c_str());
    }
}

void writeMarkdown(const std::string& path, const std::string& plotDir, const std::vector<SceneResults>& results,
                   const EffectCosts& effects, const ReportContext& context) {
    std::ofstream md = openForWriting(path);
    md << "# What accuracy costs in time\n\n"
       << "<!-- Generated by `" << context.command << "`: edit apps/accuracy/, not this file. -->\n\n"
       << "Every scene below is run with Rubble's default settings, with each knob that matters to it swept one at a "
          "time from the defaults, and with the main pairs swept together (time step x substeps, velocity "
          "iterations x position correction). Each run records its error against an answer that does not come from "
          "the engine (a closed form, the statics of a structure that should stand, a conserved quantity) and the "
          "median wall time of a step; what a setting costs is that time per 1/60 s of simulated time (the median "
          "step times the steps in 1/60 s), so that a smaller time step pays for its extra steps. The plots put "
          "error against that cost on log-log axes: the line is the Pareto "
          "front (no run is both faster and more accurate than a run on it), the red ring is the defaults. Every run "
          "is in [accuracy.csv]("
       << plotDir << "/accuracy.csv).\n\n"
       << "| | |\n|---|---|\n"
       << "| command | `" << context.command << "`"
       << (context.length == Length::Quick ? " (quick: extremes only, short runs)" : "") << " |\n"
       << "| machine | " << context.machine << " |\n"
       << "| build | " << context.build << " |\n"
       << "| made | " << context.date << ", in " << format("%.0f", context.seconds) << " s |\n\n"
       << "Times are medians over each run's steps, on a shared machine whose speed varies by up to a third from "
          "minute to minute: compare a scene's runs with each other, not with runs made another day. Small scenes "
          "show mostly the step's fixed cost; that is why every scene is built of many copies of what it measures.\n\n";

    md << "## Recommended settings\n\n"
       << "For each scene: the defaults, the cheapest setting measured that meets the scene's target error, and the "
          "most accurate setting within one and four times the defaults' time. Times are ms per 1/60 s of simulated "
          "time.\n\n"
       << "| scene | target | defaults: error, ms | cheapest within target | best within 1x | best within 4x |\n"
       << "|---|---|---|---|---|---|\n";
    for (const SceneResults& scene : results) {
        const Recommendation advice = recommend(scene, {1.0, 4.0});
        const RunResult& d = scene.runs.front();
        const auto cell = [&](std::optional<std::size_t> i) -> std::string {
            if (!i) return "none measured";
            const RunResult& r = scene.runs[*i];
            return (r.run.sweep == "defaults" ? std::string("defaults") : r.run.value) + ": " +
                   valueWithUnit(r.measured.error, scene.scene.unit) + ", " + formatMs(r.measured.msPerFrame()) + " ms";
        };
        md << "| [" << scene.scene.title << "](#" << scene.scene.id << ") | "
           << valueWithUnit(scene.scene.target, scene.scene.unit) << " | "
           << (d.usable() ? valueWithUnit(d.measured.error, scene.scene.unit) + ", " +
                                formatMs(d.measured.msPerFrame()) + " ms"
                          : "failed: " + d.failure)
           << " | " << cell(advice.cheapestMeetingTarget) << " | " << cell(advice.bestWithinBudget[0].second) << " | "
           << cell(advice.bestWithinBudget[1].second) << " |\n";
    }

    md << "\n## What each effect costs\n\n"
       << "The third promise, simulate only the effects a scene calls for, measured: " << effects.description
       << ", run with every effect declared and with each one left out in turn (the world also drops an effect its "
          "content cannot show; `simulated` says what ran).\n\n"
       << "Leaving an effect out changes what happens (without gravity nothing lands, without friction the bodies "
          "roll and slide on), so what an effect costs is the scene's, not one stage's alone. A negative cost is "
          "time the effect saves: sleeping's, once the bodies rest. The last column is the median over the last 2 s, "
          "when what can sleep has had time to.\n\n"
       << "| effect | simulated without it | ms/step without it | the effect's cost | stages that ran only with it | "
          "stage whose time it changed most | ms/step without it, last 2 s |\n"
       << "|---|---|---|---|---|---|---|\n"
       << "| (all " << __builtin_popcount(effects.all.simulated.bits) << ", none left out) | | "
       << formatMs(effects.all.msPerStep) << " | | | | " << formatMs(effects.all.msPerStepAtEnd) << " |\n";
    const auto signedMs = [](double ms) { return format("%+.3g ms", ms); };
    for (const auto& [effect, run] : effects.without) {
        std::string stopped;
        int mostChanged = -1;
        double change = 0;
        for (int k = 0; k < kStageCount; ++k) {
            const auto s = static_cast<std::size_t>(k);
            if (effects.all.stageRan[s] && !run.stageRan[s])
                stopped += (stopped.empty() ? "" : ", ") + std::string(stageName(static_cast<Stage>(k)));
            const double delta = effects.all.stageMs[s] - run.stageMs[s];
            if (std::abs(delta) > std::abs(change)) change = delta, mostChanged = k;
        }
        const double cost = effects.all.msPerStep - run.msPerStep;
        md << "| " << effectName(effect) << " | "
           << (run.simulated == effects.all.simulated.without(effect) ? "the rest" : "differs") << " | "
           << formatMs(run.msPerStep) << " | " << signedMs(cost) << " ("
           << format("%+.0f", run.msPerStep > 0 ? 100.0 * cost / run.msPerStep : 0.0) << "%) | "
           << (stopped.empty() ? "-" : stopped) << " | "
           << (mostChanged < 0 ? std::string("-")
                               : std::string(stageName(static_cast<Stage>(mostChanged))) + " " + signedMs(change))
           << " | " << formatMs(run.msPerStepAtEnd) << " |\n";
    }
    md << "\nWith every effect, " << effects.all.sleepingAtEnd << " bodies were asleep after the last step.\n";

    for (const SceneResults& scene : results) {
        const MeasurementScene& s = scene.scene;
        md << "\n<a id=\"" << s.id << "\"></a>\n\n## " << s.title << "\n\n"
           << s.description << " Error: " << errorLabel(s);
        if (!s.secondaryName.empty()) md << "; also " << s.secondaryName << " (" << s.secondaryUnit << ")";
        md << ". Target: " << valueWithUnit(s.target, s.unit) << ". " << scene.runs.size() << " runs in "
           << format("%.1f", scene.seconds) << " s.\n\n"
           << "![" << s.title << ": error against ms per step](" << plotDir << "/" << s.id << ".svg)\n\n";
        const std::vector<std::pair<double, double>> p = points(scene);
        const std::vector<std::size_t> front = paretoFront(p);
        const std::string defaultsKey = settingsKey(scene.runs.front().run.settings);
        bool identical = true, anyTimeOnly = false;
        for (const RunResult& r : scene.runs)
            if (r.run.timeOnly) {
                anyTimeOnly = true;
                identical &= r.failure.empty() && r.measured.stateHash == scene.runs.front().measured.stateHash;
            }
        if (anyTimeOnly)
            md << "Time-only knobs (broad phase, threads): the final state of every run "
               << (identical ? "is bit for bit the defaults'" : "**differs from the defaults'**") << ".\n\n";
        md << "| sweep | setting | " << s.errorName << " (" << s.unit << ") |";
        if (!s.secondaryName.empty()) md << ' ' << s.secondaryName << " (" << s.secondaryUnit << ") |";
        md << " ms/step | ms per 1/60 s | steps |\n|---|---|---|" << (s.secondaryName.empty() ? "" : "---|")
           << "---|---|---|\n";
        for (std::size_t i = 0; i < scene.runs.size(); ++i) {
            const RunResult& r = scene.runs[i];
            const bool onFront = std::find(front.begin(), front.end(), i) != front.end();
            const bool isDefaults = settingsKey(r.run.settings) == defaultsKey;
            md << "| " << r.run.sweep << " | " << (isDefaults ? "**" + r.run.value + "**" : r.run.value)
               << (onFront ? " (front)" : "") << " | ";
            if (!r.failure.empty()) {
                md << "failed: " << r.failure << " |" << (s.secondaryName.empty() ? "" : " |") << " | | |\n";
                continue;
            }
            md << formatError(r.measured.error) << " |";
            if (!s.secondaryName.empty()) md << ' ' << formatError(r.measured.secondaryError) << " |";
            md << ' ' << formatMs(r.measured.msPerStep) << " | " << formatMs(r.measured.msPerFrame()) << " | "
               << r.measured.steps << " |\n";
        }
    }
    if (!md) throw Error("accuracy: writing '" + path + "' failed");
}

}  // namespace rubble::accuracy
