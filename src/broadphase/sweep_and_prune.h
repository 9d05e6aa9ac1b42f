#pragma once
// Sweep-and-prune over the moving bodies' boxes: sort the boxes by their minimum on one axis, then each box scans
// forward through the boxes that start before it ends and tests the two other axes, many candidates per SIMD
// instruction. Exact (every overlapping pair once, none twice) and independent of the thread count.
//
// Temporal coherence: the sorted order is kept between steps as stable slots, so a step in which bodies moved a
// little re-sorts by insertion in O(n + moves), and bodies added or removed since the last step are merged in or
// dropped without starting over. A new sweep axis or a large disorder falls back to a parallel radix sort.
#include <cstdint>
#include <vector>

#include "broadphase/broadphase.h"
#include "broadphase/radix_sort.h"
#include "storage/aligned_vector.h"

namespace rubble::detail {

class TaskPool;

class SweepAndPrune {
public:
    /// Replaces out with every pair (a < b, dense indices) of boxes that overlap and that filter accepts. out is not
    /// sorted, but it is the same for any thread count. slotOfDense[i] < slotCount is the stable slot of dense
    /// body i: the same body keeps its slot across calls while its dense index may change.
    void findPairs(const Bounds& bounds, const std::uint32_t* slotOfDense, std::uint32_t slotCount,
                   const PairFilter& filter, TaskPool& pool, std::vector<BodyPair>& out);

    /// Pairs the last call found past the pair budget and did not keep.
    std::uint64_t droppedPairs() const { return droppedPairs_; }
    void setPairBudget(PairBudget budget) { budget_ = budget; }

    /// Axis swept by the last call (0 = x, 1 = y, 2 = z), -1 before the first.
    int lastAxis() const { return axis_; }
    /// Whether the last call re-sorted the kept order by insertion (true) or radix-sorted from scratch (false).
    bool lastUsedInsertionSort() const { return usedInsertion_; }
    /// Element moves the last insertion pass made (0 after a radix sort).
    std::uint64_t lastInsertionMoves() const { return insertionMoves_; }

    /// Runs the sweep with the scalar form of the kernel: the reference the SIMD form is tested against.
    void useScalarKernel(bool scalar) { scalarKernel_ = scalar; }

    /// Forgets the kept order (buffers stay allocated): the next call sorts from scratch.
    void reset();

private:
    bool sortByInsertion(const float* minAxis, const std::uint32_t* slotOfDense, std::uint32_t slotCount,
                         std::uint32_t n, TaskPool& pool);
    void sortByRadix(const float* minAxis, std::uint32_t n, TaskPool& pool);
    void gatherSorted(const Bounds& bounds, TaskPool& pool);
    void sweep(const PairFilter& filter, TaskPool& pool, std::vector<BodyPair>& out);

    int axis_ = -1;
    bool usedInsertion_ = false;
    bool scalarKernel_ = false;
    std::uint64_t insertionMoves_ = 0;

    // State carried to the next step: the sorted order as dense indices (denseOfSorted_, below) and the slot of
    // each dense index, which together name last step's order by slot. Everything else is scratch.
    AlignedVector<std::uint32_t> prevSlotOfDense_;
    // Per slot: dense index this step, or a marker for "not present" / "already placed by the kept order".
    std::vector<std::uint32_t> denseOfSlot_;  ///< kAbsent between calls
    // The same for a few bodies among many slots: (slot << 32 | dense index) sorted, and each one's marker.
    std::vector<std::uint64_t> slotTable_;
    std::vector<std::uint32_t> slotMarks_;

    // Sort items: sortable key of the box minimum << 32 | dense index. Ordering the packed integer orders by
    // (minimum, dense index), a total order, so insertion and radix sorts produce the same sequence.
    AlignedVector<std::uint64_t> items_;
    AlignedVector<std::uint64_t> newItems_;
    AlignedVector<std::uint64_t> merged_;
    RadixSortScratch radix_;

    // The boxes in sorted order (padded with NaN so that full-width loads past the end never match): the sweep
    // reads these contiguously. axis* is the swept axis, u/v the two others.
    AlignedVector<float> axisMin_, axisMax_, uMin_, uMax_, vMin_, vMax_;
    AlignedVector<std::uint32_t> denseOfSorted_;

    std::vector<std::vector<BodyPair>> chunkPairs_;
    std::vector<std::uint64_t> chunkDropped_;
    std::uint64_t droppedPairs_ = 0;
    PairBudget budget_;
    std::vector<double> chunkMoments_;
    std::vector<std::uint32_t> chunkCounts_;
    std::vector<std::size_t> pairOffsets_;
};

}  // namespace rubble::detail
