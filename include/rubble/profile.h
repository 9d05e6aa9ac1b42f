#pragma once
#include <array>
#include <cstdint>
#include <string_view>

#include "rubble/settings.h"

namespace rubble {

/// The stages of a step, in data order. Only stages that exist are listed; later stages join this list.
enum class Stage : std::uint8_t {
    IntegrateVelocities,
    UpdateBounds,
    BroadPhase,
    NarrowPhase,
    ContactCache,
    Islands,
    Solver,
    IntegratePositions,
    Ccd,     ///< continuous collision, only with Effect::ContinuousCollision
    Events,  ///< contact and sensor events, only while a body asks for them (BodyDef::contactEvents, ::sensor)
    Count,
};
inline constexpr int kStageCount = static_cast<int>(Stage::Count);

/// Stage name shared by the runner's table, the trace and the benchmark counters.
std::string_view stageName(Stage s);

struct StageTiming {
    bool ran = false;
    double beginUs = 0;  ///< microseconds since the world was created
    double ms = 0;       ///< wall time of the stage
};

/// Timings and counts of one step.
struct Profile {
    std::uint64_t stepIndex = 0;
    double beginUs = 0;  ///< microseconds since the world was created
    double stepMs = 0;
    std::array<StageTiming, kStageCount> stages{};
    EffectSet effects;              ///< effects that were simulated in this step
    std::uint32_t bodyCount = 0;    ///< bodies in the world, static ones included
    std::uint32_t movingCount = 0;  ///< dynamic and kinematic bodies
    std::uint32_t frozenCount = 0;  ///< bodies frozen in this step: state non-finite, or leaving the coordinate limit
    BroadPhaseKind broadPhase = BroadPhaseKind::Auto;  ///< algorithm that found the moving pairs (Auto: none ran)
    std::uint32_t movingPairs = 0;                     ///< candidate pairs of two moving bodies
    /// Candidate pairs of two moving bodies past the pair budget, dropped or left untested (docs/limits.md: bodies
    /// piled onto one point; an upper bound on the overlaps lost); 0 in any scene the budget is meant for. The
    /// runner warns when it is not.
    std::uint64_t droppedPairs = 0;
    /// Static bodies and mesh triangles near moving bodies past the static budget and dropped (docs/limits.md: static
    /// bodies piled onto one point); 0 in any scene the budget is meant for. The runner warns when it is not.
    std::uint64_t droppedStaticHits = 0;
    std::uint32_t staticPairs = 0;    ///< candidate pairs of a moving and a static body (meshes excluded)
    std::uint32_t meshPairs = 0;      ///< moving bodies against static meshes and heightfields
    std::uint32_t meshTriangles = 0;  ///< triangles handed over with the mesh pairs
    std::uint32_t manifolds = 0;      ///< contact manifolds (touching or speculative pairs)
    std::uint32_t contactPoints = 0;
    std::uint32_t reusedManifolds = 0;    ///< manifolds moved with their bodies rather than computed again
    std::uint32_t matchedManifolds = 0;   ///< manifolds that continue one of the previous step (same pair and parts)
    std::uint32_t warmStartedPoints = 0;  ///< points whose feature matched: they start from last step's impulses
    std::uint32_t seededManifolds = 0;    ///< new manifolds started from the loads that hold their bodies at rest
    std::uint32_t constraints = 0;        ///< contact manifolds the solver works on (a dynamic body on one side)
    std::uint32_t colors = 0;             ///< graph colours of the contact constraints (most in any one block)
    std::uint32_t solverBlocks = 0;       ///< blocks of small islands, each solved whole by one task
    std::uint32_t largeIslandConstraints = 0;  ///< constraints of islands solved colour by colour across threads
    float laneOccupancy = 0;                   ///< filled SIMD lanes over lanes used by the solver, in [0, 1]
    std::uint32_t joints = 0;        ///< joints that acted in this step (unbroken; zero when joints did not run)
    std::uint32_t brokenJoints = 0;  ///< joints that broke in this step
    /// Colours of the large islands' joints, each run across the threads (0: they ran serially, being few).
    std::uint32_t jointColours = 0;
    std::uint32_t batchedJoints = 0;  ///< of those joints, ball joints solved in SIMD lanes
    /// Time of the joint solver's work inside the solver stage (rows, warm start, iterations), ms; the iterations of
    /// joints in blocks of small islands run in the blocks' tasks, and their time is summed over the threads.
    double jointMs = 0;
    std::uint32_t islands = 0;  ///< islands of dynamic bodies that touch or are jointed to something, asleep included
    std::uint32_t largestIsland = 0;   ///< bodies in the largest island
    std::uint32_t sleepingBodies = 0;  ///< bodies asleep after the step
    std::uint32_t ccdBodies = 0;       ///< fast bodies swept by continuous collision (Stage::Ccd)
    std::uint32_t ccdHits = 0;         ///< of those, bodies moved back to their time of impact
    std::uint32_t sensorPairs = 0;     ///< pairs a sensor takes part in, kept out of the solver (Stage::Events)
    std::uint32_t events = 0;          ///< contact and sensor events the step reported

    const StageTiming& operator[](Stage s) const { return stages[static_cast<int>(s)]; }
    StageTiming& operator[](Stage s) { return stages[static_cast<int>(s)]; }
};

}  // namespace rubble
