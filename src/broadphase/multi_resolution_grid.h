#pragma once
// Multi-resolution grid broad phase (Millington's multi-resolution map, Mirtich's hierarchical hash grid).
//
// Levels whose cell sizes grow by a fixed ratio hold the bodies; each body lives in the one level whose cell size
// is the smallest that is not below its largest extent, in the cell that holds its centre. Two bodies of one level
// can then only overlap if their cells are neighbours, and a body can only overlap a coarser body whose centre lies
// within half a coarse cell of its box. A step:
//   1. one parallel pass finds the size range and the origin (smallest centre), which fix the levels;
//   2. a parallel pass packs every body's (level, z, y, x) cell into a key, coordinates relative to the origin, so
//      the world needs no bounds, and copies its box into one 32-byte record (so that step 4 misses the cache
//      once per body rather than once per bound, when the bounds outgrow the cache);
//   3. the shared parallel radix sort orders (key << indexBits | index) words: cells become runs of slots, rows
//      (level, z, y) runs of cells;
//   4. the boxes are gathered into that order, so every inner loop reads contiguous SoA lanes;
//   5. same-level pairs come from the row itself and its four forward rows (y + 1; and y - 1 .. y + 1 at z + 1: the
//      half-neighbourhood, each pair of neighbouring rows is visited from exactly one side), restricted to cells
//      x - 1 .. x + 1. Almost every cell holds one body in sparse scenes, so the work is organised per row, not
//      per cell: the z + 1 rows have consecutive keys and so are one contiguous run of slots, as are the rest of
//      the own row and the y + 1 row; a run shorter than one SIMD batch per row is tested whole (the exact test
//      discards the cells outside x - 1 .. x + 1), a longer one row by row through forward-moving x windows. The
//      forward rows are found by one cursor that only moves forward as rows are walked in key order;
//   6. pairs with coarser levels come from an open-addressing hash table (cell key -> slot range) over the coarse
//      cells, probed with each fine cell's box grown by half a coarse cell.
// Every candidate is decided by the exact overlaps() predicate, so the grid only ever costs time, never pairs.
// Work is split in chunks whose bounds depend only on counts, and chunk outputs are concatenated in chunk order,
// so the result does not depend on the thread count.
#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "broadphase/broadphase.h"
#include "broadphase/radix_sort.h"
#include "storage/aligned_vector.h"

namespace rubble::detail {

class TaskPool;

/// What the caller knows of the boxes' rows since the grid's last findPairs.
enum class RowContinuity : std::uint8_t {
    None,         ///< rows were added, removed or moved otherwise
    SameRows,     ///< every row holds the same body's box as in the last call
    InCellOrder,  ///< the rows were put in the last call's cell order (boxesInCellOrder()) and nothing else changed
};

class MultiResolutionGrid {
public:
    /// Levels cover sizes from the largest box down by factors of levelRatio, at most this many of them; boxes
    /// smaller than the finest cell share it (still exact, only slower). 4^14 spans any sane size range.
    static constexpr int kMaxLevels = 15;

    /// levelRatio: growth of the cell size from one level to the next (clamped to >= 1.5).
    explicit MultiResolutionGrid(float levelRatio = 4.0f);

    /// Appends to `out` (cleared first) every pair a < b of boxes that overlap and that the filter accepts, each
    /// once. Not sorted; identical for every thread count. With `continuity`, a large grid whose layout still fits
    /// re-sorts only the boxes that changed cell since the last call; the pairs are the same either way.
    void findPairs(const Bounds& bounds, const PairFilter& filter, TaskPool& pool, std::vector<BodyPair>& out,
                   RowContinuity continuity = RowContinuity::None);
    /// Pairs the last findPairs found past the pair budget and did not keep.
    std::uint64_t droppedPairs() const { return droppedPairs_; }
    void setPairBudget(PairBudget budget) { budget_ = budget; }
    /// Boxes that changed cell in the last findPairs, when it re-sorted only those (else every box was sorted).
    std::uint32_t changedCells() const { return changedCells_; }
    /// Whether the last findPairs re-sorted only the boxes that changed cell.
    bool lastSortWasIncremental() const { return incremental_; }

