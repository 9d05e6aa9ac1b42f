#include "trace_writer.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "rubble/error.h"

void TraceWriter::addStep(const rubble::Profile& p) {
    events_.push_back({-1, p.beginUs, p.stepMs * 1000.0, static_cast<unsigned long long>(p.stepIndex)});
    for (int k = 0; k < rubble::kStageCount; ++k)
        if (p.stages[k].ran)
            events_.push_back(
                {k, p.stages[k].beginUs, p.stages[k].ms * 1000.0, static_cast<unsigned long long>(p.stepIndex)});
}

void TraceWriter::write(const std::string& path) const {
    std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "w"), &std::fclose);
    if (!file) throw rubble::Error("cannot write trace " + path + ": " + std::strerror(errno));
    FILE* f = file.get();
    std::fputs("{\"displayTimeUnit\":\"ms\",\"traceEvents\":[\n", f);
    std::fputs("{\"name\":\"process_name\",\"ph\":\"M\",\"pid\":1,\"args\":{\"name\":\"rubble\"}}", f);
    for (const Event& e : events_) {
        const std::string name =
            e.stage < 0 ? "step" : std::string(rubble::stageName(static_cast<rubble::Stage>(e.stage)));
        std::fprintf(f,
                     ",\n{\"name\":\"%s\",\"cat\":\"%s\",\"ph\":\"X\",\"pid\":1,\"tid\":1,\"ts\":%.3f,\"dur\":%.3f,"
                     "\"args\":{\"step\":%llu}}",
                     name.c_str(), e.stage < 0 ? "step" : "stage", e.beginUs, e.durationUs, e.step);
    }
    std::fputs("\n]}\n", f);
    if (std::ferror(f)) throw rubble::Error("cannot write trace " + path + ": write failed");
}
