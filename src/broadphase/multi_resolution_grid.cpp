#include "broadphase/multi_resolution_grid.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <tuple>

#include "core/parallel.h"
#include "simd/simd.h"

namespace rubble::detail {

namespace {

// Small enough that S2 (9,100 bodies) and S3 (4,000) split their key and gather passes across two workers.
constexpr std::size_t kBodyChunk = 4096;
// Cell coordinates are relative to the smallest centre and clamped to at most 20 bits (a million cells per axis),
// fewer when the key and the body index would not fit one 64-bit word together (1M bodies: 13 bits). Clamping is
// monotone and never moves two cells further apart, so neighbouring cells stay neighbours and no pair is lost; only
// a world wider than that many finest cells would crowd its far edge into the last cell (slower, still exact).
constexpr int kMaxAxisBits = 20;
// Software prefetch distance of the gather, in slots: its reads are random, one cache line per body.
constexpr std::uint32_t kGatherPrefetch = 16;
constexpr std::size_t kBoxStride = 8;  // floats per body record: one 32-byte half of a cache line
// From this many bodies on, the SoA bounds (24 bytes a body) outgrow the private L2, and the gather's six random
// reads per body cost six misses; copying each box into one record during the key pass (sequential) leaves one.
// Below it, the copy costs more than it saves.
constexpr std::uint32_t kRecordsFrom = 200000;
// ... unless the rows are already near their slots (the world keeps large worlds in cell order): a read within this
// many rows of the slot finds its cache lines still loaded from its neighbours' reads, so the gather needs no records
// when three quarters of the last gather's reads were that near.
constexpr std::uint32_t kNearRows = 8192;
// The binning cell is larger than the level's extent bound by this factor, so that rounding can never put two
// touching bodies of one level two cells apart: extents are float differences (a true extent exceeds its rounded
// value by at most 2^-24 of it), centres and cell coordinates doubles (relative error ~1e-16).
constexpr double kBinMargin = 1e-6;
// From this many boxes on, the grid keeps its layout (origin, levels, key widths) while the boxes fit it, and when the
// caller vouches for the rows (RowContinuity), re-sorts only the boxes that changed cell and merges them into the
// rest: ~3-10% of a sparse world's bodies change cell per step, and the radix sort of all keys was a fifth of the
// 1M-sphere world's step. Below it the full sort is cheap, and the layout fits each step's boxes as tightly as they
// allow.
constexpr std::uint32_t kIncrementalFrom = 65536;
// A layout kept from step to step gets room to keep: the largest box may grow by this fraction, and the centres may
// move this fraction of the span (and at least kOriginRoomCells finest cells) beyond either side, before it is
// built again.
constexpr double kExtentRoom = 1.0 / 32.0;
constexpr double kSpanRoom = 1.0 / 16.0;
constexpr double kOriginRoomCells = 8.0;
// Slack, in cells, on the coarse-level query ranges for the same reason.
constexpr double kQuerySlack = 1e-6;
// Boxes with a non-finite bound get this key: they sort after every cell and are tested against everything.
constexpr std::uint64_t kOutlierKey = ~std::uint64_t{0};
constexpr std::uint64_t kEmptySlot = ~std::uint64_t{0};
constexpr std::uint32_t kNoCell = ~std::uint32_t{0};

std::size_t rowChunkSize(std::size_t rows) {
    // Enough chunks to balance clustered scenes across workers; depends only on the row count.
    return std::clamp<std::size_t>(rows / 256, 32, 2048);
}

/// The boxes in slot order, as raw pointers for the inner loops.
struct SortedView {
    const float* minX;
    const float* minY;
    const float* minZ;
    const float* maxX;
    const float* maxY;
    const float* maxZ;
    const std::uint32_t* body;
};

/// Counts the candidates [j, j1) of a search that spent its budget as dropped (with `slotX`, those up to x cell xHi).
/// Out of line: only piles get here, and inlined it would weigh on the search loop of every scene.
[[gnu::noinline, gnu::cold]] void skipCandidates(ChunkPairs& pairs, std::uint32_t j, std::uint32_t j1,
                                                 const std::uint32_t* slotX, std::uint32_t xHi) {
    const std::uint32_t end =
        slotX != nullptr ? static_cast<std::uint32_t>(std::upper_bound(slotX + j, slotX + j1, xHi) - slotX) : j1;
    pairs.skip(end - j);
}

/// Calls hit(j) for every slot j in [j0, j1) whose box overlaps slot i's, ascending. One SIMD batch of candidates
/// per step; the arrays are padded by a batch so the last load stays in bounds, and lanes past j1 are masked off.
/// With a row's x cells `slotX` (ascending in [j0, j1)), stops after the first batch that reaches past x cell xHi:
/// later slots of the row lie further right and cannot be neighbours. Once slot i's search has spent its budget
/// (`pairs`), the candidates left are counted as dropped, not tested.
template <class Hit>
inline void forOverlapping(const SortedView& s, std::uint32_t i, std::uint32_t j0, std::uint32_t j1,
                           const std::uint32_t* slotX, std::uint32_t xHi, const simd::FloatW& laneIndex,
                           ChunkPairs& pairs, Hit&& hit) {
    using simd::FloatW;
    if (j0 >= j1) return;
    if (pairs.bodyDone()) [[unlikely]]
        return skipCandidates(pairs, j0, j1, slotX, xHi);
    const FloatW aMinX(s.minX[i]), aMinY(s.minY[i]), aMinZ(s.minZ[i]);
    const FloatW aMaxX(s.maxX[i]), aMaxY(s.maxY[i]), aMaxZ(s.maxZ[i]);
    for (std::uint32_t j = j0;; j += static_cast<std::uint32_t>(simd::kLanes)) {
        // Closed intervals on every axis: exactly overlaps().
        auto m = simd::andMask(
            laneIndex < FloatW(static_cast<float>(j1 - j)),
            simd::andMask(aMinX <= simd::load<FloatW>(s.maxX + j), simd::load<FloatW>(s.minX + j) <= aMaxX));
        m = simd::andMask(
            m, simd::andMask(aMinY <= simd::load<FloatW>(s.maxY + j), simd::load<FloatW>(s.minY + j) <= aMaxY));
        m = simd::andMask(
            m, simd::andMask(aMinZ <= simd::load<FloatW>(s.maxZ + j), simd::load<FloatW>(s.minZ + j) <= aMaxZ));
        // Most batches hit nothing: test before the per-lane loop, which the compiler may keep out of line.
        if (simd::any(m)) simd::forEachSetLane(m, [&](std::size_t k) { hit(j + static_cast<std::uint32_t>(k)); });
        if (j1 - j <= simd::kLanes || (slotX != nullptr && slotX[j + simd::kLanes - 1] > xHi)) return;
        if (pairs.bodyDone()) [[unlikely]]
            return skipCandidates(pairs, j + static_cast<std::uint32_t>(simd::kLanes), j1, slotX, xHi);
    }
}

/// A box's largest extent (0 for an inverted box: overlaps() then needs its centre inside the other box, which the
/// centre-distance bound covers) and whether it is usable: a box whose float centre or extent is not finite is an
/// outlier. The statistics and the keys both decide this here, in float, so they agree lane for lane.
template <class F>
simd::MaskOf<F> boxExtent(const F (&lo)[3], const F (&hi)[3], F& extent) {
    extent = F(0.0f);
    simd::MaskOf<F> finite = simd::isFinite(F(0.0f));
    for (int a = 0; a < 3; ++a) {
        const F e = hi[a] - lo[a];
        finite = simd::andMask(finite, simd::andMask(simd::isFinite(e), simd::isFinite((lo[a] + hi[a]) * F(0.5f))));
        extent = simd::max(extent, e);
    }
    return finite;
}

/// Running minima and maxima of the usable boxes, lane by lane.
template <class F>
struct BoxRanges {
    F centreMin[3], centreMax[3], extentMin, extentMax;
    std::uint32_t outliers = 0;

