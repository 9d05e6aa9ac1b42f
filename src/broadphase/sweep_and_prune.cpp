#include "broadphase/sweep_and_prune.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/parallel.h"
#include "simd/simd.h"

namespace rubble::detail {

namespace {

// Per-slot markers in denseOfSlot_; dense indices are always below both.
constexpr std::uint32_t kAbsent = 0xFFFFFFFFu;
constexpr std::uint32_t kPlaced = 0xFFFFFFFEu;
// Up to this many bodies, and with this many slots per body or more (statics hold slots too), the markers by slot
// are a sorted table rather than an array over every slot.
constexpr std::uint32_t kSparseSlotsMax = 4096;
constexpr std::size_t kSparseSlotRatio = 16;
// Not a valid item (its dense index would be kAbsent): marks dropped entries before compaction.
constexpr std::uint64_t kNoItem = ~std::uint64_t{0};

// Chunks of the O(n) passes (moments, mapping, gathers): big enough that a task is worth scheduling.
constexpr std::size_t kStreamChunk = 16384;

// A switch of sweep axis throws the kept order away, so near-equal spreads must not flip it step after step: the
// current axis stays until another one's spread is clearly larger.
constexpr double kAxisSwitchRatio = 1.25;

// Temporal coherence pays while re-sorting the kept order costs less than a radix sort from scratch. Measured at
// 100k boxes on one thread: about 0.1 insertion moves per body re-sort in 60% of the radix sort's time, and the two
// break even near one move per body. The radix sort runs on every thread and the insertion pass on one, so the
// budget is a quarter of that; the pass bails out as soon as it crosses it (wasting at most n/4 moves). Bodies new
// since the last step, and far movers, are sorted on their own and merged in, cheap up to the same fraction.
constexpr std::uint64_t kInsertionMovesPerBodyDivisor = 4;
constexpr std::uint32_t kNewBodiesDivisor = 4;
// How far (in positions of last step's order) a body may have moved and still be re-sorted by insertion.
constexpr std::size_t kNeighbourhood = 16;

std::uint64_t makeItem(float key, std::uint32_t dense) { return std::uint64_t{floatToSortableKey(key)} << 32 | dense; }
std::uint32_t denseOf(std::uint64_t item) { return static_cast<std::uint32_t>(item); }

// Sweep chunks are ranges of the sorted order. Their size depends only on n, so the merged output does not depend
// on the thread count; they are small so that work stealing can even out dense regions (a cluster's boxes scan
// many more candidates than the same number of boxes in open space).
std::size_t sweepChunkFor(std::size_t n) { return std::clamp<std::size_t>(n / 64, 256, 1024); }

// Runs produce(i, keep, move) for i in [0, count) in parallel, each call setting its two outputs to an item or to
// kNoItem, then packs the kept items into out (null when nothing is kept) and the moved ones into moved
// (appended), both in index order. tmp holds 2 * count entries; counts is per-chunk scratch.
template <class Produce>
void produceCompacted(std::size_t count, TaskPool& pool, std::uint64_t* tmp, std::vector<std::uint32_t>& counts,
                      AlignedVector<std::uint64_t>* out, AlignedVector<std::uint64_t>& moved, Produce produce) {
    const std::size_t chunks = TaskPool::chunkCount(count, kStreamChunk);
    counts.assign(2 * (chunks + 1), 0);
    std::uint32_t* keptCounts = counts.data();
    std::uint32_t* movedCounts = counts.data() + chunks + 1;
    std::uint64_t* tmpMoved = tmp + count;
    pool.forChunks(count, kStreamChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::uint32_t kept = 0, move = 0;
        for (std::size_t i = begin; i < end; ++i) {
            produce(i, tmp[i], tmpMoved[i]);
            kept += tmp[i] != kNoItem;
            move += tmpMoved[i] != kNoItem;
        }
        keptCounts[c + 1] = kept;
        movedCounts[c + 1] = move;
    });
    for (std::size_t c = 0; c < chunks; ++c) keptCounts[c + 1] += keptCounts[c], movedCounts[c + 1] += movedCounts[c];
    const std::size_t movedBase = moved.size();
    assert(out != nullptr || keptCounts[chunks] == 0);
    if (out != nullptr) out->resize(keptCounts[chunks]);
    moved.resize(movedBase + movedCounts[chunks]);
    std::uint64_t* outData = out != nullptr ? out->data() : nullptr;
    pool.forChunks(count, kStreamChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::uint64_t* dst = outData + keptCounts[c];
        std::uint64_t* dstMoved = moved.data() + movedBase + movedCounts[c];
        for (std::size_t i = begin; i < end; ++i) {
            if (tmp[i] != kNoItem) *dst++ = tmp[i];
            if (tmpMoved[i] != kNoItem) *dstMoved++ = tmpMoved[i];
        }
    });
}

