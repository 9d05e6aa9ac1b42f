#pragma once
// Parallel LSD radix sort over the TaskPool. Every entry point sorts stably and gives the same result on any
// thread count: the input is cut into chunks whose boundaries depend only on the element count, each chunk counts
// its digits, the counts are prefix-summed in (digit, chunk) order by one thread, and each chunk scatters its own
// elements to the offsets it was given. Passes whose digit is the same for every element are skipped, so keys
// that use few bits (small indices, a narrow float range) cost fewer passes.
//
// The working form is a 64-bit item that carries its own payload: the key lives in a bit range of the item and
// the other bits ride along. A (uint32 key, uint32 value) pair is the item key << 32 | value sorted on the high
// half; moving one 8-byte word per element is cheaper than scattering two arrays.
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "broadphase/broadphase.h"
#include "storage/aligned_vector.h"

namespace rubble::detail {

class TaskPool;

/// Maps a float to an unsigned key with the same order (for non-NaN input; -0 sorts just before +0): positive
/// floats get the sign bit set, negative floats have every bit flipped so that larger magnitudes sort lower.
inline std::uint32_t floatToSortableKey(float f) {
    const std::uint32_t u = std::bit_cast<std::uint32_t>(f);
    return u ^ ((u & 0x80000000u) != 0 ? 0xFFFFFFFFu : 0x80000000u);
}
/// Inverse of floatToSortableKey.
inline float sortableKeyToFloat(std::uint32_t k) {
    return std::bit_cast<float>(k ^ ((k & 0x80000000u) != 0 ? 0x80000000u : 0xFFFFFFFFu));
}

/// Buffers a sort reuses from call to call, so that steady-state sorting does not allocate.
struct RadixSortScratch {
    AlignedVector<std::uint64_t> items;   ///< packed input for the pair and BodyPair entry points
    AlignedVector<std::uint64_t> buffer;  ///< ping-pong target of the scatter passes
    std::vector<std::uint32_t> counts;    ///< per-chunk digit counts, then per-chunk scatter offsets
    std::vector<BodyPair> pairs;          ///< sortPairs' counting sort by first body: the scattered pairs
};

/// Sorts items[0, n) by the bits [lowBit, lowBit + keyBits) of each item, stably; the other bits are payload.
/// keyBits in [0, 64 - lowBit]. The result is in items.
void radixSortBits(std::uint64_t* items, std::size_t n, int lowBit, int keyBits, RadixSortScratch& scratch,
                   TaskPool& pool);

/// Sorts 64-bit keys ascending.
void radixSort(std::uint64_t* keys, std::size_t n, RadixSortScratch& scratch, TaskPool& pool);

/// Sorts (keys[k], values[k]) by key, stably: values of equal keys keep their input order.
void radixSort(std::uint32_t* keys, std::uint32_t* values, std::size_t n, RadixSortScratch& scratch, TaskPool& pool);

/// Sorts (keys[k], values[k]) by float key (no NaN), stably.
void radixSort(float* keys, std::uint32_t* values, std::size_t n, RadixSortScratch& scratch, TaskPool& pool);

/// Sorts pairs by (a, b), the canonical order of candidate lists. The key is a << w | b with w the bit width of
/// the largest b, so 1M bodies cost 40-bit keys rather than 64-bit ones. Already sorted input costs one read.
void sortPairs(std::vector<BodyPair>& pairs, TaskPool& pool, RadixSortScratch& scratch);
/// As above with a scratch owned by the calling thread (kept between calls, so steady-state use does not
/// allocate).
void sortPairs(std::vector<BodyPair>& pairs, TaskPool& pool);

}  // namespace rubble::detail
