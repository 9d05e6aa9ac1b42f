#pragma once

namespace rubble {

/// What the running library was built for: the benchmarks and the runner print it next to their numbers.
struct BuildInfo {
    const char* instructionSet;  ///< e.g. "avx512bw", "avx2", "sse4.2"
    int floatLanes;              ///< floats per SIMD register in the stage kernels
    int hardwareThreads;
    /// The -march of the core library that is running: "x86-64-v2" (SSE4.2), "x86-64-v3" (AVX2) or "x86-64-v4"
    /// (AVX-512) in a dispatch build, where the dynamic loader chose it for this CPU; "native" in a build for the
    /// build machine alone.
    const char* coreBuild;
};

BuildInfo buildInfo();

}  // namespace rubble