struct SortedBoxes {
    const float *axisMin, *axisMax, *uMin, *uMax, *vMin, *vMax;
    const std::uint32_t* dense;
    std::size_t count;
};

// The lanes of a mask as bits (lane k at bit k), from the one-bool-per-lane form simd/ offers: eight 0/1 bytes
// at a time, gathered into one byte by a multiply whose partial products land each byte's bit in the top byte.
template <class M>
std::uint32_t laneBits(const M& m) {
    constexpr std::size_t L = sizeof(M) == sizeof(bool) ? 1 : simd::kLanes;
    if constexpr (L < 8) {
        bool b[L];
        simd::storeMask(b, m);
        std::uint32_t bits = 0;
        for (std::size_t k = 0; k < L; ++k) bits |= static_cast<std::uint32_t>(b[k]) << k;
        return bits;
    } else {
        static_assert(L % 8 == 0 && L <= 32);
        bool b[L];
        simd::storeMask(b, m);
        std::uint32_t bits = 0;
        for (std::size_t g = 0; g < L / 8; ++g) {
            std::uint64_t bytes;
            std::memcpy(&bytes, b + 8 * g, 8);
            bits |= static_cast<std::uint32_t>((bytes * 0x0102040810204080ull) >> 56) << (8 * g);
        }
        return bits;
    }
}

// Emits the pairs of box dp with the boxes dense[k] for the set lanes k of hit. Out of line: pairs are rare next
// to candidate blocks, and inlined, this path's registers push the scan loop's pointers onto the stack.
template <class M>
[[gnu::noinline]] void emitHits(M hit, const std::uint32_t* dense, std::uint32_t dp, const PairFilter& filter,
                                ChunkPairs& pairs) {
    for (std::uint32_t bits = laneBits(hit); bits != 0; bits &= bits - 1) {
        const std::uint32_t dq = dense[std::countr_zero(bits)];
        const BodyPair pair{std::min(dp, dq), std::max(dp, dq)};
        pairs.add(pair, filter.accepts(pair.a, pair.b));
    }
}

// Sorted positions [begin, end) each scan forward through the boxes that start before they end, a block of lanes
// at a time. Blocks start on multiples of the lane count, so that every load is aligned (the arrays start on a
// cache line) instead of splitting two lines; the first block masks off the lanes up to and including p. The swept
// axis needs no test inside a block when the block's last minimum is still in range (the order is sorted), so a
// block costs one scalar compare and the u and v tests. Those two are combined without a branch: a branch on the u
// test alone is taken in about one block in seven in open space, at random, and its mispredictions cost more than
// the two loads they would save. The one branch left (any lane a pair) is rarely taken. Runs over simd::FloatW in
// production and over float as the reference.
template <class F>
void sweepRange(const SortedBoxes& boxes, std::size_t begin, std::size_t end, const PairFilter& filter,
                ChunkPairs& pairs) {
    constexpr std::size_t L = simd::lanesOf<F>;
    const float* const axisMin = boxes.axisMin;
    const float* const uMin = boxes.uMin;
    const float* const uMax = boxes.uMax;
    const float* const vMin = boxes.vMin;
    const float* const vMax = boxes.vMax;
    const std::uint32_t* const dense = boxes.dense;
    const F lanes = simd::laneIndices<F>();
    for (std::size_t p = begin; p < end; ++p) {
        const float maxP = boxes.axisMax[p];
        const F maxPW = simd::broadcast<F>(maxP);
        const F uMinP = simd::broadcast<F>(uMin[p]), uMaxP = simd::broadcast<F>(uMax[p]);
        const F vMinP = simd::broadcast<F>(vMin[p]), vMaxP = simd::broadcast<F>(vMax[p]);
        const std::uint32_t dp = dense[p];
        pairs.startBody();
        std::size_t q = (p + 1) / L * L;
        // Lanes of the first block that lie after p (all of them when p + 1 starts a block).
        const auto afterP = lanes > simd::broadcast<F>(static_cast<float>(p + 1 - q) - 1.0f);
        // The NaN padding past the end fails every compare, so the scan stops there at the latest.
        for (;; q += L) {
            const bool full = axisMin[q + L - 1] <= maxP;
            const F uMinQ = simd::load<F>(uMin + q), uMaxQ = simd::load<F>(uMax + q);
            const F vMinQ = simd::load<F>(vMin + q), vMaxQ = simd::load<F>(vMax + q);
            auto hit = simd::andMask(simd::andMask(uMinQ <= uMaxP, uMinP <= uMaxQ),
                                     simd::andMask(vMinQ <= vMaxP, vMinP <= vMaxQ));
            if (!full) hit = simd::andMask(hit, simd::load<F>(axisMin + q) <= maxPW);
            if (q <= p) hit = simd::andMask(hit, afterP);
            if (simd::any(hit)) {
                emitHits(hit, dense + q, dp, filter, pairs);
                if (pairs.bodyDone() && full) {
                    // A pile: the boxes still in the swept range go untested (counted as dropped).
                    const float* rangeEnd =
                        std::upper_bound(axisMin + q + L, axisMin + std::max(boxes.count, q + L), maxP,
                                         [](float value, float min) { return !(min <= value); });
                    pairs.skip(static_cast<std::uint64_t>(rangeEnd - (axisMin + q + L)));
                    break;
                }
            }
            if (!full) break;
        }
    }
}

}  // namespace

