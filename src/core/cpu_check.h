#pragma once
// The instruction sets the core was compiled for, checked against the CPU before any of the core's code runs.
// A dispatch build installs one library per x86-64 level and the dynamic loader picks one the CPU runs; this check
// is for the other ways a library meets a CPU it was not built for (a native build copied to another machine, a
// level forced with LD_LIBRARY_PATH): a message naming what is missing instead of an illegal instruction.
#include <cstdint>
#include <string>

namespace rubble::detail {

/// One bit per instruction-set extension a compiler may use at the x86-64 levels Rubble builds for.
enum CpuFeature : std::uint32_t {
    kCpuSse41 = 1u << 0,
    kCpuSse42 = 1u << 1,
    kCpuPopcnt = 1u << 2,
    kCpuAvx = 1u << 3,
    kCpuAvx2 = 1u << 4,
    kCpuFma = 1u << 5,
    kCpuBmi1 = 1u << 6,
    kCpuBmi2 = 1u << 7,
    kCpuF16c = 1u << 8,
    kCpuLzcnt = 1u << 9,
    kCpuMovbe = 1u << 10,
    kCpuAvx512f = 1u << 11,
    kCpuAvx512bw = 1u << 12,
    kCpuAvx512cd = 1u << 13,
    kCpuAvx512dq = 1u << 14,
    kCpuAvx512vl = 1u << 15,
};

/// The features the core's compiler was allowed to use (from its -march). Data, not code: it is read by the check
/// compiled for the oldest x86-64, before anything compiled for the core's level runs.
extern const std::uint32_t kCoreCpuFeatures;
/// The -march the core was compiled with: "x86-64-v2", "x86-64-v3", "x86-64-v4" or "native".
extern const char kCoreBuildName[];

/// The features this CPU offers as the C library sees them: what the dynamic loader used to pick a level, with
/// those hidden by GLIBC_TUNABLES=glibc.cpu.hwcaps=-NAME taken away.
std::uint32_t cpuFeatures();

/// Names of the features in `required` that are not in `present`, comma-separated; empty when none are missing.
std::string missingCpuFeatures(std::uint32_t required, std::uint32_t present);

/// Throws rubble::Error naming the missing features when the CPU cannot run the core.
void requireCpuFeatures();

}  // namespace rubble::detail
