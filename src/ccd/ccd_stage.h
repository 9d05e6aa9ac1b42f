#pragma once
// Continuous-collision stage (Effect::ContinuousCollision): after the step's last substep, every fast body is swept
// from where it started the step to where it ended, and one that would have passed into or through static geometry
// (static bodies, mesh and heightfield triangles) goes back to its first time of impact (ccd/time_of_impact.h). It
// keeps its velocity, as in Box2D: next step's speculative contacts, which now see the surface, stop it. Bullets
// (BodyDef::bullet) are swept against the dynamic bodies too, at the poses those ended the step in.
//
// Fast: moved more in the step (translation, plus turn times reach) than half its smallest extent, Box2D's test;
// speculative contacts catch the rest. Bodies that start the step touching a target are left to the contacts.
// Against a triangle a body is swept only when its centre of mass crossed the triangle's plane during the step (as
// Box2D's one-sided segments do): a body sliding over a tessellated floor, which meets the next triangle's edge
// as it goes, is never stopped there.
//
// Non-bullets run first, in parallel (each reads only static geometry and its own motion), then bullets, which read
// the others' final poses and write only their own: the result is the same for any thread count.
#include <cstdint>
#include <vector>

#include "rubble/math.h"
#include "shapes/shape.h"
#include "storage/body_storage.h"

namespace rubble::detail {

class StaticBvh;
class TaskPool;
struct BodyPair;
struct ShapeBoundsTable;

struct CcdStats {
    std::uint32_t fastBodies = 0;  ///< bodies swept
    std::uint32_t hits = 0;        ///< bodies moved back to a time of impact
};

class ContinuousCollision {
public:
    /// Before the step's substeps: keeps the poses the sweeps start from.
    void begin(const MovingBodies& bodies, TaskPool& pool);
    /// After the step's last substep. `extents`: the shapes' reach and inner extent (bounds.h). `movingPairs`: this
    /// step's candidate pairs of moving bodies (bullets find their dynamic targets among them).
    void run(BodyStorage& storage, const std::vector<Shape>& shapes, const ShapeBoundsTable& extents,
             const StaticBvh& staticTree, const std::vector<BodyPair>& movingPairs, float linearSlop, TaskPool& pool);
    const CcdStats& stats() const { return stats_; }

private:
    /// What every sweep of a run reads.
    struct Sweeps {
        const std::vector<Shape>& shapes;
        const ShapeBoundsTable& extents;
        const StaticBvh& staticTree;
        float treeScale;  ///< StaticBvh::scale(), for the query box's pad
        float linearSlop;
    };
    /// One fast body's sweep; returns true when it moved back.
    bool sweepBody(std::uint32_t body, BodyStorage& storage, const Sweeps& sweeps,
                   const std::vector<std::uint32_t>* dynamicTargets);

    AlignedVector<float> px_, py_, pz_, qx_, qy_, qz_, qw_;  ///< poses at the start of the step
    std::vector<std::uint32_t> fast_, bullets_;
    std::vector<std::uint8_t> hit_;
    /// Per bullet (in bullets_ order): the dynamic bodies its candidate pairs name.
    std::vector<std::vector<std::uint32_t>> bulletTargets_;
    CcdStats stats_;
};

}  // namespace rubble::detail
