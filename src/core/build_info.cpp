#include "rubble/build_info.h"

#include <thread>

#include "core/cpu_check.h"
#include "simd/simd.h"

#ifndef RUBBLE_CORE_ARCH
#error "RUBBLE_CORE_ARCH names the -march the core is compiled with (CMakeLists.txt)"
#endif

namespace rubble {

namespace detail {

extern const char kCoreBuildName[] = RUBBLE_CORE_ARCH;

// What the compiler was told it may use, from the macros its -march defines.
extern const std::uint32_t kCoreCpuFeatures = 0u
#ifdef __SSE4_1__
                                              | kCpuSse41
#endif
#ifdef __SSE4_2__
                                              | kCpuSse42
#endif
#ifdef __POPCNT__
                                              | kCpuPopcnt
#endif
#ifdef __AVX__
                                              | kCpuAvx
#endif
#ifdef __AVX2__
                                              | kCpuAvx2
#endif
#ifdef __FMA__
                                              | kCpuFma
#endif
#ifdef __BMI__
                                              | kCpuBmi1
#endif
#ifdef __BMI2__
                                              | kCpuBmi2
#endif
#ifdef __F16C__
                                              | kCpuF16c
#endif
#ifdef __LZCNT__
                                              | kCpuLzcnt
#endif
#ifdef __MOVBE__
                                              | kCpuMovbe
#endif
#ifdef __AVX512F__
                                              | kCpuAvx512f
#endif
#ifdef __AVX512BW__
                                              | kCpuAvx512bw
#endif
#ifdef __AVX512CD__
                                              | kCpuAvx512cd
#endif
#ifdef __AVX512DQ__
                                              | kCpuAvx512dq
#endif
#ifdef __AVX512VL__
                                              | kCpuAvx512vl
#endif
    ;

}  // namespace detail

BuildInfo buildInfo() {
#if defined(__AVX512F__)
    const char* isa = "avx512";
#elif defined(__AVX2__)
    const char* isa = "avx2";
#elif defined(__AVX__)
    const char* isa = "avx";
#elif defined(__SSE4_2__)
    const char* isa = "sse4.2";
#elif defined(__SSE2__)
    const char* isa = "sse2";
#else
    const char* isa = "scalar";
#endif
    return {isa, static_cast<int>(simd::kLanes), static_cast<int>(std::thread::hardware_concurrency()),
            detail::kCoreBuildName};
}

}  // namespace rubble