    BoxRanges() {
        constexpr float inf = std::numeric_limits<float>::infinity();
        for (int a = 0; a < 3; ++a) centreMin[a] = F(inf), centreMax[a] = F(-inf);
        extentMin = F(inf), extentMax = F(0.0f);
    }
    void add(const Bounds& b, std::size_t i) {
        const F lo[3] = {simd::load<F>(&b.minX[i]), simd::load<F>(&b.minY[i]), simd::load<F>(&b.minZ[i])};
        const F hi[3] = {simd::load<F>(&b.maxX[i]), simd::load<F>(&b.maxY[i]), simd::load<F>(&b.maxZ[i])};
        F extent;
        const auto finite = boxExtent(lo, hi, extent);
        // Only approximate: the origin and span only shape the keys (clamping keeps them exact), and the largest
        // extent is checked against the same float extents the keys use.
        for (int a = 0; a < 3; ++a) {
            const F c = (lo[a] + hi[a]) * F(0.5f);
            centreMin[a] = simd::select(finite, simd::min(centreMin[a], c), centreMin[a]);
            centreMax[a] = simd::select(finite, simd::max(centreMax[a], c), centreMax[a]);
        }
        extentMin = simd::select(finite, simd::min(extentMin, extent), extentMin);
        extentMax = simd::select(finite, simd::max(extentMax, extent), extentMax);
        simd::forEachSetLane(simd::notMask(finite), [&](std::size_t) { ++outliers; });
    }
};

}  // namespace

/// How (level, x, y, z) packs into a key: level above z above y above x, so keys sort by level, then row (z, y),
/// then x. axisBits is as small as the occupied span allows, which keeps the radix sort to few passes.
struct MultiResolutionGrid::Layout {
    int indexBits = 0;  ///< bits of a body index below the key in a sort item
    int axisBits = 0;
    std::uint32_t maxCoord = 0;
    std::uint32_t keyBits = 0;