void SweepAndPrune::reset() {
    axis_ = -1;
    prevSlotOfDense_.clear();
    usedInsertion_ = false;
    insertionMoves_ = 0;
}

void SweepAndPrune::findPairs(const Bounds& bounds, const std::uint32_t* slotOfDense, std::uint32_t slotCount,
                              const PairFilter& filter, TaskPool& pool, std::vector<BodyPair>& out) {
    out.clear();
    droppedPairs_ = 0;
    const std::uint32_t n = bounds.size();
    usedInsertion_ = false;
    insertionMoves_ = 0;
    if (n == 0) {
        prevSlotOfDense_.clear();
        return;
    }

    // Sweep along the axis of largest spread of the centres: it separates boxes best, so the fewest candidates
    // pass the swept-axis interval test. Sums are per fixed chunk in double and merged in chunk order, so the
    // choice is the same on any thread count.
    const std::array<const float*, 3> mins = {bounds.minX.data(), bounds.minY.data(), bounds.minZ.data()};
    const std::array<const float*, 3> maxs = {bounds.maxX.data(), bounds.maxY.data(), bounds.maxZ.data()};
    const std::size_t momentChunks = TaskPool::chunkCount(n, kStreamChunk);
    chunkMoments_.assign(momentChunks * 6, 0.0);
    pool.forChunks(n, kStreamChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        for (int a = 0; a < 3; ++a) {
            double sum = 0, sumSq = 0;
            for (std::size_t i = begin; i < end; ++i) {
                const double centre = static_cast<double>(mins[a][i]) + static_cast<double>(maxs[a][i]);
                sum += centre;
                sumSq += centre * centre;
            }
            chunkMoments_[c * 6 + a * 2] = sum;
            chunkMoments_[c * 6 + a * 2 + 1] = sumSq;
        }
    });
    std::array<double, 3> variance{};
    for (int a = 0; a < 3; ++a) {
        double sum = 0, sumSq = 0;
        for (std::size_t c = 0; c < momentChunks; ++c)
            sum += chunkMoments_[c * 6 + a * 2], sumSq += chunkMoments_[c * 6 + a * 2 + 1];
        const double mean = sum / n;
        variance[a] = std::max(0.0, sumSq / n - mean * mean);
    }
    int axis = static_cast<int>(std::max_element(variance.begin(), variance.end()) - variance.begin());
    const bool haveOrder = axis_ >= 0 && !prevSlotOfDense_.empty();
    if (haveOrder && variance[axis] <= kAxisSwitchRatio * variance[axis_]) axis = axis_;

    if (haveOrder && axis == axis_) usedInsertion_ = sortByInsertion(mins[axis], slotOfDense, slotCount, n, pool);
    if (!usedInsertion_) sortByRadix(mins[axis], n, pool);
    axis_ = axis;

    gatherSorted(bounds, pool);
    sweep(filter, pool, out);

    prevSlotOfDense_.resize(n);
    std::uint32_t* prevSlots = prevSlotOfDense_.data();
    pool.forChunks(n, kStreamChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        std::copy(slotOfDense + begin, slotOfDense + end, prevSlots + begin);
    });
}

