// Benchmarks print what they were built for before any number, so results are kept per machine and SIMD width.
#include <benchmark/benchmark.h>

#include <string>

#include "rubble/build_info.h"

int main(int argc, char** argv) {
    const rubble::BuildInfo info = rubble::buildInfo();
    benchmark::AddCustomContext("rubble_isa", info.instructionSet);
    benchmark::AddCustomContext("rubble_float_lanes", std::to_string(info.floatLanes));
    benchmark::AddCustomContext("rubble_core_build", info.coreBuild);
    benchmark::AddCustomContext("hardware_threads", std::to_string(info.hardwareThreads));
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
