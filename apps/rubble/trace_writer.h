#pragma once
// Chrome trace-event JSON (the "X" complete-event form), which Perfetto and chrome://tracing open.
#include <string>
#include <vector>

#include "rubble/profile.h"

class TraceWriter {
public:
    /// Records the step and each stage that ran in it as nested events on one track.
    void addStep(const rubble::Profile& profile);
    /// Throws rubble::Error when the file cannot be written.
    void write(const std::string& path) const;
    std::size_t eventCount() const { return events_.size(); }

private:
    struct Event {
        int stage;  ///< -1 for the whole step
        double beginUs;
        double durationUs;
        unsigned long long step;
    };
    std::vector<Event> events_;
};