bool SweepAndPrune::sortByInsertion(const float* minAxis, const std::uint32_t* slotOfDense, std::uint32_t slotCount,
                                    std::uint32_t n, TaskPool& pool) {
    const std::size_t prevCount = prevSlotOfDense_.size();
    const std::uint32_t* prevSlotOfDense = prevSlotOfDense_.data();
    const std::uint32_t* prevOrder = denseOfSorted_.data();  // last step's sorted order, in last step's dense indices

    // The common step adds and removes nothing: then every body has the dense index it had, which one sequential
    // compare proves, and last step's order is this step's order as it stands.
    bool sameBodies = prevCount == n;
    if (sameBodies) {
        const std::size_t chunks = TaskPool::chunkCount(n, kStreamChunk);
        chunkCounts_.assign(chunks, 0);
        pool.forChunks(n, kStreamChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
            chunkCounts_[c] = std::equal(slotOfDense + begin, slotOfDense + end, prevSlotOfDense + begin) ? 0 : 1;
        });
        sameBodies = std::all_of(chunkCounts_.begin(), chunkCounts_.end(), [](std::uint32_t c) { return c == 0; });
    }
    // A body whose new minimum lies outside the old minima of its neighbourhood in last step's order would cost
    // a long run of insertion moves: it teleported, or it is a new body that took a freed slot and with it a
    // stranger's place. Such far movers join the new bodies, which are sorted apart and merged in.
    const float* oldKeys = axisMin_.data();
    const auto place = [&, prevCount](std::size_t k, std::uint32_t d, std::uint64_t& keep, std::uint64_t& move) {
        const float key = minAxis[d];
        const float lo = oldKeys[k >= kNeighbourhood ? k - kNeighbourhood : 0];
        const float hi = oldKeys[std::min(k + kNeighbourhood, prevCount - 1)];
        const bool near = lo <= key && key <= hi;
        keep = near ? makeItem(key, d) : kNoItem;
        move = near ? kNoItem : makeItem(key, d);
    };
    merged_.resize(2 * std::max<std::size_t>(prevCount, n));
    newItems_.clear();
    if (sameBodies) {
        produceCompacted(
            prevCount, pool, merged_.data(), chunkCounts_, &items_, newItems_,
            [&](std::size_t k, std::uint64_t& keep, std::uint64_t& move) { place(k, prevOrder[k], keep, move); });
    } else {
        // Bodies came or went: follow each one through its slot, which stays with the body across swap-removes.
        // The markers live in an array by slot, whose entries are kAbsent between calls (this call resets the ones it
        // writes, all at this step's bodies' slots) or, for a few bodies among many slots (a million statics), in a
        // table sorted by slot: growing the array to every slot of such a world cost 4 ms when its count grew.
        const bool sparse = n <= kSparseSlotsMax && slotCount > kSparseSlotRatio * std::size_t(n);
        std::uint32_t* denseOfSlot = nullptr;
        if (sparse) {
            slotTable_.resize(n);
            for (std::uint32_t i = 0; i < n; ++i) slotTable_[i] = std::uint64_t(slotOfDense[i]) << 32 | i;
            std::sort(slotTable_.begin(), slotTable_.end());
            slotMarks_.resize(n);
            for (std::uint32_t j = 0; j < n; ++j) slotMarks_[j] = static_cast<std::uint32_t>(slotTable_[j]);
        } else {
            if (denseOfSlot_.size() < slotCount) denseOfSlot_.resize(slotCount, kAbsent);
            denseOfSlot = denseOfSlot_.data();
            // Slots are distinct, so the chunks write disjoint entries.
            pool.forChunks(n, kStreamChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
                for (std::size_t i = begin; i < end; ++i) denseOfSlot[slotOfDense[i]] = static_cast<std::uint32_t>(i);
            });
        }
        // The marker of a slot, or null for a slot no body of this step holds.
        const auto markerOf = [&](std::uint32_t slot) -> std::uint32_t* {
            if (!sparse) return slot < slotCount ? denseOfSlot + slot : nullptr;
            const auto it = std::lower_bound(slotTable_.begin(), slotTable_.end(), std::uint64_t(slot) << 32);
            if (it == slotTable_.end() || (*it >> 32) != slot) return nullptr;
            return slotMarks_.data() + (it - slotTable_.begin());
        };
        // Last step's order, mapped to this step's dense indices; bodies removed since then drop out.
        produceCompacted(prevCount, pool, merged_.data(), chunkCounts_, &items_, newItems_,
                         [&](std::size_t k, std::uint64_t& keep, std::uint64_t& move) {
                             keep = move = kNoItem;
                             std::uint32_t* marker = markerOf(prevSlotOfDense[prevOrder[k]]);
                             if (marker == nullptr) return;
                             const std::uint32_t d = *marker;
                             if (d >= n) return;  // absent (or, defensively, a slot seen twice)
                             *marker = kPlaced;   // each slot occurs once in the old order: disjoint writes
                             place(k, d, keep, move);
                         });
        // Bodies added since then: their slot was not in the old order.
        produceCompacted(n, pool, merged_.data(), chunkCounts_, nullptr, newItems_,
                         [&](std::size_t i, std::uint64_t& keep, std::uint64_t& move) {
                             keep = kNoItem;
                             move = *markerOf(slotOfDense[i]) == kPlaced
                                        ? kNoItem
                                        : makeItem(minAxis[i], static_cast<std::uint32_t>(i));
                         });
        if (!sparse)
            pool.forChunks(n, kStreamChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
                for (std::size_t i = begin; i < end; ++i) denseOfSlot[slotOfDense[i]] = kAbsent;
            });
    }
    const std::size_t added = newItems_.size();
    if (added > n / kNewBodiesDivisor) return false;

    // Insertion sort of the kept order with a budget of moves; past it the order is too scrambled to be worth it.
    const std::uint64_t budget = n / kInsertionMovesPerBodyDivisor + 64;
    std::uint64_t moves = 0;
    std::uint64_t* items = items_.data();
    const std::size_t kept = items_.size();
    for (std::size_t i = 1; i < kept; ++i) {
        const std::uint64_t item = items[i];
        if (items[i - 1] <= item) continue;
        std::size_t j = i;
        do {
            items[j] = items[j - 1];
            --j;
        } while (j > 0 && items[j - 1] > item);
        items[j] = item;
        moves += i - j;
        if (moves > budget) return false;
    }
    insertionMoves_ = moves;

    if (added > 0) {
        // Items are distinct (dense indices differ), so sorting all 64 bits gives the (minimum, dense) order.
        constexpr std::size_t kRadixAbove = 4096;
        if (added > kRadixAbove)
            radixSortBits(newItems_.data(), added, 0, 64, radix_, pool);
        else
            std::sort(newItems_.begin(), newItems_.end());
        merged_.resize(n);
        std::merge(items_.begin(), items_.end(), newItems_.begin(), newItems_.end(), merged_.begin());
        std::swap(items_, merged_);
    }
    assert(items_.size() == n);
    return true;
}

