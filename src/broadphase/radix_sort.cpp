#include "broadphase/radix_sort.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cstring>

#include "core/parallel.h"

namespace rubble::detail {

namespace {

// 8-bit digits: 256 counters per chunk stay in L1 and 256 scatter streams stay within what the store buffers and
// L1 can keep open; wider digits save a pass but lose more than that to cache misses in the scatter.
constexpr int kMaxDigitBits = 8;
constexpr std::size_t kMaxRadix = std::size_t{1} << kMaxDigitBits;
// Below this, the histogram set-up costs more than a quadratic sort does.
constexpr std::size_t kInsertionSortBelow = 64;

// Chunks are large enough that each one streams its 256 scatter targets efficiently, and few enough (at most 32)
// that the serial prefix sum over (digit, chunk) stays negligible. They depend only on n, never on threads.
std::size_t chunkSizeFor(std::size_t n) { return std::max<std::size_t>(8192, (n + 31) / 32); }

std::uint64_t keyMask(int keyBits) { return keyBits >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << keyBits) - 1; }

void insertionSort(std::uint64_t* items, std::size_t n, int lowBit, std::uint64_t mask) {
    for (std::size_t i = 1; i < n; ++i) {
        const std::uint64_t item = items[i];
        const std::uint64_t key = (item >> lowBit) & mask;
        std::size_t j = i;
        for (; j > 0 && ((items[j - 1] >> lowBit) & mask) > key; --j) items[j] = items[j - 1];
        items[j] = item;
    }
}

}  // namespace

void radixSortBits(std::uint64_t* items, std::size_t n, int lowBit, int keyBits, RadixSortScratch& scratch,
                   TaskPool& pool) {
    assert(lowBit >= 0 && keyBits >= 0 && lowBit + keyBits <= 64);
    assert(n < (std::size_t{1} << 32));  // counts are 32-bit
    if (n < 2 || keyBits == 0) return;
    if (n < kInsertionSortBelow) {
        insertionSort(items, n, lowBit, keyMask(keyBits));
        return;
    }

    const int passes = (keyBits + kMaxDigitBits - 1) / kMaxDigitBits;
    // Spread the bits evenly (40 bits: 5 x 8; 20 bits: 3 x 7) so that no pass is wasted on a sliver of a digit.
    const int digitBits = (keyBits + passes - 1) / passes;
    const std::size_t radix = std::size_t{1} << digitBits;
    const std::size_t chunkSize = chunkSizeFor(n);
    const std::size_t chunks = TaskPool::chunkCount(n, chunkSize);
    // The top pass may hold fewer key bits than digitBits (20 bits: 7 + 7 + 6); its mask keeps payload bits above
    // the key out of the digit.
    int shifts[64];
    std::uint64_t masks[64];
    for (int p = 0; p < passes; ++p) {
        shifts[p] = lowBit + p * digitBits;
        masks[p] = keyMask(std::min(digitBits, keyBits - p * digitBits));
    }
    const auto digitOf = [](std::uint64_t item, int shift, std::uint64_t mask) {
        return static_cast<std::size_t>((item >> shift) & mask);
    };

    // One read counts the digits of every pass per chunk: the totals tell which passes to skip, and the first pass
    // that runs uses its per-chunk counts directly since nothing has moved yet.
    std::vector<std::uint32_t>& counts = scratch.counts;
    const std::size_t perChunk = static_cast<std::size_t>(passes) * radix;
    counts.assign(chunks * perChunk, 0);
    pool.forChunks(n, chunkSize, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::uint32_t* h = counts.data() + c * perChunk;
        for (std::size_t i = begin; i < end; ++i)
            for (int p = 0; p < passes; ++p) ++h[p * radix + digitOf(items[i], shifts[p], masks[p])];
    });

    bool skip[64] = {};
    for (int p = 0; p < passes; ++p) {
        for (std::size_t d = 0; d < radix && !skip[p]; ++d) {
            std::size_t total = 0;
            for (std::size_t c = 0; c < chunks; ++c) total += counts[c * perChunk + p * radix + d];
            if (total == n) skip[p] = true;
            if (total != 0) break;  // the first non-empty digit decides: all of n, or not constant
        }
    }

    scratch.buffer.resize(n);
    std::uint64_t* src = items;
    std::uint64_t* dst = scratch.buffer.data();
    bool countsFresh = true;  // counts still describe src (nothing has been scattered yet)
    for (int p = 0; p < passes; ++p) {
        if (skip[p]) continue;
        const int shift = shifts[p];
        const std::uint64_t mask = masks[p];
        // offsets[c * radix + d]: where chunk c writes its first element of digit d.
        std::uint32_t* offsets = counts.data();
        if (countsFresh) {
            for (std::size_t c = 0; c < chunks; ++c)
                std::memmove(offsets + c * radix, counts.data() + c * perChunk + p * radix,
                             radix * sizeof(std::uint32_t));
            countsFresh = false;
        } else {
            pool.forChunks(n, chunkSize, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
                std::uint32_t* h = offsets + c * radix;
                std::fill(h, h + radix, 0u);
                for (std::size_t i = begin; i < end; ++i) ++h[digitOf(src[i], shift, mask)];
            });
        }
        // Digit-major, chunk-minor: equal digits keep chunk order, which is what makes the sort stable.
        std::uint32_t running = 0;
        for (std::size_t d = 0; d < radix; ++d)
            for (std::size_t c = 0; c < chunks; ++c) {
                const std::uint32_t count = offsets[c * radix + d];
                offsets[c * radix + d] = running;
                running += count;
            }
        pool.forChunks(n, chunkSize, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
            std::uint32_t next[kMaxRadix];
            std::memcpy(next, offsets + c * radix, radix * sizeof(std::uint32_t));
            for (std::size_t i = begin; i < end; ++i) {
                const std::uint64_t item = src[i];
                dst[next[digitOf(item, shift, mask)]++] = item;
            }
        });
        std::swap(src, dst);
    }
    if (src != items) {
        pool.forChunks(n, chunkSize, [&](std::size_t, std::size_t begin, std::size_t end, int) {
            std::memcpy(items + begin, src + begin, (end - begin) * sizeof(std::uint64_t));
        });
    }
}