    /// The boxes of the last findPairs in cell order (level, z, y, x; boxes with a non-finite bound last): boxes
    /// that are near in space are near in this order. A permutation of 0 .. size - 1 of that call's boxes.
    const AlignedVector<std::uint32_t>& boxesInCellOrder() const { return slotBody_; }
    /// Levels that held at least one body in the last findPairs.
    int levelCount() const { return occupiedLevelCount_; }
    /// Cells that held at least one body in the last findPairs.
    std::uint32_t cellCount() const { return cellCount_; }
    /// Most bodies in one cell in the last findPairs (a measure of how well the levels fit the sizes).
    std::uint32_t maxBodiesPerCell() const { return maxBodiesPerCell_; }
    /// Cell size of the i-th occupied level (finest first), i < levelCount().
    float levelCellSize(int i) const { return static_cast<float>(levelSize_[occupiedLevels_[i]]); }

    /// One occupied cell of the last findPairs, for debug drawing. `level` counts from the finest level of that
    /// step's set-up (levels that held no body included), so one level keeps its number while bodies come and go.
    struct CellBox {
        int level = 0;
        double min[3] = {0, 0, 0};
        double max[3] = {0, 0, 0};
    };
    /// Calls visit(const CellBox&) for every cell that held a body in the last findPairs, in key order (level, then
    /// z, y, x), until visit returns false. A cell is the region of centres binned into it, so it spans one binning
    /// cell (the level's size times 1 + 1e-6); the far-edge cell of a world wider than 2^20 finest cells also holds
    /// the clamped centres beyond it. Reads what the step left: no work is added to the step.
    template <class Visit>
    void forEachCell(Visit&& visit) const {
        const std::uint32_t valid = std::min<std::uint32_t>(validCount_, static_cast<std::uint32_t>(items_.size()));
        const std::uint32_t maxCoord = (1u << cellAxisBits_) - 1;
        for (std::uint32_t s = 0; s < valid; ++s) {
            const std::uint64_t key = items_[s] >> cellIndexBits_;
            if (s > 0 && key == (items_[s - 1] >> cellIndexBits_)) continue;
            const std::uint32_t coord[3] = {static_cast<std::uint32_t>(key) & maxCoord,
                                            static_cast<std::uint32_t>(key >> cellAxisBits_) & maxCoord,
                                            static_cast<std::uint32_t>(key >> (2 * cellAxisBits_)) & maxCoord};
            CellBox cell;
            cell.level = static_cast<int>(key >> (3 * cellAxisBits_));
            const double size = 1.0 / levelInvBin_[cell.level];
            for (int a = 0; a < 3; ++a) {
                cell.min[a] = origin_[a] + coord[a] * size;
                cell.max[a] = origin_[a] + (coord[a] + 1.0) * size;
            }
            if (!visit(static_cast<const CellBox&>(cell))) return;
        }
    }

private:
    /// What one chunk of bodies contributes to the level set-up (finite boxes only).
    struct ChunkStats {
        double centreMin[3];
        double centreMax[3];
        double extentMin;
        double extentMax;
        std::uint32_t outliers;  ///< boxes whose float centre or extent is not finite
    };
    /// What one chunk of rows found.
    struct ChunkOutput {
        std::vector<BodyPair> pairs;
        std::uint64_t dropped = 0;
        // Scratch of the coarse-level search: what a row's bodies met and kept in their own level (overlaps, pairs),
        // a cell's ranges.
        std::vector<std::pair<std::size_t, std::size_t>> spent;
        std::vector<std::pair<std::uint32_t, std::uint32_t>> coarseRanges;
    };
    /// Cell starts of one chunk of slots, for the cell statistics: runs that straddle chunks are joined afterwards.
    struct CellRuns {
        std::uint32_t cells = 0;   ///< cells starting in the chunk
        std::uint32_t head = 0;    ///< slots before the first start (they continue the previous chunk's run)
        std::uint32_t tail = 0;    ///< slots of the last run started in the chunk
        std::uint32_t maxRun = 0;  ///< longest run started in the chunk, cut at its end
    };
    struct Layout;