void SweepAndPrune::sortByRadix(const float* minAxis, std::uint32_t n, TaskPool& pool) {
    items_.resize(n);
    std::uint64_t* items = items_.data();
    pool.forChunks(n, kStreamChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) items[i] = makeItem(minAxis[i], static_cast<std::uint32_t>(i));
    });
    // The dense index is already in input order, so sorting the key half stably yields (key, dense) order.
    radixSortBits(items, n, 32, 32, radix_, pool);
}

void SweepAndPrune::gatherSorted(const Bounds& bounds, TaskPool& pool) {
    const std::size_t n = items_.size();
    const std::size_t padded = n + simd::kLanes;
    for (auto* a : {&axisMin_, &axisMax_, &uMin_, &uMax_, &vMin_, &vMax_}) a->resize(padded);
    denseOfSorted_.resize(padded);

    const int u = (axis_ + 1) % 3, v = (axis_ + 2) % 3;
    const std::array<const float*, 3> mins = {bounds.minX.data(), bounds.minY.data(), bounds.minZ.data()};
    const std::array<const float*, 3> maxs = {bounds.maxX.data(), bounds.maxY.data(), bounds.maxZ.data()};
    const float *aMax = maxs[axis_], *bMinU = mins[u], *bMaxU = maxs[u], *bMinV = mins[v], *bMaxV = maxs[v];
    const std::uint64_t* items = items_.data();
    float *sAxisMin = axisMin_.data(), *sAxisMax = axisMax_.data(), *sUMin = uMin_.data(), *sUMax = uMax_.data(),
          *sVMin = vMin_.data(), *sVMax = vMax_.data();
    std::uint32_t* sDense = denseOfSorted_.data();
    // The sorted order visits the dense arrays at random: past a few hundred thousand bodies every read misses the
    // cache, and the gather is bound by how many misses are in flight. Prefetching a fixed distance ahead keeps more
    // of them going than the out-of-order window does by itself. The swept minimum needs no read: it is the key.
    constexpr std::size_t kPrefetchDistance = 24;
    pool.forChunks(n, kStreamChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t k = begin; k < end; ++k) {
            if (k + kPrefetchDistance < end) {
                const std::uint32_t ahead = denseOf(items[k + kPrefetchDistance]);
                for (const float* a : {aMax, bMinU, bMaxU, bMinV, bMaxV}) __builtin_prefetch(a + ahead);
            }
            const std::uint32_t d = denseOf(items[k]);
            sAxisMin[k] = sortableKeyToFloat(static_cast<std::uint32_t>(items[k] >> 32));
            sAxisMax[k] = aMax[d];
            sUMin[k] = bMinU[d], sUMax[k] = bMaxU[d];
            sVMin[k] = bMinV[d], sVMax[k] = bMaxV[d];
            sDense[k] = d;
        }
    });
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (auto* a : {&axisMin_, &axisMax_, &uMin_, &uMax_, &vMin_, &vMax_}) std::fill(a->begin() + n, a->end(), nan);
    std::fill(denseOfSorted_.begin() + n, denseOfSorted_.end(), 0u);
}

