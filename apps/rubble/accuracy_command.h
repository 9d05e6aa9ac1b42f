#pragma once
// `rubble accuracy`: measures every knob's error against its time and writes the report (apps/accuracy/).

namespace rubble::apps {

extern const char* const kAccuracyUsage;

/// argv[1] is "accuracy". Returns the process's exit code.
int runAccuracyCommand(int argc, char** argv);

}  // namespace rubble::apps