    void computeStats(const Bounds& bounds, TaskPool& pool);
    /// Whether the last call's layout still holds these boxes: every box within the top level's size (which keeps
    /// the grid exact) and every centre inside the keyed span (which keeps cells from crowding at its edge).
    bool layoutStillFits(std::uint32_t n, std::uint32_t outliers, double extentMax, const double (&centreMin)[3],
                         const double (&centreMax)[3]) const;
    void computeKeys(const Bounds& bounds, const Layout& layout, AlignedVector<std::uint64_t>& keys, TaskPool& pool);
    /// items_ holds last call's sorted items and bodyKeys_ this call's, in row order: sorts the items of the boxes
    /// that changed cell and merges them with the rest into items_.
    void resortChangedCells(const Layout& layout, RowContinuity continuity, TaskPool& pool);
    void gatherAndBuildRows(const Bounds& bounds, const Layout& layout, std::uint32_t validCount, TaskPool& pool);
    void buildCoarseTable(const Layout& layout, std::uint32_t validCount);
    void queryRows(const Layout& layout, const PairFilter& filter, TaskPool& pool);
    void queryOutliers(std::uint32_t validCount, const PairFilter& filter, std::vector<BodyPair>& out) const;

    double levelRatio_;

    // Per-step level set-up (finest level first).
    int levelTotal_ = 0;
    std::array<double, kMaxLevels> levelSize_{};    ///< bound on the extent of the level's boxes
    std::array<double, kMaxLevels> levelInvBin_{};  ///< 1 / binning cell size (slightly larger than levelSize_)
    std::array<int, kMaxLevels> occupiedLevels_{};
    std::array<std::uint32_t, kMaxLevels + 1> levelRowBegin_{};  ///< first row of each level, by level
    int occupiedLevelCount_ = 0;
    double origin_[3] = {0, 0, 0};

    // Member buffers, reused every step so that a warmed-up grid does not allocate.
    std::vector<ChunkStats> chunkStats_;
    AlignedVector<float> boxes_;          ///< 8 floats per body (min xyz, max xyz, 2 unused), body order
    AlignedVector<std::uint64_t> items_;  ///< key << indexBits | body, sorted
    RadixSortScratch sortScratch_;
    Bounds sorted_;                          ///< boxes in slot order, padded by a SIMD batch for tail loads
    AlignedVector<std::uint32_t> slotBody_;  ///< body index of each slot
    AlignedVector<std::uint32_t> slotX_;     ///< x cell of each slot
    std::vector<std::uint32_t> chunkRowCount_;
    std::vector<std::uint32_t> chunkFarReads_;  ///< per chunk of the gather: reads far from their slot
    bool records_ = false;                      ///< this call copies boxes into records for the gather
    bool gatherWasLocal_ = false;               ///< the last gather read mostly near its slots
    std::vector<CellRuns> chunkCells_;
    AlignedVector<std::uint64_t> rowKey_;     ///< (level, z, y) of each row, then sentinels
    AlignedVector<std::uint32_t> rowBegin_;   ///< first slot of each row; rowBegin_[rowCount_] = valid slots
    AlignedVector<std::uint64_t> tableKey_;   ///< coarse cell keys
    AlignedVector<std::uint32_t> tableCell_;  ///< first and end slot of each coarse cell, two per table entry
    std::uint64_t tableMask_ = 0;
    int tableShift_ = 64;
    std::vector<ChunkOutput> chunkOutputs_;
    std::uint64_t droppedPairs_ = 0;
    PairBudget budget_;
    // The incremental re-sort: this call's items in row order, the stayers and movers of each chunk.
    AlignedVector<std::uint64_t> bodyKeys_;
    AlignedVector<std::uint64_t> kept_;
    AlignedVector<std::uint64_t> moved_;
    std::vector<std::uint32_t> chunkKept_, chunkKeptBegin_, chunkMoved_, chunkMovedBegin_;
    std::uint32_t changedCells_ = 0;
    bool incremental_ = false;
    std::uint32_t lastCount_ = 0;  ///< boxes in the last call, and whether any was an outlier
    bool lastHadOutliers_ = false;
    int lastLevelBits_ = 0;

    std::uint32_t rowCount_ = 0;
    std::uint32_t cellCount_ = 0;
    std::uint32_t maxBodiesPerCell_ = 0;
    // How the last findPairs packed cell keys, kept for forEachCell.
    int cellAxisBits_ = 0;
    int cellIndexBits_ = 0;
    std::uint32_t validCount_ = 0;
};

}  // namespace rubble::detail
