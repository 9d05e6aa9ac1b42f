#pragma once
// Bodies in structure-of-arrays storage. Moving (dynamic and kinematic) bodies and static bodies live in separate
// sets so that static bodies cost nothing in the per-step passes and static-static pairs cannot arise.
// A slot map turns BodyId (slot index + generation) into a dense index; removal swaps the last body into the hole.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "rubble/body.h"
#include "rubble/id.h"
#include "rubble/math.h"
#include "storage/aligned_vector.h"
#include "storage/slot_map.h"

namespace rubble::detail {

class TaskPool;

enum BodyFlags : std::uint8_t {
    kFlagKinematic = 1u << 0,
    kFlagFrozen = 1u << 1,   ///< state went non-finite; no longer simulated
    kFlagAsleep = 1u << 2,   ///< resting in a sleeping island: the broad phase skips pairs of two such bodies
    kFlagNoSleep = 1u << 3,  ///< BodyDef::allowSleep was false: its island never sleeps
    kFlagBullet = 1u << 4,   ///< BodyDef::bullet: continuous collision against dynamic bodies too
    // The two below are also static bodies' flags (StaticBodies::flags).
    kFlagContactEvents = 1u << 5,  ///< BodyDef::contactEvents: its pairs are reported (src/events/)
    kFlagSensor = 1u << 6,         ///< BodyDef::sensor: reports overlaps, pushes nothing (src/events/)
    kFlagNoResponse = 1u << 7,     ///< BodyDef::contactResponse false: its contacts are never solved (src/events/)
};

/// Dynamic and kinematic bodies. Position is the centre of mass; the user-facing origin is
/// position - rotate(orientation, localCenter).
struct MovingBodies {
    AlignedVector<float> px, py, pz;           ///< centre of mass, world
    AlignedVector<float> qx, qy, qz, qw;       ///< orientation of the body frame
    AlignedVector<float> vx, vy, vz;           ///< linear velocity of the centre of mass
    AlignedVector<float> wx, wy, wz;           ///< angular velocity, world frame
    AlignedVector<float> fx, fy, fz;           ///< force accumulator, cleared by integrate velocities
    AlignedVector<float> tx, ty, tz;           ///< torque accumulator about the centre of mass, world frame
    AlignedVector<float> invMass;              ///< 0 for kinematic and frozen bodies
    AlignedVector<float> invIx, invIy, invIz;  ///< inverse principal moments (0 where rotation is locked)
    AlignedVector<float> irx, iry, irz, irw;   ///< rotation from the principal frame to the body frame
    /// World inverse inertia R diag(invI) R^T (symmetric), refreshed by integrate velocities for later stages.
    AlignedVector<float> iwXX, iwYY, iwZZ, iwXY, iwXZ, iwYZ;
    AlignedVector<float> linearDamping, angularDamping;  ///< 1/s
    AlignedVector<float> gravityScale;                   ///< 0 for kinematic bodies
    AlignedVector<float> lcx, lcy, lcz;                  ///< centre of mass in the body frame
    AlignedVector<float> friction, restitution, density;
    AlignedVector<float> sleepTimer;        ///< how long the body has rested, s (islands_sleep.cpp)
    std::vector<std::uint32_t> sleepGroup;  ///< while asleep: the sleeping island that holds it (islands_sleep.h)
    std::vector<std::uint32_t> shape;       ///< shape slot index
    std::vector<std::uint32_t> filterCategory, filterMask;
    std::vector<std::uint64_t> userData;
    std::vector<std::uint8_t> flags;
    std::vector<std::uint32_t> slot;  ///< back-reference: dense index -> slot