    std::uint64_t pack(int level, std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
        return (static_cast<std::uint64_t>(level) << (3 * axisBits)) |
               (static_cast<std::uint64_t>(z) << (2 * axisBits)) | (static_cast<std::uint64_t>(y) << axisBits) | x;
    }
    int level(std::uint64_t key) const { return static_cast<int>(key >> (3 * axisBits)); }
    std::uint32_t x(std::uint64_t key) const { return static_cast<std::uint32_t>(key) & maxCoord; }
    std::uint32_t y(std::uint64_t key) const { return static_cast<std::uint32_t>(key >> axisBits) & maxCoord; }
    std::uint32_t z(std::uint64_t key) const { return static_cast<std::uint32_t>(key >> (2 * axisBits)) & maxCoord; }
    /// floor(u) clamped to [0, maxCoord]; monotone in u, which is all exactness needs.
    std::uint32_t cell(double u) const {
        if (!(u > 0.0)) return 0;
        if (u >= static_cast<double>(maxCoord)) return maxCoord;
        return static_cast<std::uint32_t>(u);
    }
};

MultiResolutionGrid::MultiResolutionGrid(float levelRatio)
    : levelRatio_(std::isfinite(levelRatio) ? std::max(1.5, static_cast<double>(levelRatio)) : 4.0) {}

void MultiResolutionGrid::computeStats(const Bounds& b, TaskPool& pool) {
    const std::size_t n = b.size();
    chunkStats_.resize(TaskPool::chunkCount(n, kBodyChunk));
    pool.forChunks(n, kBodyChunk, [&](std::size_t chunk, std::size_t begin, std::size_t end, int) {
        BoxRanges<simd::FloatW> wide;
        BoxRanges<float> tail;
        std::size_t i = begin;
        for (; i + simd::kLanes <= end; i += simd::kLanes) wide.add(b, i);
        for (; i < end; ++i) tail.add(b, i);
        ChunkStats s{};
        for (int a = 0; a < 3; ++a) s.centreMin[a] = tail.centreMin[a], s.centreMax[a] = tail.centreMax[a];
        s.extentMin = tail.extentMin, s.extentMax = tail.extentMax;
        s.outliers = tail.outliers + wide.outliers;
        for (std::size_t k = 0; k < simd::kLanes; ++k) {
            for (int a = 0; a < 3; ++a) {
                s.centreMin[a] = std::min(s.centreMin[a], static_cast<double>(simd::lane(wide.centreMin[a], k)));
                s.centreMax[a] = std::max(s.centreMax[a], static_cast<double>(simd::lane(wide.centreMax[a], k)));
            }
            s.extentMin = std::min(s.extentMin, static_cast<double>(simd::lane(wide.extentMin, k)));
            s.extentMax = std::max(s.extentMax, static_cast<double>(simd::lane(wide.extentMax, k)));
        }
        chunkStats_[chunk] = s;
    });
}

void MultiResolutionGrid::computeKeys(const Bounds& b, const Layout& layout, AlignedVector<std::uint64_t>& keys,
                                      TaskPool& pool) {
    const std::size_t n = b.size();
    keys.resize(n);
    const bool records = records_;
    if (records) boxes_.resize(n * kBoxStride);
    const int top = levelTotal_ - 1;
    // One bit above every cell key: outliers sort after all cells.
    const std::uint64_t outlierKey = std::uint64_t{1} << layout.keyBits;
    pool.forChunks(n, kBodyChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) {
            const float lo[3] = {b.minX[i], b.minY[i], b.minZ[i]};
            const float hi[3] = {b.maxX[i], b.maxY[i], b.maxZ[i]};
            if (records) {
                float* box = boxes_.data() + i * kBoxStride;
                box[0] = lo[0], box[1] = lo[1], box[2] = lo[2], box[3] = hi[0], box[4] = hi[1], box[5] = hi[2];
            }
            float extent;
            std::uint64_t key = outlierKey;
            if (boxExtent(lo, hi, extent)) {
                // The smallest level whose size bounds the extent (the top level's bound is the largest extent).
                int level = 0;
                while (level < top && extent > levelSize_[level]) ++level;
                std::uint32_t cell[3];
                for (int a = 0; a < 3; ++a)
                    cell[a] = layout.cell((0.5 * (double{lo[a]} + double{hi[a]}) - origin_[a]) * levelInvBin_[level]);
                key = layout.pack(level, cell[0], cell[1], cell[2]);
            }
            keys[i] = key << layout.indexBits | i;
        }
    });
}

