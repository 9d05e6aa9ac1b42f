#pragma once
// The third promise measured: one scene that calls for every effect, run with all of them and with each one left
// out in turn, so that what each effect costs (and what leaving it out saves) shows in milliseconds.
#include <array>
#include <string>
#include <vector>

#include "measurement.h"
#include "rubble/profile.h"

namespace rubble::accuracy {

struct EffectRun {
    EffectSet declared;
    EffectSet simulated;  ///< what the world ran (it drops effects its content cannot show)
    double msPerStep = 0;
    double msPerStepAtEnd = 0;                  ///< median over the last 2 s, when what can sleep has had time to
    std::array<double, kStageCount> stageMs{};  ///< median over the steps the stage ran in (0 when it never ran)
    std::array<bool, kStageCount> stageRan{};
    std::uint32_t sleepingAtEnd = 0;
};

struct EffectCosts {
    std::string description;  ///< the scene
    long steps = 0;
    EffectRun all;
    std::vector<std::pair<Effect, EffectRun>> without;  ///< one per effect, in Effect order
};

EffectCosts measureEffectCosts(int threads, Length length);

}  // namespace rubble::accuracy
