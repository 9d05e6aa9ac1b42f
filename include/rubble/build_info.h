#pragma once

namespace rubble {

/// What the library was built for: the benchmarks and the runner print it next to their numbers.
struct BuildInfo {
    const char* instructionSet;  ///< e.g. "avx512bw", "avx2", "sse4.2"
    int floatLanes;              ///< floats per SIMD register in the stage kernels
    int hardwareThreads;
};

BuildInfo buildInfo();

}  // namespace rubble
