// The accuracy report's measurements are right, not only runnable: each is checked against what numerical analysis
// says the error must be, and the report's selection (Pareto front, recommendations, sweeps) against brute force.
//
// Free fall under semi-implicit Euler moves with the end-of-substep velocity, so after t = n h it is exactly
// g t h / 2 too low (explicit Euler: too high by as much); Verlet and RK4 are exact for constant acceleration.
// What else the measurement sees is float rounding of positions near y = 100 m (half an ulp, 3.8e-6 m, per substep):
// at most 480 x 3.8e-6 = 1.8e-3 m over 2 s at h = 1/240 s, so the bound is 2e-3 m.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "measurement.h"
#include "report.h"
#include "sweeps.h"

namespace rubble::accuracy {
namespace {

const MeasurementScene& scene(const std::string& id) {
    static const std::vector<MeasurementScene> scenes = measurementScenes(RUBBLE_SOURCE_DIR "/scenes");
    const auto it = std::find_if(scenes.begin(), scenes.end(), [&](const MeasurementScene& s) { return s.id == id; });
    if (it == scenes.end()) throw std::runtime_error("no measurement scene " + id);
    return *it;
}

WorldSettings settings(Integrator integrator, int hertz, int substeps = WorldSettings{}.substeps) {
    WorldSettings s;
    s.threads = 1;
    s.integrator = integrator;
    s.timeStep = 1.0f / static_cast<float>(hertz);
    s.substeps = substeps;
    return s;
}

Measured measure(const std::string& id, const WorldSettings& s) { return scene(id).measure(s, Length::Quick); }

TEST(AccuracyMeasurement, FreeFallErrorIsHalfOfGTimesTimeTimesSubstep) {
    constexpr double kRounding = 2e-3;  // m, see the top of the file
    for (const int hertz : {60, 120})
        for (const int substeps : {1, 4}) {
            const double h = 1.0 / (hertz * substeps);
            const double expected = 0.5 * 9.81 * 2.0 * h;
            EXPECT_NEAR(measure("free_fall", settings(Integrator::SemiImplicitEuler, hertz, substeps)).error, expected,
                        kRounding)
                << hertz << " Hz x " << substeps;
            EXPECT_NEAR(measure("free_fall", settings(Integrator::ExplicitEuler, hertz, substeps)).error, expected,
                        kRounding)
                << hertz << " Hz x " << substeps;
            EXPECT_LT(measure("free_fall", settings(Integrator::Verlet, hertz, substeps)).error, kRounding);
            EXPECT_LT(measure("free_fall", settings(Integrator::RungeKutta4, hertz, substeps)).error, kRounding);
        }
}

TEST(AccuracyMeasurement, HalvingTheStepHalvesTheFirstOrderIntegratorsError) {
    // Free fall (constant force) and the tumbling box (the gyroscopic torque changes with the motion): both first
    // order for the Euler family. Ratios within 10% of 1/2: the tumbling box's higher-order terms at h = 1/240 s
    // are a few percent of its error.
    for (const Integrator integrator : {Integrator::SemiImplicitEuler, Integrator::ExplicitEuler})
        for (const char* id : {"free_fall", "tumbling_box"}) {
            const double coarse = measure(id, settings(integrator, 60)).error;
            const double fine = measure(id, settings(integrator, 120)).error;
            EXPECT_NEAR(fine / coarse, 0.5, 0.05)
                << id << " " << integratorName(integrator) << ": " << coarse << " -> " << fine;
        }
}

TEST(AccuracyMeasurement, RungeKuttaErrorFallsSixteenfoldWhenTheStepHalves) {
    // RK4 is fourth order in the free motion it integrates: the tumbling box's energy drift falls at least 2^4 = 16
    // times when the step halves. Measured 27.5 (12 -> 24 Hz) and 29.7 (16 -> 32 Hz), order 4.8: the leading h^4 term
    // of the energy error is small for this motion. Large steps (1/12 s, one substep: 0.42 rad a step) keep the error
    // far above float rounding, which takes over near 1e-4 % (from 40 Hz on); first order would give 2.
    const double coarse = measure("tumbling_box", settings(Integrator::RungeKutta4, 12, 1)).error;
    const double fine = measure("tumbling_box", settings(Integrator::RungeKutta4, 24, 1)).error;
    EXPECT_GT(coarse / fine, 14.0) << coarse << " -> " << fine;
    EXPECT_LT(coarse / fine, 40.0) << coarse << " -> " << fine;
    EXPECT_GT(fine, 1e-3) << "% of the energy: far above rounding";
}

TEST(AccuracyMeasurement, SpringIsFirstOrderWhateverTheIntegrator) {
    // Springs are soft constraints of the solver, integrated implicitly over the substep (joint_solver.h), not forces
    // the integrator sees: their energy loss halves with the step for every integrator, RK4 included. This pins that
    // the report's spring measures the spring, and that the integrator knob cannot buy spring accuracy.
    for (const Integrator integrator : {Integrator::SemiImplicitEuler, Integrator::RungeKutta4}) {
        const double coarse = measure("spring", settings(integrator, 120)).error;
        const double fine = measure("spring", settings(integrator, 240)).error;
        EXPECT_NEAR(fine / coarse, 0.5, 0.1) << integratorName(integrator) << ": " << coarse << " -> " << fine;
    }
}

TEST(AccuracyMeasurement, PendulumConvergesToTheEllipticIntegralPeriod) {
    // The reference period (large amplitude, compound pendulum) is independent of the engine: if it were wrong the
    // error would stop falling at the size of the mistake. From 1/60 s x 4 to 1/480 s x 8 it falls 16-fold, to under
    // 0.02% (the remaining error is the ball joint's softness).
    const double coarse = measure("pendulum", settings(Integrator::SemiImplicitEuler, 60, 4)).secondaryError;
    const double fine = measure("pendulum", settings(Integrator::SemiImplicitEuler, 480, 8)).secondaryError;
    EXPECT_LT(fine, 0.02) << "period error, %";
    EXPECT_LT(fine, coarse / 8) << coarse << " -> " << fine;
}

TEST(AccuracyMeasurement, SameRunTwiceAndOnTwoThreadsGivesTheSameError) {
    for (const char* id : {"pendulum", "tower", "gas"}) {
        WorldSettings one = settings(Integrator::SemiImplicitEuler, 60);
        WorldSettings two = one;
        two.threads = 2;
        const Measured a = measure(id, one), b = measure(id, one), c = measure(id, two);
        EXPECT_EQ(a.error, b.error) << id;
        EXPECT_EQ(a.stateHash, b.stateHash) << id;
        EXPECT_EQ(a.error, c.error) << id;
        EXPECT_EQ(a.stateHash, c.stateHash) << id;
    }
}

TEST(AccuracyReport, ParetoFrontMatchesBruteForce) {
    std::mt19937 random(3);
    std::uniform_int_distribution<int> coarse(0, 9);  // few distinct values, so that ties are common
    for (int round = 0; round < 200; ++round) {
        std::vector<std::pair<double, double>> points(static_cast<std::size_t>(1 + round % 25));
        for (auto& p : points)
            p = {coarse(random) * 0.5 + 0.1, coarse(random) == 0 ? std::nan("") : coarse(random) * 1e-3};
        std::set<std::pair<double, double>> expected;  // undominated finite points
        for (const auto& p : points) {
            if (!std::isfinite(p.second)) continue;
            bool dominated = false;
            for (const auto& q : points)
                dominated |= std::isfinite(q.second) && q.first <= p.first && q.second <= p.second && q != p;
            if (!dominated) expected.insert(p);
        }
        const std::vector<std::size_t> front = paretoFront(points);
        std::set<std::pair<double, double>> got;
        for (std::size_t k = 0; k < front.size(); ++k) {
            got.insert(points[front[k]]);
            if (k > 0) {
                EXPECT_LT(points[front[k - 1]].first, points[front[k]].first) << "by increasing time, no repeats";
            }
        }
        EXPECT_EQ(got, expected) << "round " << round;
    }
}

TEST(AccuracyReport, RecommendationsMatchBruteForce) {
    SceneResults results;
    results.scene.target = 0.01;
    std::mt19937 random(5);
    std::uniform_real_distribution<double> ms(0.1, 2.0), error(0.001, 0.1);
    for (int i = 0; i < 40; ++i) {
        RunResult r;
        r.run.settings.velocityIterations = i + 1;  // distinct settings
        r.measured.timeStep = 1.0f / 60.0f;
        r.measured.msPerStep = ms(random);
        r.measured.error = error(random);
        if (i == 7) r.failure = "refused";
        results.runs.push_back(r);
    }
    const Recommendation advice = recommend(results, {1.0, 4.0});
    std::optional<std::size_t> cheapest;
    for (std::size_t i = 0; i < results.runs.size(); ++i) {
        const RunResult& r = results.runs[i];
        if (r.usable() && r.measured.error <= 0.01 &&
            (!cheapest || r.measured.msPerStep < results.runs[*cheapest].measured.msPerStep))
            cheapest = i;
    }
    EXPECT_EQ(advice.cheapestMeetingTarget, cheapest);
    for (const auto& [factor, best] : advice.bestWithinBudget) {
        ASSERT_TRUE(best.has_value());
        const double budget = factor * results.runs[0].measured.msPerFrame();
        EXPECT_LE(results.runs[*best].measured.msPerFrame(), budget);
        for (const RunResult& r : results.runs)
            if (r.usable() && r.measured.msPerFrame() <= budget) {
                EXPECT_LE(results.runs[*best].measured.error, r.measured.error);
            }
    }
}

TEST(AccuracyReport, PlanSweepsEachKnobFromTheDefaultsAndThePairsTogether) {
    WorldSettings defaults;
    defaults.threads = 1;
    const MeasurementScene& tower = scene("tower");
    const std::vector<PlannedRun> full = planRuns(tower, defaults, Length::Full);
    ASSERT_FALSE(full.empty());
    EXPECT_EQ(full[0].sweep, "defaults");
    EXPECT_EQ(settingsKey(full[0].settings), settingsKey(defaults));
    for (const PlannedRun& run : full) {
        if (run.sweep.find(" x ") != std::string::npos || run.sweep == "defaults") continue;
        // A single-knob run differs from the defaults in that knob only: its settings, with the knob set back, are
        // the defaults (checked by the number of fields that differ in the key).
        const std::string a = settingsKey(run.settings), b = settingsKey(defaults);
        int differing = 0;
        std::size_t i = 0, j = 0;
        while (i <= a.size() && j <= b.size()) {
            const std::size_t ei = std::min(a.find('|', i), a.size()), ej = std::min(b.find('|', j), b.size());
            differing += a.substr(i, ei - i) != b.substr(j, ej - j) ? 1 : 0;
            i = ei + 1, j = ej + 1;
        }
        EXPECT_LE(differing, 1) << run.sweep << " " << run.value;
    }
    const auto count = [&](const std::vector<PlannedRun>& runs, const std::string& sweep) {
        return std::count_if(runs.begin(), runs.end(), [&](const PlannedRun& r) { return r.sweep == sweep; });
    };
    EXPECT_EQ(count(full, "time step"), 5);
    EXPECT_EQ(count(full, "velocity iterations"), 6);
    EXPECT_EQ(count(full, "time step x substeps"), 20);
    EXPECT_EQ(count(full, "velocity iterations x position correction"), 18);
    const std::vector<PlannedRun> quick = planRuns(tower, defaults, Length::Quick);
    EXPECT_EQ(count(quick, "time step"), 3) << "1/30, the default 1/60 and 1/480 s";
    EXPECT_EQ(count(quick, "time step x substeps"), 4);
    for (const PlannedRun& run : full)
        if (run.sweep == "threads") {
            EXPECT_TRUE(run.timeOnly);
        }
}

}  // namespace
}  // namespace rubble::accuracy