    std::uint32_t size() const { return static_cast<std::uint32_t>(slot.size()); }
    /// Appends a zero-initialised body and returns its dense index.
    std::uint32_t pushBack();
    /// Moves the last body into `dense` and shrinks by one; returns the slot of the moved body (or ~0u).
    std::uint32_t swapRemove(std::uint32_t dense);
};

/// Static bodies: pose and surface only.
struct StaticBodies {
    AlignedVector<float> px, py, pz;
    AlignedVector<float> qx, qy, qz, qw;
    AlignedVector<float> friction, restitution, density;
    std::vector<std::uint32_t> shape;
    std::vector<std::uint32_t> filterCategory, filterMask;
    std::vector<std::uint64_t> userData;
    std::vector<std::uint8_t> flags;  ///< kFlagContactEvents, kFlagSensor, kFlagNoResponse
    std::vector<std::uint32_t> slot;

    std::uint32_t size() const { return static_cast<std::uint32_t>(slot.size()); }
    std::uint32_t pushBack();
    std::uint32_t swapRemove(std::uint32_t dense);
};

enum class BodySet : std::uint8_t { Moving, Static };

/// What a body's slot holds: where the body lives now.
struct BodySlot {
    std::uint32_t dense = 0;
    BodySet set = BodySet::Moving;
};

/// The moving bodies that fell asleep or woke since some point (slots, any order, repeats allowed), or `all` when
/// there were too many to list: what the sleep stage tells the stages that keep state about sleepers.
struct SleepChanges {
    std::span<const std::uint32_t> slots;
    bool all = false;
};

/// The slot map plus both sets.
class BodyStorage {
public:
    MovingBodies moving;
    StaticBodies statics;

    /// Reserves a slot for a new body in `set` and returns its handle; the caller fills the dense row.
    BodyId allocate(BodySet set, std::uint32_t& denseOut);
    void release(BodyId id);
    /// Null pointer when the handle is null, out of range or stale.
    const BodySlot* find(BodyId id) const;
    std::uint32_t count() const { return moving.size() + statics.size(); }
    /// Where each slot's body lives, by slot (meaningful while alive(slot)).
    const std::vector<BodySlot>& slots() const { return slots_; }
    bool alive(std::uint32_t slot) const { return ids_.alive(slot); }
    /// The dense row of the moving body in `slot` when one lives there and sleeps, else ~0u.
    std::uint32_t sleepingRow(std::uint32_t slot) const {
        if (!alive(slot) || slots_[slot].set != BodySet::Moving) return ~0u;
        const std::uint32_t i = slots_[slot].dense;
        return (moving.flags[i] & kFlagAsleep) != 0 ? i : ~0u;
    }
    /// The handle of the body in `slot` (its last body when the slot is free).
    BodyId idAt(std::uint32_t slot) const { return ids_.idAt(slot); }
    /// Counts additions, removals and reorders: while it stays the same, every dense index names the same body.
    std::uint64_t layoutChanges() const { return layoutChanges_; }
    /// Counts the events that can give an existing moving row another body (removals, which move the last row into
    /// the hole, and reorders); additions only append rows. While it stays the same, rows below the old count keep
    /// their bodies.
    std::uint64_t movingRowMoves() const { return movingRowMoves_; }
    /// Puts the moving bodies in a new order: row k becomes the body that is at row order[k] now (`order` is a
    /// permutation of 0 .. moving.size() - 1). Every handle keeps its body; dense indices change, which
    /// layoutChanges() counts. Used to keep bodies that are near in space near in memory (World::step).
    void reorderMoving(const std::uint32_t* order, TaskPool& pool);
    /// Debug aid (RUBBLE_VALIDATE): every live slot points at a row that points back, every array has the
    /// set's length. Returns a description of the first broken invariant, or an empty string.
    std::string checkInvariants() const;

private:
    /// One spare array per element type: reorderMoving gathers into it and swaps it with the array.
    struct ReorderScratch {
        AlignedVector<float> floats;
        std::vector<std::uint32_t> words;
        std::vector<std::uint64_t> longs;
        std::vector<std::uint8_t> bytes;
    };

    SlotMap<BodyId> ids_;
    ReorderScratch reorderScratch_;
    std::vector<BodySlot> slots_;
    std::uint64_t layoutChanges_ = 0;
    std::uint64_t movingRowMoves_ = 0;
};

}  // namespace rubble::detail
