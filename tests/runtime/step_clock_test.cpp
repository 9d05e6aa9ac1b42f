// The fixed-step clock and its catch-up cap: against an integer model of the accumulator, and through the Runtime's
// counters, deterministically (advance) and on a real thread that cannot keep up.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <random>
#include <thread>

#include "rubble/runtime.h"
#include "runtime/runtime_fixture.h"
#include "runtime/step_clock.h"

using namespace rubble;

TEST(StepClock, MatchesAnIntegerAccumulatorAndNeverExceedsTheCap) {
    // Model in integer microseconds (exact): due = floor(acc / step), run min(due, cap), drop the rest.
    constexpr std::int64_t stepUs = 8000;
    constexpr int cap = 4;
    detail::StepClock clock(stepUs * 1e-6, cap);
    std::mt19937 rng(3);
    std::uniform_int_distribution<std::int64_t> elapsedUs(0, 60000);
    std::int64_t acc = 0, dropped = 0, ran = 0, total = 0;
    for (int wake = 0; wake < 10000; ++wake) {
        const std::int64_t e = elapsedUs(rng);
        total += e;
        acc += e;
        std::int64_t due = acc / stepUs;
        acc -= due * stepUs;
        const bool behind = due > cap;
        if (behind) dropped += due - cap, due = cap;
        ran += due;
        const int steps = clock.advance(static_cast<double>(e) * 1e-6);
        ASSERT_EQ(steps, due) << "wake " << wake;
        ASSERT_LE(steps, cap);
        ASSERT_EQ(clock.behind(), behind);
    }
    EXPECT_EQ(clock.droppedSteps(), static_cast<std::uint64_t>(dropped));
    // Every microsecond of wall time is either simulated, dropped or still in the accumulator.
    EXPECT_EQ(ran * stepUs + dropped * stepUs + acc, total);
    EXPECT_NEAR(clock.remainder(), static_cast<double>(acc) * 1e-6, 1e-6);
}

TEST(RuntimeClock, ACapTurnsAStallIntoSlowdown) {
    RuntimeSettings settings;
    settings.rate = 120;
    settings.maxStepsPerWake = 4;
    Runtime runtime(test::boxesOnFloor(2, 1), settings);
    runtime.advance(1.0);  // a one-second stall: 120 steps were due
    const RuntimeStats s = runtime.stats();
    EXPECT_EQ(s.steps, 4u);
    EXPECT_EQ(s.droppedSteps, 116u);
    EXPECT_NEAR(s.droppedSeconds, 116.0 / 120.0, 1e-6);  // the wall-clock step is 1/120 s to the nanosecond
    EXPECT_TRUE(s.behind);
    EXPECT_EQ(s.maxStepsPerWake, 4u);
    // One window of 1 s that simulated 4 steps of 1/120 s.
    EXPECT_NEAR(s.slowdown, 4.0 / 120.0, 1e-12);
    EXPECT_NEAR(s.physicsHz, 4.0, 1e-9);

    // Keeping up again: wakes of exactly one step each run one step and report real time.
    for (int i = 0; i < 120; ++i) runtime.advance(1.0 / 120.0);
    const RuntimeStats after = runtime.stats();
    EXPECT_FALSE(after.behind);
    EXPECT_EQ(after.droppedSteps, 116u);
    EXPECT_NEAR(after.slowdown, 1.0, 0.02);  // a window ends on whichever wake crosses 0.5 s: +-1 step of 60
    EXPECT_NEAR(static_cast<double>(after.steps), 4 + 120, 1);
}

TEST(RuntimeClock, AThreadThatCannotKeepUpSlowsDownWithinTheCap) {
    // 400 boxes resting on a floor take far more than 5 us per step (publishing their poses alone does, even once
    // they sleep), so 200 kHz cannot be reached.
    RuntimeSettings settings;
    settings.rate = 100000;  // the highest rate (1 / limits::kMinTimeStep)
    settings.maxStepsPerWake = 3;
    Runtime runtime(test::boxesOnFloor(20, 1), settings);
    runtime.start();
    std::this_thread::sleep_for(std::chrono::milliseconds(700));
    runtime.stop();
    const RuntimeStats s = runtime.stats();
    EXPECT_GT(s.steps, 0u);
    EXPECT_LE(s.maxStepsPerWake, 3u);
    EXPECT_GT(s.droppedSteps, 0u);
    // At least one 0.5 s window closed; it simulated far less than it took.
    EXPECT_LT(s.slowdown, 0.9);
    EXPECT_GT(s.slowdown, 0.0);
    EXPECT_GT(s.lastStepMs, 0.005);
}
