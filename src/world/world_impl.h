#pragma once
// World::Impl: the state behind the public World, shared by the files that implement World's API (world.cpp for
// bodies, step.cpp for the step, query/ for the queries).
#include <memory>
#include <string>
#include <vector>

#include "bounds/bounds.h"
#include "broadphase/broadphase_stage.h"
#include "ccd/ccd_stage.h"
#include "contacts/contact_cache.h"
#include "contacts/resting_loads.h"
#include "core/parallel.h"
#include "core/profile.h"
#include "events/contact_events.h"
#include "events/sensor_events.h"
#include "integrate/integrate.h"
#include "islands/islands.h"
#include "islands/sleep.h"
#include "narrowphase/narrowphase_stage.h"
#include "query/query_cache.h"
#include "rubble/world.h"
#include "shapes/shape.h"
#include "solver/contact_solver.h"
#include "solver/joint_solver.h"
#include "storage/body_storage.h"
#include "storage/joint_storage.h"
#include "storage/slot_map.h"
#include "world/effects.h"
#include "world/validation.h"

namespace rubble {
namespace detail {

/// R diag(d) R^T as the six entries of a symmetric matrix (xx, yy, zz, xy, xz, yz).
void rotateDiagonal(Quat r, Vec3 d, float out[6]);

}  // namespace detail

using detail::BodySet;
using detail::BodySlot;
using detail::describe;
using detail::fail;
using detail::MovingBodies;
using detail::requireFinite;
using detail::requireInWorld;
using detail::requireNonNegative;
using detail::requireUnit;
using detail::requireWithin;
using detail::rotateDiagonal;
using detail::Shape;

struct World::Impl {
    WorldSettings settings;
    std::unique_ptr<detail::TaskPool> pool;
    detail::BodyStorage bodies;

    detail::SlotMap<ShapeId> shapeIds;
    std::vector<Shape> shapes;              ///< by shape slot
    std::vector<std::uint32_t> shapeUsers;  ///< by shape slot: bodies using it

    detail::IntegrationScratch integrationScratch;
    detail::ShapeBoundsTable shapeBounds;
    detail::Bounds movingBounds;
    std::uint64_t boundsRowMoves = ~std::uint64_t{0};  ///< BodyStorage::movingRowMoves() at the last updateBounds
    detail::BoundsParams boundsParams;                 ///< ... and its parameters
    std::vector<std::uint32_t> fellAsleepRows;         ///< scratch: rows whose kept box is stale
    detail::BroadPhaseStage broadPhase;
    detail::CandidatePairs pairs;
    detail::NarrowPhaseStage narrowPhase;
    detail::Contacts contacts;
    detail::ContactCache contactCache;
    std::vector<detail::PointImpulse> impulses;
    /// The contacts above are the last step's (the collision stages ran in it): World::contactsOf reads them.
    bool contactsOfLastStep = false;
    detail::RestingLoads restingLoads;
    detail::IslandBuilder islandBuilder;
    detail::Islands islands;
    detail::SleepingIslands sleeping;
    /// Extra edges of the island graph (dense index pairs): the links that hold each sleeping island together, and
    /// where joints will add theirs.
    std::vector<detail::IslandEdge> islandEdges;
    detail::ContactSolver contactSolver;
    detail::ContinuousCollision ccd;
    detail::JointStore joints;
    detail::JointSolver jointSolver;
    detail::JointCoupling jointCoupling;
    /// Events (src/events/): bodies that ask for contact events, and sensors and bodies without contact response
    /// (whose manifolds leave the contacts), counted so that a world without them runs no event code; the last
    /// step's events.
    std::uint32_t listeningBodies = 0;
    std::uint32_t separatedBodies = 0;
    detail::ContactEventStage contactEventStage;
    detail::SensorEventStage sensorEventStage;
    ContactEvents contactEvents;
    SensorEvents sensorEvents;
    std::vector<std::uint32_t> nonFinite;
    std::vector<BodyId> frozenReports;
    /// The scene queries' trees (src/query/); told of every body added, removed or moved outside the step.
    detail::QueryCache queries;

    /// Bodies are put in the broad-phase grid's cell order from this many moving bodies on, every
    /// spatialOrderPeriod steps: once their arrays outgrow the caches, every stage that gathers the bodies of a
    /// pair (narrow phase, solver, the grid's own gather) then reads neighbouring rows instead of random ones.
    /// Members, not constants, so that tests can order small worlds.
    std::uint32_t spatialOrderFrom = 200000;
    std::uint32_t spatialOrderPeriod = 64;
    std::uint32_t stepsSinceSpatialOrder = 0;
    bool spatiallyOrdered = false;  ///< false until the first order: a world created in random order waits no period

    Profile profile;
    std::uint64_t steps = 0;
    detail::Clock::time_point origin = detail::Clock::now();

    EffectSet effects;
    bool effectsDirty = true;
    detail::StaticMaterialCounts staticMaterials;
    detail::MovingMaterialCounts movingMaterials;
    bool anyDamping = false;
    bool forcesPending = false;

    explicit Impl(const WorldSettings& s) : settings(s), pool(std::make_unique<detail::TaskPool>(s.threads)) {}

    const Shape& shapeOf(ShapeId id, const char* where) const {
        if (id.isNull()) fail(where, "the shape handle is null");
        if (!shapeIds.contains(id))
            fail(where, "shape handle (index " + std::to_string(id.index) + ", generation " +
                            std::to_string(id.generation) + ") is stale or not from this world");
        return shapes[id.index];
    }

