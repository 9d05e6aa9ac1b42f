#include "trace_writer.h"

#include <cerrno>
#include <cstring>

#include "rubble/error.h"

TraceWriter::TraceWriter(const std::string& path) : path_(path), file_(std::fopen(path.c_str(), "w"), &std::fclose) {
    if (!file_) throw rubble::Error("cannot write trace " + path + ": " + std::strerror(errno));
    std::fputs("{\"displayTimeUnit\":\"ms\",\"traceEvents\":[\n", file_.get());
    std::fputs("{\"name\":\"process_name\",\"ph\":\"M\",\"pid\":1,\"args\":{\"name\":\"rubble\"}}", file_.get());
}

void TraceWriter::event(const char* name, const char* category, double beginUs, double durationUs, std::uint64_t step) {
    std::fprintf(file_.get(),
                 ",\n{\"name\":\"%s\",\"cat\":\"%s\",\"ph\":\"X\",\"pid\":1,\"tid\":1,\"ts\":%.3f,\"dur\":%.3f,"
                 "\"args\":{\"step\":%llu}}",
                 name, category, beginUs, durationUs, static_cast<unsigned long long>(step));
    ++events_;
}

void TraceWriter::addStep(const rubble::Profile& p) {
    event("step", "step", p.beginUs, p.stepMs * 1000.0, p.stepIndex);
    for (int k = 0; k < rubble::kStageCount; ++k)
        if (p.stages[k].ran)
            event(std::string(rubble::stageName(static_cast<rubble::Stage>(k))).c_str(), "stage", p.stages[k].beginUs,
                  p.stages[k].ms * 1000.0, p.stepIndex);
}

void TraceWriter::finish() {
    std::fputs("\n]}\n", file_.get());
    const bool failed = std::ferror(file_.get()) != 0;
    if (std::fclose(file_.release()) != 0 || failed)
        throw rubble::Error("cannot write trace " + path_ + ": write failed");
}
