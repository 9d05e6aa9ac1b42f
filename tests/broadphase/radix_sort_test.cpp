// The parallel radix sort against std::stable_sort: every key kind and entry point, the input shapes that break
// radix sorts (sorted, reversed, all equal, constant digits, narrow keys with payload bits), sizes around the
// small-input path, and identical results on 1 and 2 threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include "broadphase/radix_sort.h"
#include "core/parallel.h"

namespace {

using namespace rubble::detail;

enum class Shape { Random, Sorted, Reversed, AllEqual, FewDistinct };
constexpr Shape kShapes[] = {Shape::Random, Shape::Sorted, Shape::Reversed, Shape::AllEqual, Shape::FewDistinct};
constexpr std::size_t kSizes[] = {0, 1, 17, 63, 64, 1000, 100'000};

std::vector<std::uint32_t> makeKeys(Shape shape, std::size_t n, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::vector<std::uint32_t> k(n);
    for (auto& x : k) x = static_cast<std::uint32_t>(rng());
    switch (shape) {
        case Shape::Random:
            break;
        case Shape::Sorted:
            std::sort(k.begin(), k.end());
            break;
        case Shape::Reversed:
            std::sort(k.begin(), k.end(), std::greater<>());
            break;
        case Shape::AllEqual:
            std::fill(k.begin(), k.end(), 0xABCD1234u);
            break;
        case Shape::FewDistinct:
            for (auto& x : k) x = (x % 5) * 0x01010101u;
            break;
    }
    return k;
}

// Values 0..n-1 reveal stability: equal keys must keep ascending values.
template <class K>
void expectMatchesStableSort(const std::vector<K>& keys, const std::vector<K>& sortedKeys,
                             const std::vector<std::uint32_t>& sortedValues) {
    std::vector<std::uint32_t> idx(keys.size());
    std::iota(idx.begin(), idx.end(), 0u);
    std::stable_sort(idx.begin(), idx.end(), [&](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b]; });
    ASSERT_EQ(sortedValues.size(), idx.size());
    for (std::size_t i = 0; i < idx.size(); ++i) {
        ASSERT_EQ(sortedValues[i], idx[i]) << "at " << i;
        ASSERT_EQ(sortedKeys[i], keys[idx[i]]) << "at " << i;
    }
}

TEST(RadixSort, FloatKeyMappingPreservesOrder) {
    const float v[] = {-1e30f, -2.5f, -1.0f, -1e-30f, -0.0f, 0.0f, 1e-30f, 1.0f, 2.5f, 1e30f};
    for (std::size_t i = 0; i + 1 < std::size(v); ++i) {
        EXPECT_LT(floatToSortableKey(v[i]), floatToSortableKey(v[i + 1])) << v[i] << " vs " << v[i + 1];
        EXPECT_EQ(sortableKeyToFloat(floatToSortableKey(v[i])), v[i]);
    }
}

TEST(RadixSort, Uint32KeyValueMatchesStableSort) {
    TaskPool pool(2);
    RadixSortScratch scratch;
    for (Shape shape : kShapes)
        for (std::size_t n : kSizes) {
            SCOPED_TRACE(::testing::Message() << "shape " << static_cast<int>(shape) << " n " << n);
            const std::vector<std::uint32_t> keys = makeKeys(shape, n, 7);
            std::vector<std::uint32_t> k = keys, v(n);
            std::iota(v.begin(), v.end(), 0u);
            radixSort(k.data(), v.data(), n, scratch, pool);
            expectMatchesStableSort(keys, k, v);
        }
}

TEST(RadixSort, FloatKeyValueMatchesStableSort) {
    TaskPool pool(2);
    RadixSortScratch scratch;
    for (Shape shape : kShapes)
        for (std::size_t n : kSizes) {
            SCOPED_TRACE(::testing::Message() << "shape " << static_cast<int>(shape) << " n " << n);
            std::mt19937 rng(11);
            std::uniform_real_distribution<float> d(-1000.0f, 1000.0f);
            std::vector<float> keys(n);
            for (auto& x : keys) {
                x = d(rng);
                if (x == 0.0f) x = 1.0f;  // -0 sorts before +0 here but ties with it in std::stable_sort
            }
            if (shape == Shape::Sorted) std::sort(keys.begin(), keys.end());
            if (shape == Shape::Reversed) std::sort(keys.begin(), keys.end(), std::greater<>());
            if (shape == Shape::AllEqual) std::fill(keys.begin(), keys.end(), -3.25f);
            if (shape == Shape::FewDistinct)
                for (auto& x : keys) x = std::round(x / 400.0f) * 1.5f + (x < 0 ? -0.5f : 0.5f);
            std::vector<float> k = keys;
            std::vector<std::uint32_t> v(n);
            std::iota(v.begin(), v.end(), 0u);
            radixSort(k.data(), v.data(), n, scratch, pool);
            expectMatchesStableSort(keys, k, v);
        }
}

TEST(RadixSort, Uint64KeysMatchSort) {
    TaskPool pool(2);
    RadixSortScratch scratch;
    for (int bits : {64, 40, 12, 1})
        for (std::size_t n : kSizes) {
            SCOPED_TRACE(::testing::Message() << "bits " << bits << " n " << n);
            std::mt19937_64 rng(5);
            std::vector<std::uint64_t> keys(n);
            for (auto& x : keys) x = bits == 64 ? rng() : rng() & ((std::uint64_t{1} << bits) - 1);
            std::vector<std::uint64_t> expected = keys;
            std::sort(expected.begin(), expected.end());
            radixSort(keys.data(), n, scratch, pool);
            ASSERT_EQ(keys, expected);
        }
}

TEST(RadixSort, BitRangeSortCarriesPayloadStably) {
    // Key in bits [9, 29): a 20-bit key split into uneven digits, with payload bits on both sides of it.
    TaskPool pool(2);
    RadixSortScratch scratch;
    const int lowBit = 9, keyBits = 20;
    const auto keyOf = [&](std::uint64_t x) { return (x >> lowBit) & ((std::uint64_t{1} << keyBits) - 1); };
    for (std::size_t n : kSizes) {
        std::mt19937_64 rng(3);
        std::vector<std::uint64_t> items(n);
        for (auto& x : items) x = rng() & ~(std::uint64_t{0xFFF} << (lowBit + 8));  // few distinct keys: ties
        std::vector<std::uint64_t> expected = items;
        std::stable_sort(expected.begin(), expected.end(),
                         [&](std::uint64_t a, std::uint64_t b) { return keyOf(a) < keyOf(b); });
        radixSortBits(items.data(), n, lowBit, keyBits, scratch, pool);
        ASSERT_EQ(items, expected) << n;
    }
}

TEST(RadixSort, SortPairsCanonicalOrder) {
    TaskPool pool(2);
    for (std::uint32_t maxIndex : {1u, 1000u, 1'000'000u, 0xFFFFFFFFu})
        for (std::size_t n : kSizes) {
            SCOPED_TRACE(::testing::Message() << "maxIndex " << maxIndex << " n " << n);
            std::mt19937 rng(9);
            std::uniform_int_distribution<std::uint32_t> d(0, maxIndex);
            std::vector<BodyPair> pairs(n);
            for (auto& p : pairs) p = {d(rng), d(rng)};
            std::vector<BodyPair> expected = pairs;
            std::sort(expected.begin(), expected.end());
            sortPairs(pairs, pool);
            ASSERT_EQ(pairs, expected);
            sortPairs(pairs, pool);  // sorted input stays as it is
            ASSERT_EQ(pairs, expected);
        }
}

// Pairs of a resting pile: a few per body, keys wider than three radix passes. They take the counting sort by first
// body, each body's pairs then sorted by insertion (or std::sort for the one body given 40 pairs).
TEST(RadixSort, SortPairsFewPerBodyCanonicalOrder) {
    TaskPool pool(2);
    std::mt19937 rng(17);
    std::uniform_int_distribution<std::uint32_t> first(0, 4'999), second(0, 99'999);
    std::vector<BodyPair> pairs(20'000);
    for (auto& p : pairs) p = {first(rng), second(rng)};
    for (std::size_t i = 0; i < 40; ++i) pairs[i * 97] = {1'234, second(rng)};
    std::vector<BodyPair> expected = pairs;
    std::sort(expected.begin(), expected.end());
    sortPairs(pairs, pool);
    EXPECT_EQ(pairs, expected);
}

TEST(RadixSort, SameResultOnOneAndTwoThreads) {
    TaskPool one(1), two(2);
    RadixSortScratch s1, s2;
    for (Shape shape : kShapes) {
        const std::size_t n = 300'001;
        const std::vector<std::uint32_t> keys = makeKeys(shape, n, 21);
        std::vector<std::uint32_t> k1 = keys, k2 = keys, v1(n), v2(n);
        std::iota(v1.begin(), v1.end(), 0u);
        v2 = v1;
        radixSort(k1.data(), v1.data(), n, s1, one);
        radixSort(k2.data(), v2.data(), n, s2, two);
        EXPECT_EQ(k1, k2);
        EXPECT_EQ(v1, v2);

        // 50,000 bodies take the radix sort, 5,000 the counting sort by first body (60 pairs each on average).
        for (const std::uint32_t bodies : {50'000u, 5'000u}) {
            std::vector<BodyPair> p1(n), p2;
            for (std::size_t i = 0; i < n; ++i) p1[i] = {keys[i] % bodies, keys[(i * 7) % n] % 50'000};
            p2 = p1;
            std::vector<BodyPair> expected = p1;
            std::sort(expected.begin(), expected.end());
            sortPairs(p1, one);
            sortPairs(p2, two);
            EXPECT_EQ(p1, p2);
            EXPECT_EQ(p1, expected);
        }
    }
}

}  // namespace