void MultiResolutionGrid::resortChangedCells(const Layout& layout, RowContinuity continuity, TaskPool& pool) {
    const std::size_t n = items_.size();
    const int indexBits = layout.indexBits;
    const std::uint64_t indexMask = (std::uint64_t{1} << indexBits) - 1;
    const bool sameRows = continuity == RowContinuity::SameRows;
    const std::size_t chunks = TaskPool::chunkCount(n, kBodyChunk);
    chunkKept_.resize(chunks);
    chunkMoved_.resize(chunks);
    kept_.resize(n);
    moved_.resize(n);
    // 1. Last step's sorted items in order: a box whose cell is the same keeps its place relative to the others that
    //    stayed (the same key, and a row that is the same or, in cell order, the slot itself: both ascending), so
    //    each chunk's stayers are already sorted, and all of one chunk's come before the next chunk's.
    pool.forChunks(n, kBodyChunk, [&](std::size_t chunk, std::size_t begin, std::size_t end, int) {
        std::uint64_t* kept = kept_.data() + begin;
        std::uint64_t* moved = moved_.data() + begin;
        std::uint32_t keptCount = 0, movedCount = 0;
        for (std::size_t s = begin; s < end; ++s) {
            const std::uint64_t previous = items_[s];
            const std::uint64_t item = bodyKeys_[sameRows ? previous & indexMask : s];
            if ((item >> indexBits) == (previous >> indexBits))
                kept[keptCount++] = item;
            else
                moved[movedCount++] = item;
        }
        chunkKept_[chunk] = keptCount;
        chunkMoved_[chunk] = movedCount;
    });
    // 2. The boxes that changed cell, gathered and sorted alone.
    std::size_t movedTotal = 0;
    for (std::size_t c = 0; c < chunks; ++c) {
        const std::size_t begin = c * kBodyChunk;
        std::copy_n(moved_.data() + begin, chunkMoved_[c], moved_.data() + movedTotal);
        movedTotal += chunkMoved_[c];
    }
    radixSortBits(moved_.data(), movedTotal, indexBits, static_cast<int>(layout.keyBits), sortScratch_, pool);
    // 3. Merged, one chunk of stayers at a time: the changed boxes that go between a chunk's first stayer and the
    //    next chunk's are found by binary search (items are unique: they carry the row).
    chunkMovedBegin_.resize(chunks + 1);
    std::size_t movedAt = 0;
    for (std::size_t c = 0; c < chunks; ++c) {
        if (chunkKept_[c] > 0 && movedAt < movedTotal) {
            const std::uint64_t first = kept_[c * kBodyChunk];
            movedAt = static_cast<std::size_t>(
                std::lower_bound(moved_.data() + movedAt, moved_.data() + movedTotal, first) - moved_.data());
        }
        // The first chunk also takes every changed box before its first stayer.
        chunkMovedBegin_[c] = c == 0 ? 0 : static_cast<std::uint32_t>(movedAt);
    }
    chunkMovedBegin_[chunks] = static_cast<std::uint32_t>(movedTotal);
    // An empty chunk of stayers leaves its changed boxes to the next chunk's merge, so no range is taken twice.
    for (std::size_t c = chunks; c-- > 1;)
        if (chunkKept_[c] == 0) chunkMovedBegin_[c] = chunkMovedBegin_[c + 1];
    chunkKeptBegin_.resize(chunks);
    for (std::size_t c = 0, total = 0; c < chunks; total += chunkKept_[c], ++c)
        chunkKeptBegin_[c] = static_cast<std::uint32_t>(total);
    pool.forChunks(n, kBodyChunk, [&](std::size_t chunk, std::size_t begin, std::size_t, int) {
        const std::size_t keptBefore = chunkKeptBegin_[chunk];
        const std::uint64_t* k = kept_.data() + begin;
        const std::uint64_t* kEnd = k + chunkKept_[chunk];
        const std::uint64_t* m = moved_.data() + chunkMovedBegin_[chunk];
        const std::uint64_t* mEnd = moved_.data() + chunkMovedBegin_[chunk + 1];
        std::merge(k, kEnd, m, mEnd, items_.data() + keptBefore + chunkMovedBegin_[chunk]);
    });
    changedCells_ = static_cast<std::uint32_t>(movedTotal);
}

void MultiResolutionGrid::gatherAndBuildRows(const Bounds& b, const Layout& layout, std::uint32_t validCount,
                                             TaskPool& pool) {
    const std::size_t n = items_.size();
    // Padding that overlaps nothing, so a full SIMD batch can always be loaded at any slot.
    sorted_.resize(n + simd::kLanes);
    constexpr float inf = std::numeric_limits<float>::infinity();
    for (std::size_t s = n; s < n + simd::kLanes; ++s) {
        sorted_.minX[s] = sorted_.minY[s] = sorted_.minZ[s] = inf;
        sorted_.maxX[s] = sorted_.maxY[s] = sorted_.maxZ[s] = -inf;
    }
    slotBody_.resize(n);
    slotX_.resize(n);
    const int cellShift = layout.indexBits;
    const int rowShift = layout.indexBits + layout.axisBits;
    const std::uint64_t indexMask = (std::uint64_t{1} << layout.indexBits) - 1;
    const std::uint64_t* items = items_.data();
    const float* boxes = boxes_.data();
    const bool records = records_;
    const std::size_t chunks = TaskPool::chunkCount(n, kBodyChunk);
    chunkRowCount_.resize(chunks);
    chunkCells_.resize(chunks);
    chunkFarReads_.resize(chunks);
    pool.forChunks(n, kBodyChunk, [&](std::size_t chunk, std::size_t begin, std::size_t end, int) {
        std::uint32_t rows = 0, farReads = 0;
        CellRuns runs;
        std::size_t runStart = begin;
        for (std::size_t s = begin; s < end; ++s) {
            const std::uint64_t item = items[s];
            const auto i = static_cast<std::uint32_t>(item & indexMask);
            if (records) {
                // The reads are random; the prefetch overlaps their misses, one line per body.
                if (s + kGatherPrefetch < n)
                    __builtin_prefetch(boxes + (items[s + kGatherPrefetch] & indexMask) * kBoxStride);
                const float* box = boxes + std::size_t{i} * kBoxStride;
                sorted_.minX[s] = box[0], sorted_.minY[s] = box[1], sorted_.minZ[s] = box[2];
                sorted_.maxX[s] = box[3], sorted_.maxY[s] = box[4], sorted_.maxZ[s] = box[5];
            } else {
                sorted_.minX[s] = b.minX[i], sorted_.minY[s] = b.minY[i], sorted_.minZ[s] = b.minZ[i];
                sorted_.maxX[s] = b.maxX[i], sorted_.maxY[s] = b.maxY[i], sorted_.maxZ[s] = b.maxZ[i];
            }
            slotBody_[s] = i;
            slotX_[s] = layout.x(item >> cellShift);
            farReads += static_cast<std::uint32_t>(i + kNearRows < s || s + kNearRows < i);
            if (s >= validCount) continue;
            rows += static_cast<std::uint32_t>(s == 0 || (item >> rowShift) != (items[s - 1] >> rowShift));
            if (s == 0 || (item >> cellShift) != (items[s - 1] >> cellShift)) {
                if (runs.cells == 0) runs.head = static_cast<std::uint32_t>(s - begin);
                ++runs.cells;
                runStart = s;
            }
            if (runs.cells > 0) runs.maxRun = std::max(runs.maxRun, static_cast<std::uint32_t>(s + 1 - runStart));
        }
        runs.tail = runs.cells > 0 ? static_cast<std::uint32_t>(std::min<std::size_t>(end, validCount) - runStart) : 0;
        if (runs.cells == 0)
            runs.head = static_cast<std::uint32_t>(std::min<std::size_t>(end, validCount) -
                                                   std::min<std::size_t>(begin, validCount));
        chunkRowCount_[chunk] = rows;
        chunkCells_[chunk] = runs;
        chunkFarReads_[chunk] = farReads;
    });
    std::size_t farReads = 0;
    for (std::uint32_t f : chunkFarReads_) farReads += f;
    gatherWasLocal_ = 4 * farReads < n;
    // Prefix sums of the row starts; cell runs that straddle chunk boundaries are joined here.
    std::uint32_t rows = 0, cells = 0, open = 0, maxRun = 0;
    for (std::size_t c = 0; c < chunks; ++c) {
        const std::uint32_t count = chunkRowCount_[c];
        chunkRowCount_[c] = rows;
        rows += count;
        const CellRuns& runs = chunkCells_[c];
        cells += runs.cells;
        open += runs.head;
        maxRun = std::max(maxRun, open);
        if (runs.cells > 0) {
            maxRun = std::max(maxRun, runs.maxRun);
            open = runs.tail;
        }
    }
    rowCount_ = rows;
    cellCount_ = cells;
    maxBodiesPerCell_ = std::max(maxRun, open);
    rowKey_.resize(rows + 3);
    // Four ends past the last row: the three-row window starting at a sentinel row reads rowBegin[at + 3].
    rowBegin_.resize(rows + 4);
    pool.forChunks(validCount, kBodyChunk, [&](std::size_t chunk, std::size_t begin, std::size_t end, int) {
        std::uint32_t r = chunkRowCount_[chunk];
        for (std::size_t s = begin; s < end; ++s) {
            if (s == 0 || (items[s] >> rowShift) != (items[s - 1] >> rowShift)) {
                rowKey_[r] = items[s] >> rowShift;
                rowBegin_[r] = static_cast<std::uint32_t>(s);
                ++r;
            }
        }
    });
    // Sentinel rows that no search matches: they stop the cursor and the three-row window reads.
    rowKey_[rows] = rowKey_[rows + 1] = rowKey_[rows + 2] = kOutlierKey;
    rowBegin_[rows] = rowBegin_[rows + 1] = rowBegin_[rows + 2] = rowBegin_[rows + 3] = validCount;
}

