#pragma once
// The soak (`rubble soak`, issue 21): a large world under constant churn, rain onto a terrain mesh where every step
// removes the oldest bodies and drops as many new ones, run for long enough that a leak, a slowdown or a body going
// non-finite shows. Each window of steps reports the median and worst step time, the process's resident memory, the
// body count and the bodies frozen so far.
#include <cstdint>
#include <deque>
#include <functional>
#include <random>
#include <vector>

#include "rubble/world.h"

namespace rubble::soak {

struct SoakSettings {
    std::uint32_t bodies = 100'000;  ///< kept in the world at all times (after the first step)
    std::uint32_t churn = 1'000;     ///< removed and created every step
    long steps = 20'000;
    long window = 1'000;  ///< steps per report
    int threads = 0;      ///< 0: all cores
    std::uint32_t seed = 1;
};

struct SoakWindow {
    long endStep = 0;
    double medianStepMs = 0;
    double worstStepMs = 0;
    double residentMb = 0;     ///< of the whole process, at the window's end
    std::uint32_t bodies = 0;  ///< in the world, the terrain included
    std::uint32_t frozen = 0;  ///< bodies frozen since the start
};

/// The churning world. Bodies fall from 2-20 m onto a 200 m terrain of 80,000 triangles; each step removes the
/// `churn` oldest and creates as many new ones at random places above it.
class Soak {
public:
    explicit Soak(const SoakSettings& settings);
    /// Removes and creates `churn` bodies, then steps.
    void step();
    const World& world() const { return world_; }
    World& world() { return world_; }
    std::uint32_t frozen() const { return frozen_; }

private:
    void createBody();

    SoakSettings settings_;
    World world_;
    ShapeId ball_, box_;
    std::deque<BodyId> bodies_;  ///< oldest first
    std::mt19937 random_;
    std::uint32_t frozen_ = 0;
};

/// Runs the soak, calling `report` after every window; returns the windows.
std::vector<SoakWindow> runSoak(const SoakSettings& settings, const std::function<void(const SoakWindow&)>& report);

/// Resident memory of this process, MB (from /proc/self/statm; 0 where that is not readable).
double residentMegabytes();

}  // namespace rubble::soak
