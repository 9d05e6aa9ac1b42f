#include "sweeps.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

namespace rubble::accuracy {
namespace {

/// A knob's values: each sets the knob in a copy of the settings and names what it set.
struct KnobValue {
    std::string label;
    std::function<void(WorldSettings&)> apply;
};

std::string formatHertz(int hertz) { return "1/" + std::to_string(hertz) + " s"; }

std::string formatMillimetres(float metres) {
    char text[32];
    std::snprintf(text, sizeof text, "%g mm", static_cast<double>(metres) * 1000.0);
    return text;
}

std::vector<KnobValue> knobValues(Knob knob) {
    std::vector<KnobValue> values;
    switch (knob) {
        case Knob::TimeStep:
            for (const int hertz : {30, 60, 120, 240, 480})
                values.push_back(
                    {formatHertz(hertz), [hertz](WorldSettings& s) { s.timeStep = static_cast<float>(1.0 / hertz); }});
            break;
        case Knob::Substeps:
            for (const int n : {1, 2, 4, 8})
                values.push_back({std::to_string(n) + (n == 1 ? " substep" : " substeps"),
                                  [n](WorldSettings& s) { s.substeps = n; }});
            break;
        case Knob::VelocityIterations:
            for (const int n : {1, 2, 4, 8, 16, 32})
                values.push_back(
                    {std::to_string(n) + " velocity it.", [n](WorldSettings& s) { s.velocityIterations = n; }});
            break;
        case Knob::PositionIterations:
            for (const int n : {0, 1, 2, 4, 8})
                values.push_back(
                    {std::to_string(n) + " position it.", [n](WorldSettings& s) { s.positionIterations = n; }});
            break;
        case Knob::PositionCorrection:
            for (const auto p :
                 {PositionCorrection::SoftStep, PositionCorrection::Baumgarte, PositionCorrection::SplitImpulse})
                values.push_back({std::string(positionCorrectionName(p)),
                                  [p](WorldSettings& s) { s.solver.positionCorrection = p; }});
            break;
        case Knob::Integrator:
            for (const auto i : {Integrator::SemiImplicitEuler, Integrator::ExplicitEuler, Integrator::Verlet,
                                 Integrator::RungeKutta4})
                values.push_back({std::string(integratorName(i)), [i](WorldSettings& s) { s.integrator = i; }});
            break;
        case Knob::WarmStarting:
            for (const bool on : {true, false})
                values.push_back({on ? "warm starting" : "no warm starting",
                                  [on](WorldSettings& s) { s.solver.warmStarting = on; }});
            break;
        case Knob::SeedRestingLoads:
            for (const bool on : {true, false})
                values.push_back({on ? "resting-load seed" : "no resting-load seed",
                                  [on](WorldSettings& s) { s.solver.seedRestingLoads = on; }});
            break;
        case Knob::ContinuousCollision:
            for (const bool on : {false, true})
                values.push_back({on ? "continuous collision" : "no continuous collision", [on](WorldSettings& s) {
                                      s.effects = on ? s.effects.with(Effect::ContinuousCollision)
                                                     : s.effects.without(Effect::ContinuousCollision);
                                  }});
            break;
        case Knob::ManifoldReuse:
            for (const float d : {0.0f, 0.0005f, 0.001f, 0.005f, 0.02f})
                values.push_back(
                    {"reuse " + formatMillimetres(d), [d](WorldSettings& s) { s.manifoldReuseDistance = d; }});
            break;
        case Knob::BroadPhase:
            for (const auto b : {BroadPhaseKind::Auto, BroadPhaseKind::SweepAndPrune, BroadPhaseKind::Grid})
                values.push_back({std::string(broadPhaseName(b)), [b](WorldSettings& s) { s.broadPhase = b; }});
            break;
        case Knob::Threads:
            for (const int n : {1, 2})
                values.push_back(
                    {std::to_string(n) + (n == 1 ? " thread" : " threads"), [n](WorldSettings& s) { s.threads = n; }});
            break;
    }
    return values;
}

/// The index of the value the defaults already have (its label is the one that applies to them unchanged).
std::size_t defaultIndex(const std::vector<KnobValue>& values, const WorldSettings& defaults) {
    for (std::size_t i = 0; i < values.size(); ++i) {
        WorldSettings s = defaults;
        values[i].apply(s);
        if (settingsKey(s) == settingsKey(defaults)) return i;
    }
    return values.size();
}

/// --quick: the default and the two extremes.
std::vector<KnobValue> quickValues(std::vector<KnobValue> values, const WorldSettings& defaults) {
    if (values.size() <= 3) return values;
    const std::size_t d = defaultIndex(values, defaults);
    std::vector<KnobValue> kept;
    for (std::size_t i = 0; i < values.size(); ++i)
        if (i == 0 || i + 1 == values.size() || i == d) kept.push_back(values[i]);
    return kept;
}

}  // namespace

std::string_view knobName(Knob knob) {
    switch (knob) {
        case Knob::TimeStep:
            return "time step";
        case Knob::Substeps:
            return "substeps";
        case Knob::VelocityIterations:
            return "velocity iterations";
        case Knob::PositionIterations:
            return "position iterations";
        case Knob::PositionCorrection:
            return "position correction";
        case Knob::Integrator:
            return "integrator";
        case Knob::WarmStarting:
            return "warm starting";
        case Knob::SeedRestingLoads:
            return "resting-load seed";
        case Knob::ContinuousCollision:
            return "continuous collision";
        case Knob::ManifoldReuse:
            return "manifold reuse distance";
        case Knob::BroadPhase:
            return "broad phase";
        case Knob::Threads:
            return "threads";
    }
    return "?";
}

std::string settingsKey(const WorldSettings& s) {
    char text[256];
    std::snprintf(text, sizeof text, "%a|%d|%d|%d|%d|%d|%d|%d|%u|%a|%d|%d", static_cast<double>(s.timeStep), s.substeps,
                  s.velocityIterations, s.positionIterations, static_cast<int>(s.solver.positionCorrection),
                  static_cast<int>(s.integrator), s.solver.warmStarting ? 1 : 0, s.solver.seedRestingLoads ? 1 : 0,
                  s.effects.bits, static_cast<double>(s.manifoldReuseDistance), static_cast<int>(s.broadPhase),
                  s.threads);
    return text;
}

std::string describeSettings(const WorldSettings& s) {
    char text[256];
    std::snprintf(text, sizeof text, "1/%.0f s x %d, %d+%d %s, %s%s%s%s, reuse %g mm, %s, %d thr.",
                  1.0 / static_cast<double>(s.timeStep), s.substeps, s.velocityIterations, s.positionIterations,
                  std::string(positionCorrectionName(s.solver.positionCorrection)).c_str(),
                  std::string(integratorName(s.integrator)).c_str(), s.solver.warmStarting ? "" : ", no warm start",
                  s.solver.warmStarting && !s.solver.seedRestingLoads ? ", no seed" : "",
                  s.effects.has(Effect::ContinuousCollision) ? ", CCD" : "",
                  static_cast<double>(s.manifoldReuseDistance) * 1000.0,
                  std::string(broadPhaseName(s.broadPhase)).c_str(), s.threads);
    return text;
}

std::vector<PlannedRun> planRuns(const MeasurementScene& scene, const WorldSettings& defaults, Length length) {
    std::vector<PlannedRun> runs;
    runs.push_back({defaults, "defaults", "defaults"});
    for (const Knob knob : scene.knobs) {
        std::vector<KnobValue> values = knobValues(knob);
        if (length == Length::Quick) values = quickValues(std::move(values), defaults);
        const bool timeOnly = knob == Knob::BroadPhase || knob == Knob::Threads;
        for (const KnobValue& v : values) {
            WorldSettings s = defaults;
            v.apply(s);
            runs.push_back({s, std::string(knobName(knob)), v.label, timeOnly});
        }
    }
    if (!scene.sweepPairs) return runs;
    const auto has = [&](Knob k) { return std::find(scene.knobs.begin(), scene.knobs.end(), k) != scene.knobs.end(); };
    const std::pair<Knob, Knob> pairs[] = {{Knob::TimeStep, Knob::Substeps},
                                           {Knob::VelocityIterations, Knob::PositionCorrection}};
    for (const auto& [first, second] : pairs) {
        if (!has(first) || !has(second)) continue;
        std::vector<KnobValue> as = knobValues(first), bs = knobValues(second);
        if (length == Length::Quick) {
            as = {as.front(), as.back()};
            bs = {bs.front(), bs.back()};
        }
        const std::string sweep = std::string(knobName(first)) + " x " + std::string(knobName(second));
        for (const KnobValue& a : as)
            for (const KnobValue& b : bs) {
                WorldSettings s = defaults;
                a.apply(s);
                b.apply(s);
                runs.push_back({s, sweep, a.label + ", " + b.label});
            }
    }
    return runs;
}

}  // namespace rubble::accuracy