void MultiResolutionGrid::buildCoarseTable(const Layout& layout, std::uint32_t validCount) {
    // Only levels above the finest occupied one are ever probed.
    if (occupiedLevelCount_ < 2) return;
    const std::uint32_t first = rowBegin_[levelRowBegin_[occupiedLevels_[1]]];
    const std::uint32_t bodies = validCount - first;
    // At most one cell per body: sized by the bodies, the table needs no counting pass.
    const std::uint64_t capacity = std::max<std::uint64_t>(16, std::bit_ceil(std::uint64_t{2} * bodies));
    tableMask_ = capacity - 1;
    tableShift_ = 64 - std::countr_zero(capacity);
    tableKey_.assign(capacity, kEmptySlot);
    tableCell_.resize(2 * capacity);
    const int cellShift = layout.indexBits;
    for (std::uint32_t s = first; s < validCount;) {
        const std::uint64_t key = items_[s] >> cellShift;
        std::uint32_t t = s + 1;
        while (t < validCount && (items_[t] >> cellShift) == key) ++t;
        std::uint64_t h = (key * 0x9E3779B97F4A7C15ull) >> tableShift_;
        while (tableKey_[h] != kEmptySlot) h = (h + 1) & tableMask_;
        tableKey_[h] = key;
        tableCell_[2 * h] = s;
        tableCell_[2 * h + 1] = t;
        s = t;
    }
}

