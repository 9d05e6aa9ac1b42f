#pragma once
// Per-stage timing of a step. One scoped timer per stage call in World::step.
#include <chrono>

#include "rubble/profile.h"

namespace rubble::detail {

using Clock = std::chrono::steady_clock;

inline double microsecondsSince(Clock::time_point origin, Clock::time_point t) {
    return std::chrono::duration<double, std::micro>(t - origin).count();
}

/// Times one stage into profile[stage] and marks it as run. Substeps call a stage several times per step:
/// the times add up and the begin time is the first call's.
class StageTimer {
public:
    StageTimer(Profile& profile, Stage stage, Clock::time_point origin)
        : timing_(profile[stage]), origin_(origin), begin_(Clock::now()) {}
    ~StageTimer() {
        const auto end = Clock::now();
        if (!timing_.ran) timing_.beginUs = microsecondsSince(origin_, begin_);
        timing_.ran = true;
        timing_.ms += std::chrono::duration<double, std::milli>(end - begin_).count();
    }
    StageTimer(const StageTimer&) = delete;
    StageTimer& operator=(const StageTimer&) = delete;

private:
    StageTiming& timing_;
    Clock::time_point origin_;
    Clock::time_point begin_;
};

/// Adds the wall time of a scope to Profile::jointMs: the joint solver's share of the solver stage, whose calls are
/// interleaved with the contact solver's.
class JointTimer {
public:
    explicit JointTimer(Profile& profile) : profile_(profile), begin_(Clock::now()) {}
    ~JointTimer() { profile_.jointMs += std::chrono::duration<double, std::milli>(Clock::now() - begin_).count(); }
    JointTimer(const JointTimer&) = delete;
    JointTimer& operator=(const JointTimer&) = delete;

private:
    Profile& profile_;
    Clock::time_point begin_;
};

}  // namespace rubble::detail
