// Compiled for the oldest x86-64 (CMakeLists.txt), whatever level the rest of the core is built for.
#include "core/cpu_check.h"

#if defined(__clang__)
// glibc 2.36's header spells its return type _Bool, a C keyword clang does not accept in C++ (GCC does).
#define _Bool bool
#include <sys/platform/x86.h>
#undef _Bool
#else
#include <sys/platform/x86.h>
#endif
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <iterator>

#include "rubble/error.h"

namespace rubble::detail {

namespace {

struct NamedFeature {
    std::uint32_t bit;
    const char* name;
    unsigned glibcIndex;  ///< for x86_cpu_active: the C library's view, GLIBC_TUNABLES included
};

#define RUBBLE_CPU_FEATURE(bit, name) \
    { bit, #name, x86_cpu_##name }
constexpr NamedFeature kFeatures[] = {
    RUBBLE_CPU_FEATURE(kCpuSse41, SSE4_1),      RUBBLE_CPU_FEATURE(kCpuSse42, SSE4_2),
    RUBBLE_CPU_FEATURE(kCpuPopcnt, POPCNT),     RUBBLE_CPU_FEATURE(kCpuAvx, AVX),
    RUBBLE_CPU_FEATURE(kCpuAvx2, AVX2),         RUBBLE_CPU_FEATURE(kCpuFma, FMA),
    RUBBLE_CPU_FEATURE(kCpuBmi1, BMI1),         RUBBLE_CPU_FEATURE(kCpuBmi2, BMI2),
    RUBBLE_CPU_FEATURE(kCpuF16c, F16C),         RUBBLE_CPU_FEATURE(kCpuLzcnt, LZCNT),
    RUBBLE_CPU_FEATURE(kCpuMovbe, MOVBE),       RUBBLE_CPU_FEATURE(kCpuAvx512f, AVX512F),
    RUBBLE_CPU_FEATURE(kCpuAvx512bw, AVX512BW), RUBBLE_CPU_FEATURE(kCpuAvx512cd, AVX512CD),
    RUBBLE_CPU_FEATURE(kCpuAvx512dq, AVX512DQ), RUBBLE_CPU_FEATURE(kCpuAvx512vl, AVX512VL),
};
#undef RUBBLE_CPU_FEATURE

std::string refusal(const std::string& missing) {
    return "this build of Rubble's core library was compiled for " + std::string(kCoreBuildName) + " and needs " +
           missing +
           ", which this CPU does not offer (or GLIBC_TUNABLES hides); use a dispatch build (RUBBLE_SIMD=dispatch, "
           "the default), whose loader picks a level this CPU runs";
}

// Runs when the library is loaded, before its default-priority static constructors: in a shared library nothing
// compiled for the core's level has run yet.
[[gnu::constructor(101)]] void refuseUnsupportedCpu() {
    const std::string missing = missingCpuFeatures(kCoreCpuFeatures, cpuFeatures());
    if (missing.empty()) return;
    std::fprintf(stderr, "rubble: %s\n", refusal(missing).c_str());
    std::fflush(stderr);
    _exit(1);
}

}  // namespace

std::uint32_t cpuFeatures() {
    std::uint32_t present = 0;
    for (const NamedFeature& f : kFeatures) present |= x86_cpu_active(f.glibcIndex) ? f.bit : 0u;
    return present;
}

std::string missingCpuFeatures(std::uint32_t required, std::uint32_t present) {
    std::string names;
    for (const NamedFeature& f : kFeatures) {
        if ((required & f.bit) == 0 || (present & f.bit) != 0) continue;
        if (!names.empty()) names += ", ";
        names += f.name;
    }
    return names;
}

void requireCpuFeatures() {
    const std::string missing = missingCpuFeatures(kCoreCpuFeatures, cpuFeatures());
    if (!missing.empty()) throw Error(refusal(missing));
}

}  // namespace rubble::detail