void MultiResolutionGrid::queryRows(const Layout& layout, const PairFilter& filter, TaskPool& pool) {
    const std::uint32_t rows = rowCount_;
    const std::size_t chunkSize = rowChunkSize(rows);
    chunkOutputs_.resize(TaskPool::chunkCount(rows, chunkSize));
    const SortedView view{sorted_.minX.data(), sorted_.minY.data(), sorted_.minZ.data(), sorted_.maxX.data(),
                          sorted_.maxY.data(), sorted_.maxZ.data(), slotBody_.data()};
    const std::uint64_t* rowKey = rowKey_.data();
    const std::uint32_t* rowBegin = rowBegin_.data();
    const std::uint32_t* slotX = slotX_.data();
    const std::uint32_t maxCoord = layout.maxCoord;
    const int axisBits = layout.axisBits;
    const std::uint64_t zStep = std::uint64_t{1} << axisBits;
    const int topLevel = occupiedLevelCount_ > 0 ? occupiedLevels_[occupiedLevelCount_ - 1] : 0;
    constexpr auto lanes = static_cast<std::uint32_t>(simd::kLanes);

    const std::size_t cap = budget_.chunkCap(slotBody_.size(), chunkOutputs_.size());
    pool.forChunks(rows, chunkSize, [&](std::size_t chunk, std::size_t rBegin, std::size_t rEnd, int) {
        ChunkOutput& out = chunkOutputs_[chunk];
        const auto searchRows = [&](ChunkPairs& pairs) {
            const simd::FloatW laneIndex = simd::laneIndices<simd::FloatW>();
            auto emit = [&](std::uint32_t i, std::uint32_t j) {
                std::uint32_t a = view.body[i], b = view.body[j];
                if (a > b) std::swap(a, b);
                pairs.add({a, b}, filter.accepts(a, b));
            };
            const auto search = [&](std::uint32_t i, std::uint32_t j0, std::uint32_t j1, const std::uint32_t* x,
                                    std::uint32_t xHi) {
                forOverlapping(view, i, j0, j1, x, xHi, laneIndex, pairs, [&](std::uint32_t j) { emit(i, j); });
            };
            // What each body of the row met and kept in its own level, carried into its search of the coarser levels.
            std::vector<std::pair<std::size_t, std::size_t>>& spent = out.spent;
            // First row not below the current row's z + 1 window; the window only moves forward as rows are walked in
            // key order, so the cursor sweeps its part of the array once.
            std::uint32_t cursor = kNoCell;
            for (auto r = static_cast<std::uint32_t>(rBegin); r < rEnd; ++r) {
                const std::uint64_t rk = rowKey[r];
                const int level = static_cast<int>(rk >> (2 * axisBits));
                const auto y = static_cast<std::uint32_t>(rk) & maxCoord;
                const auto z = static_cast<std::uint32_t>(rk >> axisBits) & maxCoord;
                const std::uint32_t b = rowBegin[r], e = rowBegin[r + 1];

                // The y + 1 row directly follows in key order when it exists.
                const bool hasNext = y < maxCoord && rowKey[r + 1] == rk + 1;
                const std::uint32_t nextEnd = hasNext ? rowBegin[r + 2] : e;
                // The z + 1 rows y - 1 .. y + 1 have consecutive keys: at most three rows from the cursor on, one run
                // of slots.
                std::uint32_t g0 = r, gRows = 0;
                if (z < maxCoord) {
                    const std::uint64_t lo = rk + zStep - (y > 0 ? 1 : 0);
                    const std::uint64_t hi = rk + zStep + (y < maxCoord ? 1 : 0);
                    std::uint32_t at = cursor;
                    if (at == kNoCell) {
                        at = static_cast<std::uint32_t>(std::lower_bound(rowKey + r, rowKey + rows, lo) - rowKey);
                    } else {
                        // The window moves about one row per row, so step without branches (an exit branch per step
                        // mispredicts nearly every time) and loop only for the rare long jump; the sentinels stop it.
                        do {
                            at += static_cast<std::uint32_t>(rowKey[at] < lo);
                            at += static_cast<std::uint32_t>(rowKey[at] < lo);
                            at += static_cast<std::uint32_t>(rowKey[at] < lo);
                        } while (rowKey[at] < lo);
                    }
                    cursor = at;
                    g0 = at;
                    gRows = static_cast<std::uint32_t>(rowKey[at] <= hi) +
                            static_cast<std::uint32_t>(rowKey[at + 1] <= hi) +
                            static_cast<std::uint32_t>(rowKey[at + 2] <= hi);
                }
                const std::uint32_t gBegin = rowBegin[g0], gEnd = rowBegin[g0 + gRows];
                // A run no longer than one batch per row it spans is cheapest tested whole: the exact test discards the
                // cells outside x - 1 .. x + 1. Longer runs go row by row through x windows.
                const bool groupWhole = gEnd - gBegin <= lanes * gRows;
                // x windows: the first slot of each forward row that can still be a neighbour (x >= current x - 1).
                std::uint32_t nextAt = e;
                std::uint32_t gAt[3] = {gBegin, rowBegin[g0 + 1], rowBegin[g0 + 2]};
                std::uint32_t gTo[3] = {rowBegin[g0 + 1], rowBegin[g0 + 2], rowBegin[g0 + 3]};
                auto windowed = [&](std::uint32_t i, std::uint32_t& at, std::uint32_t to, std::uint32_t xi) {
                    while (to - at > lanes && slotX[at] + 1 < xi) ++at;
                    search(i, at, to, slotX, xi + 1);
                };
                const bool coarser = level < topLevel;
                if (coarser) spent.resize(e - b);
                for (std::uint32_t i = b; i < e; ++i) {
                    const std::uint32_t xi = slotX[i];
                    pairs.startBody();
                    if (hasNext && nextEnd - (i + 1) <= lanes) {
                        search(i, i + 1, nextEnd, nullptr, 0);
                    } else {
                        // Own row: later slots only, up to x + 1 (earlier ones found this pair already).
                        search(i, i + 1, e, slotX, xi + 1);
                        if (hasNext) windowed(i, nextAt, nextEnd, xi);
                    }
                    if (groupWhole) {
                        search(i, gBegin, gEnd, nullptr, 0);
                    } else {
                        for (std::uint32_t k = 0; k < gRows; ++k) windowed(i, gAt[k], gTo[k], xi);
                    }
                    if (coarser) spent[i - b] = {pairs.bodyOverlaps, pairs.bodyKept};
                }

                // Coarser levels: a coarse body's extent is at most its level's size and its centre is in its cell, so
                // it can only touch a fine cell's bodies if its centre lies within half a coarse cell of their union
                // box.
                if (!coarser) continue;
                for (std::uint32_t cb = b; cb < e;) {
                    std::uint32_t ce = cb + 1;
                    while (ce < e && slotX[ce] == slotX[cb]) ++ce;
                    float lo[3] = {view.minX[cb], view.minY[cb], view.minZ[cb]};
                    float hi[3] = {view.maxX[cb], view.maxY[cb], view.maxZ[cb]};
                    for (std::uint32_t i = cb + 1; i < ce; ++i) {
                        lo[0] = std::min(lo[0], view.minX[i]), hi[0] = std::max(hi[0], view.maxX[i]);
                        lo[1] = std::min(lo[1], view.minY[i]), hi[1] = std::max(hi[1], view.maxY[i]);
                        lo[2] = std::min(lo[2], view.minZ[i]), hi[2] = std::max(hi[2], view.maxZ[i]);
                    }
                    double uMin[3], uMax[3];
                    for (int a = 0; a < 3; ++a) uMin[a] = lo[a] - origin_[a], uMax[a] = hi[a] - origin_[a];
                    // The coarse cells' slot ranges first, so that each body then searches them all under its budget.
                    std::vector<std::pair<std::uint32_t, std::uint32_t>>& ranges = out.coarseRanges;
                    ranges.clear();
                    for (int li = 0; li < occupiedLevelCount_; ++li) {
                        const int coarse = occupiedLevels_[li];
                        if (coarse <= level) continue;
                        const double inv = levelInvBin_[coarse];
                        std::uint32_t qLo[3], qHi[3];
                        for (int a = 0; a < 3; ++a) {
                            qLo[a] = layout.cell(uMin[a] * inv - 0.5 - kQuerySlack);
                            qHi[a] = layout.cell(uMax[a] * inv + 0.5 + kQuerySlack);
                        }
                        for (std::uint32_t qz = qLo[2]; qz <= qHi[2]; ++qz)
                            for (std::uint32_t qy = qLo[1]; qy <= qHi[1]; ++qy)
                                for (std::uint32_t qx = qLo[0]; qx <= qHi[0]; ++qx) {
                                    const std::uint64_t probe = layout.pack(coarse, qx, qy, qz);
                                    std::uint64_t h = (probe * 0x9E3779B97F4A7C15ull) >> tableShift_;
                                    while (tableKey_[h] != probe && tableKey_[h] != kEmptySlot)
                                        h = (h + 1) & tableMask_;
                                    if (tableKey_[h] == kEmptySlot) continue;
                                    ranges.emplace_back(tableCell_[2 * h], tableCell_[2 * h + 1]);
                                }
                    }
                    for (std::uint32_t i = cb; i < ce; ++i) {
                        std::tie(pairs.bodyOverlaps, pairs.bodyKept) = spent[i - b];
                        for (const auto& [jb, je] : ranges) search(i, jb, je, nullptr, 0);
                    }
                    cb = ce;
                }
            }
        };
        out.pairs.clear();
        ChunkPairs exact{out.pairs, cap, budget_.overlapsPerBody};
        searchRows(exact);
        out.dropped = exact.dropped;
        if (exact.dropped == 0) return;
        // Past the budget: search again with the cap shared evenly, so that a pile's pairs spread over its bodies.
        out.pairs.clear();
        const std::size_t bodies = rowBegin[rEnd] - rowBegin[rBegin];
        ChunkPairs shared{out.pairs, cap, budget_.overlapsPerBody, std::max<std::size_t>(1, cap / bodies)};
        searchRows(shared);
        out.dropped = shared.dropped;
    });
}

