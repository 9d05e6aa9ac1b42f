#pragma once
// Chrome trace-event JSON (the "X" complete-event form), which Perfetto and chrome://tracing open. The file is
// opened before the run and each step written as it ends, so that an unwritable path fails at once and a long run
// keeps nothing in memory.
#include <cstdio>
#include <memory>
#include <string>

#include "rubble/profile.h"

class TraceWriter {
public:
    /// Opens `path` and writes the header; throws rubble::Error when it cannot.
    explicit TraceWriter(const std::string& path);
    /// Writes the step and each stage that ran in it as nested events on one track.
    void addStep(const rubble::Profile& profile);
    /// Writes the end of the document and closes the file; throws rubble::Error when any write failed.
    void finish();
    std::size_t eventCount() const { return events_; }

private:
    void event(const char* name, const char* category, double beginUs, double durationUs, std::uint64_t step);

    std::string path_;
    std::unique_ptr<FILE, int (*)(FILE*)> file_;
    std::size_t events_ = 0;
};
