// The row transposes of simd/transpose.h against a plain scalar reference: lane k of column c must be float c of
// row index[k], bit for bit (the rows hold random bit patterns, NaNs included, so any arithmetic on the way or a
// lane out of place shows), for distinct, repeated and all-equal indices; a store writes whole rows in lane order,
// so with repeated indices the highest lane's row is the one left, and rows not indexed are untouched.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

#include "simd/transpose.h"
#include "storage/aligned_vector.h"

namespace rubble {
namespace {

using simd::FloatW;
using simd::kLanes;
using simd::kRowFloats;

constexpr std::int32_t kRows = 3 * static_cast<std::int32_t>(kLanes) + 5;

detail::AlignedVector<float> randomRows(std::mt19937& rng) {
    detail::AlignedVector<float> rows(static_cast<std::size_t>(kRows) * kRowFloats);
    for (float& f : rows) f = std::bit_cast<float>(static_cast<std::uint32_t>(rng()));
    return rows;
}

/// Index patterns: distinct rows, rows drawn with repeats, every lane the same row, and lanes in pairs.
std::vector<std::int32_t> indexPattern(int pattern, std::mt19937& rng) {
    std::vector<std::int32_t> index(kLanes);
    if (pattern == 0) {
        std::vector<std::int32_t> all(kRows);
        std::iota(all.begin(), all.end(), 0);
        std::shuffle(all.begin(), all.end(), rng);
        std::copy_n(all.begin(), kLanes, index.begin());
    } else if (pattern == 1) {
        std::uniform_int_distribution<std::int32_t> pick(0, 5);  // few rows: many repeats
        for (std::int32_t& i : index) i = pick(rng);
    } else if (pattern == 2) {
        std::fill(index.begin(), index.end(), kRows - 1);
    } else {
        std::uniform_int_distribution<std::int32_t> pick(0, kRows - 1);
        for (std::size_t k = 0; k < kLanes; k += 2) index[k] = pick(rng), index[std::min(k + 1, kLanes - 1)] = index[k];
    }
    return index;
}

TEST(Transpose, LoadRowsTransposedPutsFloatCOfRowIndexKInLaneK) {
    std::mt19937 rng(7);
    for (int trial = 0; trial < 200; ++trial) {
        const detail::AlignedVector<float> rows = randomRows(rng);
        const std::vector<std::int32_t> index = indexPattern(trial % 4, rng);
        FloatW columns[kRowFloats];
        simd::loadRowsTransposed(rows.data(), index.data(), columns);
        for (std::size_t c = 0; c < kRowFloats; ++c) {
            alignas(64) float got[kLanes];
            columns[c].store_aligned(got);
            for (std::size_t k = 0; k < kLanes; ++k) {
                const float want = rows[static_cast<std::size_t>(index[k]) * kRowFloats + c];
                ASSERT_EQ(std::bit_cast<std::uint32_t>(got[k]), std::bit_cast<std::uint32_t>(want))
                    << "trial " << trial << " column " << c << " lane " << k << " row " << index[k];
            }
        }
        // The one-lane form.
        float one[kRowFloats];
        simd::loadRowsTransposed(rows.data(), index.data(), one);
        ASSERT_EQ(std::memcmp(one, &rows[static_cast<std::size_t>(index[0]) * kRowFloats], sizeof one), 0);
    }
}

TEST(Transpose, StoreRowsTransposedWritesWholeRowsAndTheHighestLaneWins) {
    std::mt19937 rng(11);
    for (int trial = 0; trial < 200; ++trial) {
        const detail::AlignedVector<float> before = randomRows(rng);
        const std::vector<std::int32_t> index = indexPattern(trial % 4, rng);
        alignas(64) float lanes[kRowFloats][kLanes];
        for (auto& column : lanes)
            for (float& f : column) f = std::bit_cast<float>(static_cast<std::uint32_t>(rng()));
        FloatW columns[kRowFloats];
        for (std::size_t c = 0; c < kRowFloats; ++c) columns[c] = FloatW::load_aligned(lanes[c]);

        detail::AlignedVector<float> got = before, want = before;
        simd::storeRowsTransposed(got.data(), simd::loadInt<simd::IntW>(index.data()), columns);
        for (std::size_t k = 0; k < kLanes; ++k)  // lane order: a later lane overwrites an earlier one
            for (std::size_t c = 0; c < kRowFloats; ++c)
                want[static_cast<std::size_t>(index[k]) * kRowFloats + c] = lanes[c][k];
        for (std::int32_t r = 0; r < kRows; ++r)
            ASSERT_EQ(std::memcmp(&got[static_cast<std::size_t>(r) * kRowFloats],
                                  &want[static_cast<std::size_t>(r) * kRowFloats], kRowFloats * sizeof(float)),
                      0)
                << "trial " << trial << " row " << r;

        // The one-lane form writes exactly one row.
        detail::AlignedVector<float> single = before;
        const float row[kRowFloats] = {lanes[0][0], lanes[1][0], lanes[2][0], lanes[3][0],
                                       lanes[4][0], lanes[5][0], lanes[6][0], lanes[7][0]};
        simd::storeRowsTransposed(single.data(), index[0], row);
        for (std::int32_t r = 0; r < kRows; ++r) {
            const float* expected = r == index[0] ? row : &before[static_cast<std::size_t>(r) * kRowFloats];
            ASSERT_EQ(std::memcmp(&single[static_cast<std::size_t>(r) * kRowFloats], expected, sizeof row), 0);
        }
    }
}

TEST(Transpose, LoadAfterStoreGivesTheColumnsBack) {
    std::mt19937 rng(13);
    detail::AlignedVector<float> rows = randomRows(rng);
    const std::vector<std::int32_t> index = indexPattern(0, rng);
    alignas(64) float lanes[kRowFloats][kLanes];
    FloatW columns[kRowFloats];
    for (std::size_t c = 0; c < kRowFloats; ++c) {
        for (float& f : lanes[c]) f = std::bit_cast<float>(static_cast<std::uint32_t>(rng()));
        columns[c] = FloatW::load_aligned(lanes[c]);
    }
    simd::storeRowsTransposed(rows.data(), simd::loadInt<simd::IntW>(index.data()), columns);
    FloatW back[kRowFloats];
    simd::loadRowsTransposed(rows.data(), index.data(), back);
    for (std::size_t c = 0; c < kRowFloats; ++c) {
        alignas(64) float got[kLanes];
        back[c].store_aligned(got);
        EXPECT_EQ(std::memcmp(got, lanes[c], sizeof got), 0) << "column " << c;
    }
}

}  // namespace
}  // namespace rubble
