#pragma once
// The SIMD vocabulary of Rubble: a wide float / int / mask at the native width of the build machine (xsimd picks
// the widest instruction set -march allows: 16 float lanes with AVX-512, 8 with AVX2, 4 with SSE), and the same
// operations for plain float. A kernel is written once as a template over the lane type F (float or FloatW) and
// instantiated twice: the wide version runs full batches, the float version runs tails and is the scalar
// reference. This file and the others in simd/ are the only places that name xsimd.
//
// Every operation here rounds exactly as its scalar twin (IEEE single precision, one rounding per operation; the
// project compiles with -ffp-contract=off so nothing is fused behind our back), so kernels that use only
// + - * / sqrt min max abs select give bit-identical results in either form. sin, cos and atan2 are the exceptions:
// xsimd's polynomials and libm differ in the last bits.
// GCC 12's AVX-512 intrinsics initialise a placeholder from itself (`__m512 __Y = __Y;`, GCC bug 105593), which
// -Wmaybe-uninitialized reports wherever they are inlined. The pragmas cover the intrinsic headers' lines.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
#include <immintrin.h>
#endif
#include <xsimd/xsimd.hpp>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

/// On a kernel: inline everything it calls, so that GCC keeps whole batches in registers. Under a sanitizer it is
/// left out: instrumented, a flattened kernel takes GCC minutes to compile (integrate.cpp: 437 s under ASan+UBSan,
/// most of CI's budget), for code whose speed a sanitized build does not measure.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define RUBBLE_FLATTEN
#else
#define RUBBLE_FLATTEN [[gnu::flatten]]
#endif

