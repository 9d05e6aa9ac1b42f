#pragma once
// The CPU's handling of subnormal floats while the engine works. A stack held exactly still (every contact started
// from the loads that hold it, solver/resting_loads.h) leaves velocities and impulse corrections decaying towards
// zero through the subnormal range, where each SIMD operation on x86 may take a microcode assist: S2's solver ran
// 20% slower that way. Flushing subnormal results to zero (FTZ) and reading subnormal inputs as zero (DAZ) costs
// nothing in accuracy a physics step can show (they are below 1.2e-38), and every thread of a step sets the same
// mode, so results still do not depend on the thread count.
#if defined(__SSE__) || defined(__x86_64__)
#include <xmmintrin.h>
#endif

namespace rubble::simd {

/// Sets FTZ and DAZ on this thread for its lifetime, and puts the previous mode back after.
class FlushSubnormals {
public:
#if defined(__SSE__) || defined(__x86_64__)
    FlushSubnormals() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | kFlushToZero | kDenormalsAreZero); }
    ~FlushSubnormals() { _mm_setcsr(saved_); }

private:
    static constexpr unsigned kFlushToZero = 0x8000, kDenormalsAreZero = 0x0040;
    unsigned saved_;
#else
    FlushSubnormals() = default;
#endif
public:
    FlushSubnormals(const FlushSubnormals&) = delete;
    FlushSubnormals& operator=(const FlushSubnormals&) = delete;
};

}  // namespace rubble::simd