void radixSort(std::uint64_t* keys, std::size_t n, RadixSortScratch& scratch, TaskPool& pool) {
    radixSortBits(keys, n, 0, 64, scratch, pool);
}

namespace {

// Sorts (key, value) pairs given as 32-bit key images through the packed form key << 32 | value.
template <class Key, class ToBits, class FromBits>
void sortKeyValue(Key* keys, std::uint32_t* values, std::size_t n, RadixSortScratch& scratch, TaskPool& pool,
                  ToBits toBits, FromBits fromBits) {
    if (n < 2) return;
    scratch.items.resize(n);
    std::uint64_t* items = scratch.items.data();
    const std::size_t chunk = chunkSizeFor(n);
    pool.forChunks(n, chunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) items[i] = std::uint64_t{toBits(keys[i])} << 32 | values[i];
    });
    radixSortBits(items, n, 32, 32, scratch, pool);
    pool.forChunks(n, chunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) {
            keys[i] = fromBits(static_cast<std::uint32_t>(items[i] >> 32));
            values[i] = static_cast<std::uint32_t>(items[i]);
        }
    });
}

}  // namespace

void radixSort(std::uint32_t* keys, std::uint32_t* values, std::size_t n, RadixSortScratch& scratch, TaskPool& pool) {
    sortKeyValue(
        keys, values, n, scratch, pool, [](std::uint32_t k) { return k; }, [](std::uint32_t k) { return k; });
}

void radixSort(float* keys, std::uint32_t* values, std::size_t n, RadixSortScratch& scratch, TaskPool& pool) {
    sortKeyValue(keys, values, n, scratch, pool, floatToSortableKey, sortableKeyToFloat);
}