void MultiResolutionGrid::queryOutliers(std::uint32_t validCount, const PairFilter& filter,
                                        std::vector<BodyPair>& out) const {
    // Boxes with an infinite or NaN bound (refused at the API, so only ever seen from a bug upstream) have no
    // cell; overlaps() alone decides them against every other box.
    for (std::uint32_t o = validCount; o < slotBody_.size(); ++o)
        for (std::uint32_t s = 0; s < o; ++s)
            if (overlaps(sorted_, o, sorted_, s)) {
                std::uint32_t a = slotBody_[o], b = slotBody_[s];
                if (a > b) std::swap(a, b);
                if (filter.accepts(a, b)) out.push_back({a, b});
            }
}

bool MultiResolutionGrid::layoutStillFits(std::uint32_t n, std::uint32_t outliers, double extentMax,
                                          const double (&centreMin)[3], const double (&centreMax)[3]) const {
    if (n != lastCount_ || outliers > 0 || lastHadOutliers_ || cellAxisBits_ == 0) return false;
    const double top = levelSize_[levelTotal_ - 1];
    // Boxes that shrank to under half the top level would be binned in cells too coarse for them.
    if (!(extentMax <= top) || extentMax < 0.5 * top) return false;
    const double reach = static_cast<double>((1u << cellAxisBits_) - 1);
    for (int a = 0; a < 3; ++a)
        if (!(centreMin[a] >= origin_[a]) || !((centreMax[a] - origin_[a]) * levelInvBin_[0] < reach)) return false;
    return true;
}

