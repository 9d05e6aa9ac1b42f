#pragma once
// The pairs whose kernels run in SIMD lanes (sphere-sphere, sphere-box, sphere-capsule, capsule-capsule, box-box),
// a block at a time: each side's pose, size and motion gathered lane-wide into SoA input lanes, the speculative
// margins computed in lanes, then the kernel over the block.
#include <cstdint>
#include <vector>

#include "narrowphase/pair_jobs.h"
#include "narrowphase/pair_sides.h"

namespace rubble::detail {

/// Pairs the batched kernels take at a time: four SIMD batches at AVX2's width, so that their lanes and manifolds
/// stay in L1.
inline constexpr std::size_t kBatchBlock = 64;

/// Input lanes of a block: per side the shape's pose and size (ten lanes), then each pair's margin
/// (batched_pairs.cpp).
inline constexpr std::size_t kBatchInputLanes = 21;

/// A worker's lists and lanes for the batched kernels.
struct BatchScratch {
    /// Jobs of the chunk for each batched kernel.
    std::vector<std::uint32_t> jobs[static_cast<int>(BatchedKernel::Count)];
    alignas(64) float in[kBatchInputLanes][kBatchBlock];
    /// Results of the closed-form kernels: normal xyz, point xyz, depth, second point xyz, depth.
    alignas(64) float out[11][kBatchBlock];
    alignas(64) std::uint32_t feature[2][kBatchBlock];
    alignas(64) std::int32_t count[kBatchBlock];
};

/// Where the batched kernels read their pairs' sides.
struct BatchSources {
    const BodyStorage& storage;
    const MovingRows& rows;
    const std::vector<Shape>& shapes;
    const ShapeTables& tables;
    float margin;  ///< the fixed contact margin
    float dt;      ///< the step the speculative margins cover
};

/// The chunk's jobs in scratch.jobs[kernel] through that kernel; each job's manifold is written in
/// chunk.manifolds.
void collideBatched(BatchedKernel kernel, NarrowChunk& chunk, BatchScratch& scratch, const BatchSources& sources);

}  // namespace rubble::detail
