#pragma once
// `rubble soak`: a large world under constant churn, reported every window of steps (apps/soak/).

namespace rubble::apps {

extern const char* const kSoakUsage;

/// argv[1] is "soak". Returns the process's exit code.
int runSoakCommand(int argc, char** argv);

}  // namespace rubble::apps