void MultiResolutionGrid::findPairs(const Bounds& bounds, const PairFilter& filter, TaskPool& pool,
                                    std::vector<BodyPair>& out, RowContinuity continuity) {
    out.clear();
    droppedPairs_ = 0;
    const std::uint32_t n = bounds.size();
    occupiedLevelCount_ = 0;
    cellCount_ = 0;
    rowCount_ = 0;
    maxBodiesPerCell_ = 0;

    // 1. Size range and origin.
    computeStats(bounds, pool);
    constexpr double inf = std::numeric_limits<double>::infinity();
    double centreMin[3] = {inf, inf, inf}, centreMax[3] = {-inf, -inf, -inf};
    double extentMin = inf, extentMax = 0.0;
    std::uint32_t outliers = 0;
    for (const ChunkStats& s : chunkStats_) {
        for (int a = 0; a < 3; ++a)
            centreMin[a] = std::min(centreMin[a], s.centreMin[a]),
            centreMax[a] = std::max(centreMax[a], s.centreMax[a]);
        extentMin = std::min(extentMin, s.extentMin);
        extentMax = std::max(extentMax, s.extentMax);
        outliers += s.outliers;
    }
    const std::uint32_t validCount = n - outliers;

    // Levels from the largest box down: boxes of one kind whose fattening differs a little (S4's spheres) share
    // one level whose cells fit them tightly; anchoring at the smallest box would push most of them one level up,
    // into cells `ratio` times too large.
    Layout layout;
    layout.indexBits = n > 1 ? static_cast<int>(std::bit_width(n - 1)) : 1;
    const bool large = n >= kIncrementalFrom;
    incremental_ =
        continuity != RowContinuity::None && large && layoutStillFits(n, outliers, extentMax, centreMin, centreMax);
    if (incremental_) {
        layout.axisBits = cellAxisBits_;
        layout.maxCoord = (1u << layout.axisBits) - 1;
        layout.keyBits = static_cast<std::uint32_t>(3 * layout.axisBits + lastLevelBits_);
    } else if (validCount > 0) {
        levelTotal_ = 1;
        // A large grid's layout is kept while it fits, so it gets room: a top level a little above the largest box,
        // and a span a little beyond the centres.
        const double top = (extentMax > 0.0 ? extentMax : 1.0) * (large ? 1.0 + kExtentRoom : 1.0);
        double size = top;  // all points: any cell size works
        while (levelTotal_ < kMaxLevels && size / levelRatio_ >= extentMin && size / levelRatio_ > 0.0) {
            size /= levelRatio_;
            ++levelTotal_;
        }
        levelSize_[levelTotal_ - 1] = top;
        for (int l = levelTotal_ - 2; l >= 0; --l) levelSize_[l] = levelSize_[l + 1] / levelRatio_;
        for (int l = 0; l < levelTotal_; ++l) levelInvBin_[l] = 1.0 / (levelSize_[l] * (1.0 + kBinMargin));
        double span = 0.0;
        for (int a = 0; a < 3; ++a) {
            const double room =
                large ? std::max(kSpanRoom * (centreMax[a] - centreMin[a]), kOriginRoomCells * levelSize_[0]) : 0.0;
            origin_[a] = centreMin[a] - room;
            span = std::max(span, (centreMax[a] - centreMin[a] + 2.0 * room) * levelInvBin_[0]);
        }
        // The key, one outlier bit above it and the body index share one 64-bit sort item.
        const int levelBits = static_cast<int>(std::bit_width(static_cast<std::uint32_t>(levelTotal_ - 1)));
        const int axisLimit = std::min(kMaxAxisBits, (64 - layout.indexBits - levelBits - 1) / 3);
        const double maxCoord = std::min(span, static_cast<double>((1u << axisLimit) - 1));
        layout.axisBits = static_cast<int>(std::bit_width(static_cast<std::uint32_t>(maxCoord)));
        layout.maxCoord = (1u << layout.axisBits) - 1;
        layout.keyBits = static_cast<std::uint32_t>(3 * layout.axisBits + levelBits);
        lastLevelBits_ = levelBits;
    } else {
        levelTotal_ = 1;
        lastLevelBits_ = 0;
    }

    cellAxisBits_ = layout.axisBits;
    cellIndexBits_ = layout.indexBits;
    validCount_ = validCount;
    lastCount_ = n;
    lastHadOutliers_ = outliers > 0;
    records_ = n >= kRecordsFrom && !gatherWasLocal_;

    // 2-4. Keys, sort, gather, rows. Equal keys keep index order (the sort is stable, the merge compares the
    // index too), so slots are deterministic.
    if (incremental_) {
        computeKeys(bounds, layout, bodyKeys_, pool);
        resortChangedCells(layout, continuity, pool);
    } else {
        computeKeys(bounds, layout, items_, pool);
        radixSortBits(items_.data(), n, layout.indexBits, static_cast<int>(layout.keyBits) + (outliers > 0 ? 1 : 0),
                      sortScratch_, pool);
        changedCells_ = n;
    }
    gatherAndBuildRows(bounds, layout, validCount, pool);
    const int rowLevelShift = 2 * layout.axisBits;
    for (int l = 0; l <= levelTotal_; ++l)
        levelRowBegin_[l] =
            l == levelTotal_
                ? rowCount_
                : static_cast<std::uint32_t>(std::lower_bound(rowKey_.begin(), rowKey_.begin() + rowCount_,
                                                              static_cast<std::uint64_t>(l) << rowLevelShift) -
                                             rowKey_.begin());
    for (int l = 0; l < levelTotal_; ++l)
        if (levelRowBegin_[l] < levelRowBegin_[l + 1]) occupiedLevels_[occupiedLevelCount_++] = l;
    buildCoarseTable(layout, validCount);

    // 5-6. Pairs, concatenated in chunk order.
    queryRows(layout, filter, pool);
    std::size_t total = 0;
    droppedPairs_ = 0;
    for (const ChunkOutput& c : chunkOutputs_) total += c.pairs.size(), droppedPairs_ += c.dropped;
    out.reserve(total);
    for (const ChunkOutput& c : chunkOutputs_) out.insert(out.end(), c.pairs.begin(), c.pairs.end());
    queryOutliers(validCount, filter, out);
}

}  // namespace rubble::detail