void SweepAndPrune::sweep(const PairFilter& filter, TaskPool& pool, std::vector<BodyPair>& out) {
    const std::size_t n = items_.size();
    const SortedBoxes s{axisMin_.data(), axisMax_.data(), uMin_.data(),          uMax_.data(),
                        vMin_.data(),    vMax_.data(),    denseOfSorted_.data(), n};
    const std::size_t chunkSize = sweepChunkFor(n);
    const std::size_t chunks = TaskPool::chunkCount(n, chunkSize);
    if (chunkPairs_.size() < chunks) chunkPairs_.resize(chunks);  // never shrinks: the vectors keep their capacity
    chunkDropped_.assign(chunks, 0);
    const std::size_t cap = budget_.chunkCap(n, chunks);
    pool.forChunks(n, chunkSize, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        const auto sweepChunk = [&](ChunkPairs& pairs) {
            chunkPairs_[c].clear();
            if (scalarKernel_)
                sweepRange<float>(s, begin, end, filter, pairs);
            else
                sweepRange<simd::FloatW>(s, begin, end, filter, pairs);
            chunkDropped_[c] = pairs.dropped;
        };
        ChunkPairs exact{chunkPairs_[c], cap, budget_.overlapsPerBody};
        sweepChunk(exact);
        if (exact.dropped == 0) return;
        // Past the budget: sweep again with the cap shared evenly, so that a pile's pairs spread over its bodies.
        ChunkPairs shared{chunkPairs_[c], cap, budget_.overlapsPerBody, std::max<std::size_t>(1, cap / (end - begin))};
        sweepChunk(shared);
    });
    droppedPairs_ = 0;
    for (const std::uint64_t d : chunkDropped_) droppedPairs_ += d;

    // Merge in chunk order: the output is the same sequence whatever ran where.
    pairOffsets_.assign(chunks + 1, 0);
    for (std::size_t c = 0; c < chunks; ++c) pairOffsets_[c + 1] = pairOffsets_[c] + chunkPairs_[c].size();
    out.resize(pairOffsets_[chunks]);
    constexpr std::size_t kMergeChunks = 16;
    pool.forChunks(chunks, kMergeChunks, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t c = begin; c < end; ++c)
            std::copy(chunkPairs_[c].begin(), chunkPairs_[c].end(),
                      out.begin() + static_cast<std::ptrdiff_t>(pairOffsets_[c]));
    });
}

}  // namespace rubble::detail
