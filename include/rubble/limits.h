#pragma once
// Every limit Rubble has, in one place. The World refuses input outside them (rubble::Error naming the call, the
// field and the limit) and the scene loader refuses files that cross them (naming the file and the JSON path), with
// these same numbers. docs/limits.md says why each one is where it is.
#include <cstddef>
#include <cstdint>

namespace rubble::limits {

// Settings.
inline constexpr int kMaxSubsteps = 64;
inline constexpr int kMaxIterations = 1000;  ///< velocity and position iterations each
inline constexpr int kMaxThreads = 1024;
inline constexpr float kMinTimeStep = 1e-5f;  ///< s (World::step's dt and WorldSettings::timeStep)
inline constexpr float kMaxTimeStep = 1.0f;   ///< s

// Bodies and shapes.
inline constexpr float kMinShapeSize = 1e-4f;  ///< m: radii, half extents, a hull's or mesh's extent
inline constexpr float kMaxShapeSize = 1e4f;   ///< m
inline constexpr float kMinDensity = 1e-3f;    ///< kg/m^3
inline constexpr float kMaxDensity = 1e6f;     ///< kg/m^3
inline constexpr float kMaxCoordinate = 1e5f;  ///< m: |x|, |y|, |z| of body positions and mesh vertices
inline constexpr std::uint32_t kMaxBodies = 1u << 24;
inline constexpr std::uint32_t kMaxHullVertices = 4096;
inline constexpr std::uint32_t kMaxHullFaceSides = 32;
inline constexpr std::uint32_t kMaxCompoundChildren = 65535;
inline constexpr std::uint64_t kMaxMeshTriangles = std::uint64_t{1} << 24;  ///< meshes and heightfields each

// The step.
/// Candidate pairs of moving bodies: each chunk of the broad phase's search keeps at most kPairsPerBody times its
/// share of the bodies, and at least kMinChunkPairs; pairs past that are dropped and counted (Profile::droppedPairs).
/// Once a chunk has kept its share, each body's search in it stops after meeting kSearchOverlapsPerBody overlapping
/// boxes (those the filter rejects included), and what it leaves untested is counted as dropped.
inline constexpr std::size_t kPairsPerBody = 32;
inline constexpr std::size_t kMinChunkPairs = 16384;
inline constexpr std::size_t kSearchOverlapsPerBody = 256;
/// Static candidates near moving bodies (static bodies and mesh or heightfield triangles in each body's query box):
/// each chunk of the static query keeps at most kStaticHitsPerBody times its bodies, and at least
/// kMinChunkStaticHits; the rest are dropped and counted (Profile::droppedStaticHits).
inline constexpr std::size_t kStaticHitsPerBody = 64;
inline constexpr std::size_t kMinChunkStaticHits = 65536;

// Files (the scene loader).
inline constexpr std::uint64_t kMaxSceneFileBytes = std::uint64_t{1} << 28;  ///< 256 MiB
inline constexpr std::uint64_t kMaxObjFileBytes = std::uint64_t{1} << 30;    ///< 1 GiB
inline constexpr std::uint64_t kMaxSceneBodies = kMaxBodies;                 ///< explicit and generated
inline constexpr long kMaxRunnerSteps = 100'000'000;                         ///< rubble run --steps

}  // namespace rubble::limits