    const BodySlot& slotOf(BodyId id, const char* where) const {
        const BodySlot* slot = bodies.find(id);
        if (!slot) {
            if (id.isNull()) fail(where, "the body handle is null");
            fail(where, "body handle (index " + std::to_string(id.index) + ", generation " +
                            std::to_string(id.generation) + ") is stale or not from this world");
        }
        return *slot;
    }

    /// Dense index of a moving body, or -1 for a static one.
    long movingIndex(BodyId id, const char* where) const {
        const BodySlot& s = slotOf(id, where);
        return s.set == BodySet::Moving ? static_cast<long>(s.dense) : -1;
    }

    bool isDynamic(std::uint32_t i) const {
        return !(bodies.moving.flags[i] & (detail::kFlagKinematic | detail::kFlagFrozen));
    }

    Quat orientationOf(std::uint32_t i) const {
        const MovingBodies& m = bodies.moving;
        return {m.qx[i], m.qy[i], m.qz[i], m.qw[i]};
    }

    Vec3 comOf(std::uint32_t i) const { return {bodies.moving.px[i], bodies.moving.py[i], bodies.moving.pz[i]}; }

    void refreshWorldInertia(std::uint32_t i) {
        MovingBodies& m = bodies.moving;
        const Quat r = orientationOf(i) * Quat{m.irx[i], m.iry[i], m.irz[i], m.irw[i]};
        float w[6];
        rotateDiagonal(r, {m.invIx[i], m.invIy[i], m.invIz[i]}, w);
        m.iwXX[i] = w[0], m.iwYY[i] = w[1], m.iwZZ[i] = w[2], m.iwXY[i] = w[3], m.iwXZ[i] = w[4], m.iwYZ[i] = w[5];
    }

    Vec3 applyWorldInverseInertia(std::uint32_t i, Vec3 v) const {
        const MovingBodies& m = bodies.moving;
        return {m.iwXX[i] * v.x + m.iwXY[i] * v.y + m.iwXZ[i] * v.z,
                m.iwXY[i] * v.x + m.iwYY[i] * v.y + m.iwYZ[i] * v.z,
                m.iwXZ[i] * v.x + m.iwYZ[i] * v.y + m.iwZZ[i] * v.z};
    }

    /// Mass, inverse principal inertia and centre of mass of a moving body from its shape and density.
    void setMassFromShape(std::uint32_t i) {
        MovingBodies& m = bodies.moving;
        const Shape& shape = shapes[m.shape[i]];
        const Vec3 com = shape.unitMass.centerOfMass;
        m.lcx[i] = com.x, m.lcy[i] = com.y, m.lcz[i] = com.z;
        if (!isDynamic(i)) {
            m.invMass[i] = 0;
            m.invIx[i] = m.invIy[i] = m.invIz[i] = 0;
            m.irx[i] = m.iry[i] = m.irz[i] = 0, m.irw[i] = 1;
        } else {
            const float density = m.density[i];
            const detail::PrincipalInertia& pi = shape.unitPrincipal;
            m.invMass[i] = 1.0f / (shape.unitMass.mass * density);
            m.invIx[i] = pi.moments.x > 0 ? 1.0f / (pi.moments.x * density) : 0.0f;
            m.invIy[i] = pi.moments.y > 0 ? 1.0f / (pi.moments.y * density) : 0.0f;
            m.invIz[i] = pi.moments.z > 0 ? 1.0f / (pi.moments.z * density) : 0.0f;
            m.irx[i] = pi.rotation.x, m.iry[i] = pi.rotation.y, m.irz[i] = pi.rotation.z, m.irw[i] = pi.rotation.w;
        }
        refreshWorldInertia(i);
    }

    /// Keeps listeningBodies and separatedBodies: `change` is +1 for a body added with `flags`, -1 for one removed.
    void countEventFlags(std::uint8_t flags, int change) {
        if (flags & detail::kFlagContactEvents) listeningBodies += static_cast<std::uint32_t>(change);
        if (flags & (detail::kFlagSensor | detail::kFlagNoResponse))
            separatedBodies += static_cast<std::uint32_t>(change);
    }

    /// Wakes the sleeping island of a moving body about to be pushed, moved or changed through the API.
    void wake(std::uint32_t i) { sleeping.wake(i, bodies); }

    /// A body whose state went non-finite stops being simulated (its last finite state is kept) and is reported.
    void freeze(std::uint32_t i) {
        MovingBodies& m = bodies.moving;
        if (m.flags[i] & detail::kFlagFrozen) return;
        movingMaterials.count(m, i, shapes, -1);
        m.flags[i] |= detail::kFlagFrozen;
        m.invMass[i] = 0;
        m.invIx[i] = m.invIy[i] = m.invIz[i] = 0;
        m.gravityScale[i] = 0;
        m.linearDamping[i] = m.angularDamping[i] = 0;
        m.vx[i] = m.vy[i] = m.vz[i] = m.wx[i] = m.wy[i] = m.wz[i] = 0;
        m.fx[i] = m.fy[i] = m.fz[i] = m.tx[i] = m.ty[i] = m.tz[i] = 0;
        refreshWorldInertia(i);
        const std::uint32_t slot = m.slot[i];
        frozenReports.push_back(bodies.idAt(slot));
        profile.frozenCount += 1;
    }

    void freezeReported() {
        for (std::uint32_t i : nonFinite) freeze(i);
        nonFinite.clear();
    }

    void resolveEffectsIfDirty() {
        if (!effectsDirty) return;
        effects = detail::resolveEffects(settings.effects, settings, bodies.moving, movingMaterials, staticMaterials,
                                         joints.activeCount() > 0, anyDamping);
        effectsDirty = false;
    }
};

}  // namespace rubble
