#pragma once
// The runtime's fixed-step clock: an accumulator of elapsed wall time that hands out whole steps, at most a cap per
// wake-up. Time beyond the cap is dropped rather than owed, so a machine that cannot keep up runs the simulation
// slower than real time instead of falling further behind with every wake-up (the "spiral of death").
// Time is counted in integer nanoseconds so that whole steps are whole: a float accumulator holding exactly two
// steps' worth can divide to 1.999... and run one.
#include <algorithm>
#include <cmath>
#include <cstdint>

namespace rubble::detail {

class StepClock {
public:
    StepClock(double stepSeconds, int maxStepsPerWake) { configure(stepSeconds, maxStepsPerWake); }

    /// Adds `elapsed` seconds of wall time and returns the number of steps to run now, at most the cap. When more
    /// were due, the oldest are dropped (counted in droppedSteps and droppedSeconds) and behind() turns true.
    int advance(double elapsed) {
        accumulator_ += std::llround(elapsed * 1e9);
        std::int64_t steps = accumulator_ / step_;
        accumulator_ -= steps * step_;
        behind_ = steps > cap_;
        if (behind_) {
            droppedSteps_ += static_cast<std::uint64_t>(steps - cap_);
            steps = cap_;
        }
        return static_cast<int>(steps);
    }

    /// Wall time left until the next step is due, s.
    double untilNextStep() const { return static_cast<double>(step_ - accumulator_) * 1e-9; }
    /// How far the clock is past the newest step it handed out, s (the due time of step k of the last advance's n
    /// steps is now - remainder() - (n - 1 - k) * step).
    double remainder() const { return static_cast<double>(accumulator_) * 1e-9; }
    /// Forgets partial time (after a pause: paused time is not simulated).
    void reset() { accumulator_ = 0; }
    void configure(double stepSeconds, int maxStepsPerWake) {
        step_ = std::max<std::int64_t>(1, std::llround(stepSeconds * 1e9));
        stepSeconds_ = stepSeconds;
        cap_ = maxStepsPerWake;
        accumulator_ = 0;
    }

    /// The simulated step, s (exactly 1 / rate; the wall-clock step is that rounded to a nanosecond).
    double stepSeconds() const { return stepSeconds_; }
    int cap() const { return cap_; }
    bool behind() const { return behind_; }
    std::uint64_t droppedSteps() const { return droppedSteps_; }
    double droppedSeconds() const { return static_cast<double>(droppedSteps_) * static_cast<double>(step_) * 1e-9; }

private:
    std::int64_t step_ = 1;  ///< ns
    double stepSeconds_ = 0;
    int cap_ = 1;
    std::int64_t accumulator_ = 0;  ///< ns, in [0, step)
    bool behind_ = false;
    std::uint64_t droppedSteps_ = 0;
};

}  // namespace rubble::detail