namespace {

// The counting sort by a keeps one counter per body per chunk; past this many bodies the radix sort is used.
constexpr std::size_t kMaxPairBuckets = std::size_t{1} << 20;
// Up to three radix passes (24-bit keys) cost no more than the counting sort.
constexpr int kPairSortCountingFromBits = 3 * 8;
// A body's pairs are sorted by b by insertion up to this many, by std::sort beyond.
constexpr std::size_t kInsertionSortPairsBelow = 32;
// Bodies per chunk of the per-body sorts: depends only on the body count.
constexpr std::size_t kBucketChunk = 2048;

/// Stable counting sort by a (per-chunk counts, offsets digit-major and chunk-minor as in radixSortBits), then each
/// body's pairs sorted by b: the result is the (a, b) order.
void sortPairsByFirstBody(std::vector<BodyPair>& pairs, std::size_t bodies, std::size_t chunk, TaskPool& pool,
                          RadixSortScratch& scratch) {
    const std::size_t n = pairs.size();
    const std::size_t chunks = TaskPool::chunkCount(n, chunk);
    std::vector<std::uint32_t>& offsets = scratch.counts;
    offsets.assign(chunks * bodies + bodies + 1, 0);
    std::uint32_t* bodyStart = offsets.data() + chunks * bodies;
    pool.forChunks(n, chunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::uint32_t* h = offsets.data() + c * bodies;
        for (std::size_t i = begin; i < end; ++i) ++h[pairs[i].a];
    });
    std::uint32_t running = 0;
    for (std::size_t a = 0; a < bodies; ++a) {
        bodyStart[a] = running;
        for (std::size_t c = 0; c < chunks; ++c) {
            const std::uint32_t count = offsets[c * bodies + a];
            offsets[c * bodies + a] = running;
            running += count;
        }
    }
    bodyStart[bodies] = running;
    scratch.pairs.resize(n);
    BodyPair* sorted = scratch.pairs.data();
    pool.forChunks(n, chunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::uint32_t* next = offsets.data() + c * bodies;
        for (std::size_t i = begin; i < end; ++i) sorted[next[pairs[i].a]++] = pairs[i];
    });
    pool.forChunks(bodies, kBucketChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t a = begin; a < end; ++a) {
            BodyPair* first = sorted + bodyStart[a];
            BodyPair* last = sorted + bodyStart[a + 1];
            if (static_cast<std::size_t>(last - first) >= kInsertionSortPairsBelow) {
                std::sort(first, last);
            } else {
                for (BodyPair* i = first + 1; i < last; ++i) {
                    const BodyPair item = *i;
                    BodyPair* j = i;
                    for (; j > first && item.b < (j - 1)->b; --j) *j = *(j - 1);
                    *j = item;
                }
            }
            std::copy(first, last, pairs.data() + bodyStart[a]);
        }
    });
}

}  // namespace

void sortPairs(std::vector<BodyPair>& pairs, TaskPool& pool, RadixSortScratch& scratch) {
    const std::size_t n = pairs.size();
    if (n < 2) return;
    const std::size_t chunk = chunkSizeFor(n);
    const std::size_t chunks = TaskPool::chunkCount(n, chunk);

    // One read finds the key width and whether there is anything to do (the stage sorts lists that are often
    // already in order, e.g. when an algorithm emits them that way).
    struct ChunkInfo {
        std::uint32_t maxA = 0, maxB = 0;
        bool sorted = true;
    };
    std::array<ChunkInfo, 32> info;  // chunkSizeFor makes at most 32 chunks
    assert(chunks <= info.size());
    pool.forChunks(n, chunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        ChunkInfo ci;
        for (std::size_t i = begin; i < end; ++i) {
            ci.maxA = std::max(ci.maxA, pairs[i].a);
            ci.maxB = std::max(ci.maxB, pairs[i].b);
            if (i > 0 && pairs[i] < pairs[i - 1]) ci.sorted = false;
        }
        info[c] = ci;
    });
    std::uint32_t maxA = 0, maxB = 0;
    bool sorted = true;
    for (std::size_t c = 0; c < chunks; ++c) {
        const ChunkInfo& ci = info[c];
        maxA = std::max(maxA, ci.maxA), maxB = std::max(maxB, ci.maxB), sorted &= ci.sorted;
    }
    if (sorted) return;

    const int widthB = std::bit_width(maxB);
    const int keyBits = std::bit_width(maxA) + widthB;
    // Few bodies for the pairs (a body has a handful of pairs): a counting sort by a, then each body's few pairs by
    // b, two passes over the pairs instead of one per 8 key bits. Measured: S2's 47,000 pairs of 9,100 bodies (28-bit
    // keys, four passes) sort in half the time; S3's 16,800 of 4,000 (24 bits, three passes) gain nothing. Its
    // passes over the buckets cost as much as those over the pairs: a few pairs among many bodies (2,000 pairs of
    // awake bodies in a field of 250,000 sleepers: 1.2 ms) go to the radix sort.
    const std::size_t bodies = std::size_t{maxA} + 1;
    if (keyBits > kPairSortCountingFromBits && bodies <= kMaxPairBuckets && chunks * bodies <= 4 * n) {
        sortPairsByFirstBody(pairs, bodies, chunk, pool, scratch);
        return;
    }
    scratch.items.resize(n);
    std::uint64_t* items = scratch.items.data();
    pool.forChunks(n, chunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) items[i] = std::uint64_t{pairs[i].a} << widthB | pairs[i].b;
    });
    radixSortBits(items, n, 0, keyBits, scratch, pool);
    const std::uint64_t maskB = (std::uint64_t{1} << widthB) - 1;
    pool.forChunks(n, chunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i)
            pairs[i] = {static_cast<std::uint32_t>(items[i] >> widthB), static_cast<std::uint32_t>(items[i] & maskB)};
    });
}

void sortPairs(std::vector<BodyPair>& pairs, TaskPool& pool) {
    thread_local RadixSortScratch scratch;
    sortPairs(pairs, pool, scratch);
}

}  // namespace rubble::detail