namespace rubble::simd {

// ---------------------------------------------------------------------------------------------------------------
// Types

using FloatW = xsimd::batch<float>;
using IntW = xsimd::batch<std::int32_t>;
using MaskW = xsimd::batch_bool<float>;

/// Number of float lanes of the wide type.
inline constexpr std::size_t kLanes = FloatW::size;
static_assert(IntW::size == kLanes, "int and float batches must have the same lane count");

template <class F>
struct LaneTraits;

template <>
struct LaneTraits<float> {
    using Mask = bool;
    using Int = std::int32_t;
    static constexpr std::size_t lanes = 1;
};

template <>
struct LaneTraits<FloatW> {
    using Mask = MaskW;
    using Int = IntW;
    static constexpr std::size_t lanes = kLanes;
};

/// Mask type of lane type F: bool for float, MaskW for FloatW.
template <class F>
using MaskOf = typename LaneTraits<F>::Mask;
/// Integer type with the lane count of F.
template <class F>
using IntOf = typename LaneTraits<F>::Int;
/// Lane count of F (1 for float).
template <class F>
inline constexpr std::size_t lanesOf = LaneTraits<F>::lanes;

/// Rounds n down to a multiple of the lane count of F.
template <class F>
constexpr std::size_t roundDownToLanes(std::size_t n) {
    return n - n % lanesOf<F>;
}
/// Rounds n up to a multiple of the lane count of F (for padding batches).
template <class F>
constexpr std::size_t roundUpToLanes(std::size_t n) {
    return (n + lanesOf<F> - 1) / lanesOf<F> * lanesOf<F>;
}

// ---------------------------------------------------------------------------------------------------------------
// Memory: loads and stores from SoA arrays (unaligned; the arrays are cache-line aligned but chunk offsets need
// not be multiples of the lane count when callers choose otherwise).

template <class F>
F load(const float* p);
template <>
inline float load<float>(const float* p) {
    return *p;
}
template <>
inline FloatW load<FloatW>(const float* p) {
    return FloatW::load_unaligned(p);
}

inline void store(float* p, float v) { *p = v; }
inline void store(float* p, const FloatW& v) { v.store_unaligned(p); }

template <class I>
I loadInt(const std::int32_t* p);
template <>
inline std::int32_t loadInt<std::int32_t>(const std::int32_t* p) {
    return *p;
}
template <>
inline IntW loadInt<IntW>(const std::int32_t* p) {
    return IntW::load_unaligned(p);
}
/// Loads unsigned indices (below 2^31) as signed lanes.
template <class I>
I loadIndex(const std::uint32_t* p) {
    return loadInt<I>(reinterpret_cast<const std::int32_t*>(p));
}

inline void store(std::int32_t* p, std::int32_t v) { *p = v; }
inline void store(std::int32_t* p, const IntW& v) { v.store_unaligned(p); }

/// Lanes src[index[k]] (index below 2^31).
inline float gather(const float* src, std::int32_t index) { return src[index]; }
inline FloatW gather(const float* src, const IntW& index) {
    // xsimd 8.1's batch::gather calls its kernels with explicit template arguments that the AVX-512 and AVX2
    // overloads cannot take, so it falls back to 16 scalar loads and lane inserts; the gather instruction is used
    // here directly (same lanes, fewer instructions).
#if XSIMD_WITH_AVX512F
    return _mm512_i32gather_ps(index, src, sizeof(float));
#elif XSIMD_WITH_AVX2
    return _mm256_i32gather_ps(src, index, sizeof(float));
#else
    return FloatW::gather(src, index);
#endif
}
/// dst[index[k]] = v[k]; with repeated indices the highest lane wins.
inline void scatter(float* dst, std::int32_t index, float v) { dst[index] = v; }
inline void scatter(float* dst, const IntW& index, const FloatW& v) { v.scatter(dst, index); }

// ---------------------------------------------------------------------------------------------------------------
// Construction and lanes

template <class F>
F broadcast(float s) {
    return F(s);
}

/// Lane k of a value (k = 0 for float).
inline float lane(float v, std::size_t) { return v; }
inline float lane(const FloatW& v, std::size_t k) { return v.get(k); }
inline bool lane(bool m, std::size_t) { return m; }
inline bool lane(const MaskW& m, std::size_t k) { return m.get(k); }

/// Lanes 0, 1, 2, ... as floats (0 for float).
template <class F>
F laneIndices();
template <>
inline float laneIndices<float>() {
    return 0.0f;
}
template <>
inline FloatW laneIndices<FloatW>() {
    alignas(64) float v[kLanes];
    for (std::size_t k = 0; k < kLanes; ++k) v[k] = static_cast<float>(k);
    return FloatW::load_aligned(v);
}

/// Writes the mask as one bool per lane (out must hold lanesOf<F> entries).
inline void storeMask(bool* out, bool m) { *out = m; }
inline void storeMask(bool* out, const MaskW& m) { m.store_unaligned(out); }

/// Horizontal sum (lane order of xsimd's reduction; not bit-identical to a sequential scalar sum).
inline float reduceAdd(float v) { return v; }
inline float reduceAdd(const FloatW& v) { return xsimd::hadd(v); }

// ---------------------------------------------------------------------------------------------------------------
// Arithmetic that rounds like the wide instructions do

inline float select(bool m, float a, float b) { return m ? a : b; }
inline FloatW select(const MaskW& m, const FloatW& a, const FloatW& b) { return xsimd::select(m, a, b); }
inline std::int32_t select(bool m, std::int32_t a, std::int32_t b) { return m ? a : b; }
/// Int lanes chosen by a float mask. (Goes through the float blend: xsimd 8.1's integer select does not compile
/// for AVX-512BW.)
inline IntW select(const MaskW& m, const IntW& a, const IntW& b) {
    return xsimd::bitwise_cast<IntW>(xsimd::select(m, xsimd::bitwise_cast<FloatW>(a), xsimd::bitwise_cast<FloatW>(b)));
}

/// a < b ? a : b, like minps (the second operand wins for NaN and for equal zeros).
inline float min(float a, float b) { return a < b ? a : b; }
inline FloatW min(const FloatW& a, const FloatW& b) { return xsimd::min(a, b); }
/// a > b ? a : b, like maxps.
inline float max(float a, float b) { return a > b ? a : b; }
inline FloatW max(const FloatW& a, const FloatW& b) { return xsimd::max(a, b); }

template <class F>
F clamp(const F& v, const F& lo, const F& hi) {
    return min(max(v, lo), hi);
}

inline float abs(float v) { return std::fabs(v); }
inline FloatW abs(const FloatW& v) { return xsimd::abs(v); }

/// Correctly rounded square root (sqrtss / vsqrtps), identical in both forms.
inline float sqrt(float v) { return std::sqrt(v); }
inline FloatW sqrt(const FloatW& v) { return xsimd::sqrt(v); }

/// Transcendentals: libm for float, xsimd's polynomials for FloatW; they may differ by an ulp or two.
inline float sin(float v) { return std::sin(v); }
inline FloatW sin(const FloatW& v) { return xsimd::sin(v); }
inline float cos(float v) { return std::cos(v); }
inline FloatW cos(const FloatW& v) { return xsimd::cos(v); }
/// Angle of (x, y) = atan(y / x) in the right quadrant; argument order as std::atan2.
inline float atan2(float y, float x) { return std::atan2(y, x); }
inline FloatW atan2(const FloatW& y, const FloatW& x) { return xsimd::atan2(y, x); }

/// -v where m, v elsewhere.
template <class F>
F negateWhere(const MaskOf<F>& m, const F& v) {
    return select(m, -v, v);
}

// ---------------------------------------------------------------------------------------------------------------
// Masks

inline bool isFinite(float v) { return std::isfinite(v); }
inline MaskW isFinite(const FloatW& v) { return xsimd::isfinite(v); }

inline bool any(bool m) { return m; }
inline bool any(const MaskW& m) { return xsimd::any(m); }
inline bool all(bool m) { return m; }
inline bool all(const MaskW& m) { return xsimd::all(m); }
inline bool none(bool m) { return !m; }
inline bool none(const MaskW& m) { return xsimd::none(m); }

/// Lane-wise and / or / not that read the same for bool and MaskW (bool & bool would promote to int).
inline bool andMask(bool a, bool b) { return a && b; }
inline MaskW andMask(const MaskW& a, const MaskW& b) { return a & b; }
inline bool orMask(bool a, bool b) { return a || b; }
inline MaskW orMask(const MaskW& a, const MaskW& b) { return a | b; }
inline bool notMask(bool a) { return !a; }
inline MaskW notMask(const MaskW& a) { return !a; }

/// Bit k set where lane k of the mask is: one instruction (a mask-register move or a movemask) on x86.
inline std::uint32_t laneBits(bool m) { return m ? 1u : 0u; }
inline std::uint32_t laneBits(const MaskW& m) {
#if defined(__AVX512F__)
    return static_cast<std::uint32_t>(m.data);
#elif defined(__AVX__)
    return static_cast<std::uint32_t>(_mm256_movemask_ps(m.data));
#elif defined(__SSE2__)
    return static_cast<std::uint32_t>(_mm_movemask_ps(m.data));
#else
    bool bits[kLanes];
    m.store_unaligned(bits);
    std::uint32_t out = 0;
    for (std::size_t k = 0; k < kLanes; ++k) out |= std::uint32_t{bits[k]} << k;
    return out;
#endif
}

/// Calls fn(k) for every lane k whose mask bit is set, in ascending order.
template <class Fn>
void forEachSetLane(bool m, Fn&& fn) {
    if (m) fn(std::size_t{0});
}
template <class Fn>
void forEachSetLane(const MaskW& m, Fn&& fn) {
    if (xsimd::none(m)) return;
    bool bits[kLanes];
    m.store_unaligned(bits);
    for (std::size_t k = 0; k < kLanes; ++k)
        if (bits[k]) fn(k);
}

// ---------------------------------------------------------------------------------------------------------------
// Int <-> float

inline float toFloat(std::int32_t v) { return static_cast<float>(v); }
inline FloatW toFloat(const IntW& v) { return xsimd::to_float(v); }
/// Truncates toward zero.
inline std::int32_t toInt(float v) { return static_cast<std::int32_t>(v); }
inline IntW toInt(const FloatW& v) { return xsimd::to_int(v); }

}  // namespace rubble::simd
