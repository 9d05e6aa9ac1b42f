#include "rubble/build_info.h"

#include <thread>

#include "simd/simd.h"

namespace rubble {

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
    return {isa, static_cast<int>(simd::kLanes), static_cast<int>(std::thread::hardware_concurrency())};
}

}  // namespace rubble
