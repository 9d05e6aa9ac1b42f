#pragma once
// Rows of eight floats (AoS) moved into and out of SIMD lanes by transposes: lane k of column c is float c of row
// index[k]. This stands in for gathering eight SoA arrays: each row is one or two contiguous loads, and the shuffles
// that transpose them cost far less than eight gather instructions (a hardware gather issues one load per lane).
// The rows start at `rows`, eight floats apart (row i at rows + 8 i); 32-byte aligned rows never straddle a cache
// line. Pure data movement: every float arrives bit for bit as it was.
#include <cstddef>
#include <cstdint>

#include "simd/simd.h"

namespace rubble::simd {

/// Floats per row.
inline constexpr std::size_t kRowFloats = 8;

namespace transpose_detail {

inline const float* rowAt(const float* rows, std::int32_t index) {
    return rows + static_cast<std::size_t>(static_cast<std::uint32_t>(index)) * kRowFloats;
}
inline float* rowAt(float* rows, std::int32_t index) {
    return rows + static_cast<std::size_t>(static_cast<std::uint32_t>(index)) * kRowFloats;
}

#if XSIMD_WITH_AVX512F
/// Transposes the 4x4 blocks in every 128-bit lane of four registers: lane L of r[b] element a goes to lane L of
/// r[a] element b. Its own inverse.
inline void transpose4x4InLanes(__m512& r0, __m512& r1, __m512& r2, __m512& r3) {
    const __m512 t0 = _mm512_unpacklo_ps(r0, r1), t1 = _mm512_unpackhi_ps(r0, r1);
    const __m512 t2 = _mm512_unpacklo_ps(r2, r3), t3 = _mm512_unpackhi_ps(r2, r3);
    r0 = _mm512_shuffle_ps(t0, t2, 0x44);
    r1 = _mm512_shuffle_ps(t0, t2, 0xEE);
    r2 = _mm512_shuffle_ps(t1, t3, 0x44);
    r3 = _mm512_shuffle_ps(t1, t3, 0xEE);
}
/// Row `lo` in the low 256 bits, row `hi` in the high 256 bits (AVX-512F only: no insertf32x8).
inline __m512 loadRowPair(const float* lo, const float* hi) {
    const __m512d low = _mm512_castpd256_pd512(_mm256_loadu_pd(reinterpret_cast<const double*>(lo)));
    return _mm512_castpd_ps(_mm512_insertf64x4(low, _mm256_loadu_pd(reinterpret_cast<const double*>(hi)), 1));
}
inline void storeLow(float* row, __m512 v) { _mm256_storeu_ps(row, _mm512_castps512_ps256(v)); }
inline void storeHigh(float* row, __m512 v) {
    _mm256_storeu_pd(reinterpret_cast<double*>(row), _mm512_extractf64x4_pd(_mm512_castps_pd(v), 1));
}
#elif XSIMD_WITH_AVX
/// Transposes the 4x4 blocks in both 128-bit lanes of four registers (its own inverse).
inline void transpose4x4InLanes(__m256& r0, __m256& r1, __m256& r2, __m256& r3) {
    const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
    const __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
    r0 = _mm256_shuffle_ps(t0, t2, 0x44);
    r1 = _mm256_shuffle_ps(t0, t2, 0xEE);
    r2 = _mm256_shuffle_ps(t1, t3, 0x44);
    r3 = _mm256_shuffle_ps(t1, t3, 0xEE);
}
#endif

}  // namespace transpose_detail

/// columns[c] = float c of row `index` (the one-lane form).
inline void loadRowsTransposed(const float* rows, const std::int32_t* index, float* columns) {
    const float* row = transpose_detail::rowAt(rows, *index);
    for (std::size_t c = 0; c < kRowFloats; ++c) columns[c] = row[c];
}

/// Lane k of columns[c] = float c of row index[k], for the kLanes indices at `index` (repeats allowed).
inline void loadRowsTransposed(const float* rows, const std::int32_t* index, FloatW* columns) {
    using transpose_detail::rowAt;
#if XSIMD_WITH_AVX512F
    static_assert(kLanes == 16);
    // Register j < 4 holds rows index[j] | index[j + 4], register 4 + j rows index[8 + j] | index[12 + j]. After
    // the in-lane 4x4 transposes, r[a] (a < 4) holds columns a, a + 4 of lanes 0-3 and a, a + 4 of lanes 4-7, and
    // r[4 + a] the same for lanes 8-15, so one 128-bit-lane shuffle per column puts the lanes in order.
    __m512 r[8];
    for (int j = 0; j < 4; ++j) {
        r[j] = transpose_detail::loadRowPair(rowAt(rows, index[j]), rowAt(rows, index[j + 4]));
        r[4 + j] = transpose_detail::loadRowPair(rowAt(rows, index[8 + j]), rowAt(rows, index[12 + j]));
    }
    transpose_detail::transpose4x4InLanes(r[0], r[1], r[2], r[3]);
    transpose_detail::transpose4x4InLanes(r[4], r[5], r[6], r[7]);
    for (int a = 0; a < 4; ++a) {
        columns[a] = _mm512_shuffle_f32x4(r[a], r[4 + a], 0x88);      // 128-bit lanes 0, 2 of each
        columns[a + 4] = _mm512_shuffle_f32x4(r[a], r[4 + a], 0xDD);  // 128-bit lanes 1, 3 of each
    }
#elif XSIMD_WITH_AVX
    static_assert(kLanes == 8);
    __m256 r[8];
    for (int k = 0; k < 8; ++k) r[k] = _mm256_loadu_ps(rowAt(rows, index[k]));
    transpose_detail::transpose4x4InLanes(r[0], r[1], r[2], r[3]);
    transpose_detail::transpose4x4InLanes(r[4], r[5], r[6], r[7]);
    // r[a] holds columns a | a + 4 of lanes 0-3, r[4 + a] the same of lanes 4-7.
    for (int a = 0; a < 4; ++a) {
        columns[a] = _mm256_permute2f128_ps(r[a], r[4 + a], 0x20);
        columns[a + 4] = _mm256_permute2f128_ps(r[a], r[4 + a], 0x31);
    }
#else
    alignas(64) float lanes[kRowFloats][kLanes];
    for (std::size_t k = 0; k < kLanes; ++k) {
        const float* row = rowAt(rows, index[k]);
        for (std::size_t c = 0; c < kRowFloats; ++c) lanes[c][k] = row[c];
    }
    for (std::size_t c = 0; c < kRowFloats; ++c) columns[c] = FloatW::load_aligned(lanes[c]);
#endif
}

/// Float c of row `index` = columns[c] (the one-lane form).
inline void storeRowsTransposed(float* rows, std::int32_t index, const float* columns) {
    float* row = transpose_detail::rowAt(rows, index);
    for (std::size_t c = 0; c < kRowFloats; ++c) row[c] = columns[c];
}

/// Float c of row index[k] = lane k of columns[c]: whole rows are written, in lane order, so with repeated indices
/// the highest lane wins (as with a scatter).
inline void storeRowsTransposed(float* rows, const IntW& index, const FloatW* columns) {
    using transpose_detail::rowAt;
    alignas(64) std::int32_t at[kLanes];
    index.store_aligned(at);
#if XSIMD_WITH_AVX512F
    // The inverse of loadRowsTransposed: r[a] takes 128-bit lanes 0, 1 of columns a and a + 4 interleaved, r[4 + a]
    // their lanes 2, 3; the in-lane transposes then leave whole rows in the 256-bit halves.
    const __m512i firstHalf = _mm512_setr_epi32(0, 1, 2, 3, 16, 17, 18, 19, 4, 5, 6, 7, 20, 21, 22, 23);
    const __m512i secondHalf = _mm512_setr_epi32(8, 9, 10, 11, 24, 25, 26, 27, 12, 13, 14, 15, 28, 29, 30, 31);
    __m512 r[8];
    for (int a = 0; a < 4; ++a) {
        r[a] = _mm512_permutex2var_ps(columns[a], firstHalf, columns[a + 4]);
        r[4 + a] = _mm512_permutex2var_ps(columns[a], secondHalf, columns[a + 4]);
    }
    transpose_detail::transpose4x4InLanes(r[0], r[1], r[2], r[3]);
    transpose_detail::transpose4x4InLanes(r[4], r[5], r[6], r[7]);
    for (int j = 0; j < 4; ++j) transpose_detail::storeLow(rowAt(rows, at[j]), r[j]);
    for (int j = 0; j < 4; ++j) transpose_detail::storeHigh(rowAt(rows, at[j + 4]), r[j]);
    for (int j = 0; j < 4; ++j) transpose_detail::storeLow(rowAt(rows, at[8 + j]), r[4 + j]);
    for (int j = 0; j < 4; ++j) transpose_detail::storeHigh(rowAt(rows, at[12 + j]), r[4 + j]);
#elif XSIMD_WITH_AVX
    __m256 r[8];
    for (int a = 0; a < 4; ++a) {
        r[a] = _mm256_permute2f128_ps(columns[a], columns[a + 4], 0x20);
        r[4 + a] = _mm256_permute2f128_ps(columns[a], columns[a + 4], 0x31);
    }
    transpose_detail::transpose4x4InLanes(r[0], r[1], r[2], r[3]);
    transpose_detail::transpose4x4InLanes(r[4], r[5], r[6], r[7]);
    for (int k = 0; k < 8; ++k) _mm256_storeu_ps(rowAt(rows, at[k]), r[k]);
#else
    alignas(64) float lanes[kRowFloats][kLanes];
    for (std::size_t c = 0; c < kRowFloats; ++c) columns[c].store_aligned(lanes[c]);
    for (std::size_t k = 0; k < kLanes; ++k) {
        float* row = rowAt(rows, at[k]);
        for (std::size_t c = 0; c < kRowFloats; ++c) row[c] = lanes[c][k];
    }
#endif
}

}  // namespace rubble::simd
