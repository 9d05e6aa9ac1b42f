#pragma once
// A batch of contact constraints, one manifold per SIMD lane, and the solver kernels over it. The kernels are
// written once over a lane type F: FloatW runs a whole batch per call, float runs one lane (the scalar reference
// the tests compare the wide kernels with, and that perf/ measures them against).
#include <cstddef>
#include <cstdint>
#include <span>

#include "narrowphase/manifold.h"
#include "simd/transpose.h"
#include "simd/vec.h"

namespace rubble::detail {

inline constexpr std::size_t kBatchLanes = simd::kLanes;

/// Up to kBatchLanes manifolds in SoA form. The bodies' masses are not here but in their mass rows (MassRow), read
/// by body index like the velocities: a lane with no manifold meets the still row on both sides, whose masses are
/// zero, and a point beyond a manifold's count has zero effective masses, so every impulse they compute is zero. Points
/// at pointCount and beyond are in no lane and are never read: the kernels stop there, so that a batch of one-point
/// contacts (spheres, capsules on a mesh) costs a quarter of a batch of boxes. Static bodies read the still row; only
/// dynamic bodies are written back (the kernels redirect other writes to a scratch row).
struct alignas(64) ContactBatch {
    using Lanes = float[kBatchLanes];
    std::int32_t bodyA[kBatchLanes];
    std::int32_t bodyB[kBatchLanes];
    std::int32_t pointCount;  ///< the most points of any lane's manifold
    Lanes nx, ny, nz;         ///< normal, from A to B
    Lanes t1x, t1y, t1z;      ///< friction directions: t1, t2, n right-handed
    Lanes t2x, t2y, t2z;
    Lanes friction;
    Lanes biasRate;      ///< overlap fed back as approach speed, 1/s
    Lanes massScale;     ///< soft constraint: share of the rigid response...
    Lanes impulseScale;  ///< ...and of the accumulated impulse taken away each iteration
    Lanes slop;          ///< overlap left alone by the bias (Baumgarte)
    struct Point {
        Lanes rAx, rAy, rAz;  ///< contact point from A's centre of mass at prepare()
        Lanes rBx, rBy, rBz;
        Lanes separation;  ///< at prepare(), less the anchors' normal offset: current = this + n . (xB - xA)
        Lanes normalMass, tangentMass1, tangentMass2;
        Lanes normalImpulse, tangentImpulse1, tangentImpulse2;
    } points[kMaxManifoldPoints];
};

/// What only bounces and split impulses read, beside its batch (same index), so that the other solves do not stream
/// it: the solver keeps these only when the step has restitution or split impulses.
struct alignas(64) ContactBatchExtras {
    using Lanes = float[kBatchLanes];
    Lanes restitution;
    Lanes normalGravity;  ///< B's gravity less A's along the normal (the approach's rate of change), m/s^2
    struct Point {
        Lanes relativeVelocity;  ///< normal approach speed at prepare(), for restitution
        Lanes maxNormalImpulse;  ///< largest normal impulse of the step: zero means the point never pushed
        Lanes pseudoImpulse;     ///< split impulses
    } points[kMaxManifoldPoints];
};

/// One body's row in the solver's working set: a linear and an angular 3-vector (velocity, motion since prepare(),
/// or split impulses' pseudo-velocity), padded to 32 bytes so that the wide kernels load and store whole rows and
/// transpose them into lanes (simd/transpose.h) instead of gathering six arrays. The pad holds no meaning.
struct alignas(32) BodyRow {
    Vec3 linear;
    Vec3 angular;
    float pad[2] = {0, 0};
};
static_assert(sizeof(BodyRow) == simd::kRowFloats * sizeof(float) && offsetof(BodyRow, angular) == 3 * sizeof(float),
              "a body row is eight floats: the transposes read it as such");

/// One body's masses in the solver's working set: the world inverse inertia (xx, yy, zz, xy, xz, yz) and the inverse
/// mass, zero for bodies that cannot move, 32 bytes so that the wide kernels transpose 16 of them into lanes as they
/// do velocity rows. Kept per body rather than per lane: a body in five manifolds is five lanes, and the rows a batch
/// streams through every iteration shrink by a sixth (four points) to a third (one point).
struct alignas(32) MassRow {
    float inverseInertia[6] = {0, 0, 0, 0, 0, 0};
    float inverseMass = 0;
    float pad = 0;
};
static_assert(sizeof(MassRow) == simd::kRowFloats * sizeof(float),
              "a mass row is eight floats: the transposes read it");

/// Row arrays of SolverBodies, with the scratch row this worker may write.
struct BodyRows {
    BodyRow* velocity;
    const BodyRow* motion;
    BodyRow* pseudo;
    const MassRow* mass;
    std::int32_t scratchRow;
};

/// Solve-wide constants.
struct SolveParams {
    float invH = 60;  ///< 1 / substep
    float maxPushOutVelocity = 3;
    bool useBias = true;
    /// The bodies moved since prepare() (later substeps, relax): separations follow their motion. When false the
    /// motion rows are all zero and are not read.
    bool moved = true;
};

namespace contact_kernels {

using simd::Vec3W;

template <class F>
using IndexOf = simd::IntOf<F>;

template <class F>
F at(const float* lanes, std::size_t lane) {
    return simd::load<F>(lanes + lane);
}

template <class F>
Vec3W<F> at3(const float* x, const float* y, const float* z, std::size_t lane) {
    return {at<F>(x, lane), at<F>(y, lane), at<F>(z, lane)};
}

template <class F>
void put(float* lanes, std::size_t lane, const F& v) {
    simd::store(lanes + lane, v);
}

/// The linear and angular parts of a row, in lanes.
template <class F>
struct RowW {
    Vec3W<F> linear, angular;
};

/// Rows index[k] for the lanesOf<F> indices at `index`. (Inlined by force: GCC otherwise calls it, and the six
/// wide vectors make a round trip through memory.)
template <class F>
[[gnu::always_inline]] inline RowW<F> loadRows(const BodyRow* rows, const std::int32_t* index) {
    F c[simd::kRowFloats];
    simd::loadRowsTransposed(reinterpret_cast<const float*>(rows), index, c);
    return {{c[0], c[1], c[2]}, {c[3], c[4], c[5]}};
}

/// Writes rows index[k] whole (pad zeroed); with repeated indices the highest lane wins.
template <class F>
[[gnu::always_inline]] inline void storeRows(BodyRow* rows, const IndexOf<F>& index, const Vec3W<F>& linear,
                                             const Vec3W<F>& angular) {
    const F zero(0.0f);
    const F c[simd::kRowFloats] = {linear.x, linear.y, linear.z, angular.x, angular.y, angular.z, zero, zero};
    simd::storeRowsTransposed(reinterpret_cast<float*>(rows), index, c);
}

/// Inverse mass and world inverse inertia of the bodies index[k], in lanes.
template <class F>
struct MassW {
    F inverseMass;
    simd::SymMat3W<F> inverseInertia;
};
template <class F>
[[gnu::always_inline]] inline MassW<F> loadMasses(const MassRow* rows, const std::int32_t* index) {
    F c[simd::kRowFloats];
    simd::loadRowsTransposed(reinterpret_cast<const float*>(rows), index, c);
    return {c[6], {c[0], c[1], c[2], c[3], c[4], c[5]}};
}

/// The two bodies of a batch as loaded from the rows, and where to write them back.
template <class F>
struct Pair {
    IndexOf<F> readA, readB, writeA, writeB;
    Vec3W<F> vA, wA, vB, wB;
    F mA, mB;
    simd::SymMat3W<F> iA, iB;

    Pair(const ContactBatch& b, std::size_t lane, const BodyRow* rows, const MassRow* mass, std::int32_t scratchRow) {
        readA = simd::loadInt<IndexOf<F>>(b.bodyA + lane);
        readB = simd::loadInt<IndexOf<F>>(b.bodyB + lane);
        const MassW<F> massA = loadMasses<F>(mass, b.bodyA + lane), massB = loadMasses<F>(mass, b.bodyB + lane);
        mA = massA.inverseMass, iA = massA.inverseInertia;
        mB = massB.inverseMass, iB = massB.inverseInertia;
        const IndexOf<F> scratch(scratchRow);
        writeA = simd::select(mA > F(0.0f), readA, scratch);
        writeB = simd::select(mB > F(0.0f), readB, scratch);
        const RowW<F> a = loadRows<F>(rows, b.bodyA + lane), c = loadRows<F>(rows, b.bodyB + lane);
        vA = a.linear, wA = a.angular;
        vB = c.linear, wB = c.angular;
    }

    void store(BodyRow* rows) const {
        // A before B: when both are the scratch row the value written there does not matter.
        storeRows<F>(rows, writeA, vA, wA);
        storeRows<F>(rows, writeB, vB, wB);
    }

    Vec3W<F> relativeVelocity(const Vec3W<F>& rA, const Vec3W<F>& rB) const {
        return (vB + cross(wB, rB)) - (vA + cross(wA, rA));
    }

    void apply(const Vec3W<F>& rA, const Vec3W<F>& rB, const Vec3W<F>& impulse) {
        vA -= impulse * mA;
        wA -= iA * cross(rA, impulse);
        vB += impulse * mB;
        wB += iB * cross(rB, impulse);
    }
};

/// The points some lane uses.
inline std::span<ContactBatch::Point> pointsOf(ContactBatch& b) {
    return {b.points, static_cast<std::size_t>(b.pointCount)};
}

template <class F>
Vec3W<F> anchorA(const ContactBatch::Point& p, std::size_t lane) {
    return at3<F>(p.rAx, p.rAy, p.rAz, lane);
}
template <class F>
Vec3W<F> anchorB(const ContactBatch::Point& p, std::size_t lane) {
    return at3<F>(p.rBx, p.rBy, p.rBz, lane);
}

/// Applies the accumulated impulses of every point.
template <class F>
void warmStart(ContactBatch& b, std::size_t lane, const BodyRows& rows) {
    Pair<F> pair(b, lane, rows.velocity, rows.mass, rows.scratchRow);
    const Vec3W<F> n = at3<F>(b.nx, b.ny, b.nz, lane);
    const Vec3W<F> t1 = at3<F>(b.t1x, b.t1y, b.t1z, lane);
    const Vec3W<F> t2 = at3<F>(b.t2x, b.t2y, b.t2z, lane);
    for (const ContactBatch::Point& p : pointsOf(b)) {
        const Vec3W<F> impulse = n * at<F>(p.normalImpulse, lane) + t1 * at<F>(p.tangentImpulse1, lane) +
                                 t2 * at<F>(p.tangentImpulse2, lane);
        pair.apply(anchorA<F>(p, lane), anchorB<F>(p, lane), impulse);
    }
    pair.store(rows.velocity);
}

/// Current separation of a point: at prepare() plus the bodies' motion since, the rotation linearised (the
/// anchors turn by less than a step's worth).
template <class F>
F separation(const ContactBatch::Point& p, std::size_t lane, const Vec3W<F>& n, const Vec3W<F>& rA, const Vec3W<F>& rB,
             const Vec3W<F>& dpA, const Vec3W<F>& daA, const Vec3W<F>& dpB, const Vec3W<F>& daB) {
    const Vec3W<F> d = (dpB + cross(daB, rB)) - (dpA + cross(daA, rA));
    return at<F>(p.separation, lane) + dot(n, d);
}

/// One velocity iteration: friction at every point (within the cone of last iteration's normal impulse), then the
/// normal impulses, Gauss-Seidel within the manifold.
/// With `extras`, each point's largest normal impulse is kept for restitution.
template <class F, bool Friction>
void solve(ContactBatch& b, std::size_t lane, const BodyRows& rows, const SolveParams& params,
           ContactBatchExtras* extras = nullptr) {
    Pair<F> pair(b, lane, rows.velocity, rows.mass, rows.scratchRow);
    const Vec3W<F> n = at3<F>(b.nx, b.ny, b.nz, lane);
    if constexpr (Friction) {
        const Vec3W<F> t1 = at3<F>(b.t1x, b.t1y, b.t1z, lane);
        const Vec3W<F> t2 = at3<F>(b.t2x, b.t2y, b.t2z, lane);
        const F mu = at<F>(b.friction, lane);
        for (ContactBatch::Point& p : pointsOf(b)) {
            const Vec3W<F> rA = anchorA<F>(p, lane), rB = anchorB<F>(p, lane);
            const Vec3W<F> dv = pair.relativeVelocity(rA, rB);
            const F old1 = at<F>(p.tangentImpulse1, lane), old2 = at<F>(p.tangentImpulse2, lane);
            F new1 = old1 - at<F>(p.tangentMass1, lane) * dot(dv, t1);
            F new2 = old2 - at<F>(p.tangentMass2, lane) * dot(dv, t2);
            // Coulomb's cone, not a box: the tangent impulse as a vector is clamped to mu times the normal one.
            const F limit = mu * at<F>(p.normalImpulse, lane);
            const F lengthSq = new1 * new1 + new2 * new2;
            const auto outside = lengthSq > limit * limit;
            const F scale = simd::select(outside, limit / simd::sqrt(simd::max(lengthSq, F(1e-30f))), F(1.0f));
            new1 = new1 * scale;
            new2 = new2 * scale;
            put(p.tangentImpulse1, lane, new1);
            put(p.tangentImpulse2, lane, new2);
            pair.apply(rA, rB, t1 * (new1 - old1) + t2 * (new2 - old2));
        }
    }
    Vec3W<F> dpA = Vec3W<F>::zero(), daA = dpA, dpB = dpA, daB = dpA;
    if (params.moved) {
        const RowW<F> a = loadRows<F>(rows.motion, b.bodyA + lane), c = loadRows<F>(rows.motion, b.bodyB + lane);
        dpA = a.linear, daA = a.angular;
        dpB = c.linear, daB = c.angular;
    }
    const F invH(params.invH);
    const F biasRate = at<F>(b.biasRate, lane), slop = at<F>(b.slop, lane);
    const F massScale = params.useBias ? at<F>(b.massScale, lane) : F(1.0f);
    const F impulseScale = params.useBias ? at<F>(b.impulseScale, lane) : F(0.0f);
    const F maxPush(-params.maxPushOutVelocity);
    for (int i = 0; i < b.pointCount; ++i) {
        ContactBatch::Point& p = b.points[i];
        const Vec3W<F> rA = anchorA<F>(p, lane), rB = anchorB<F>(p, lane);
        const F s = separation(p, lane, n, rA, rB, dpA, daA, dpB, daB);
        const auto apart = s > F(0.0f);
        // Apart: the bodies may close the gap this substep and no more (speculative contact). Overlapping: push
        // out at a rate the correction method sets, never faster than maxPushOutVelocity.
        // A loaded soft contact may push out as fast as its load needs (the speed at which the spring's leak and its
        // push balance): its spring would otherwise give way under a heavy body.
        const F loadPush =
            at<F>(p.normalImpulse, lane) * impulseScale / simd::max(at<F>(p.normalMass, lane) * massScale, F(1e-30f));
        F bias = simd::max(biasRate * simd::min(s + slop, F(0.0f)), simd::min(maxPush, F(0.0f) - loadPush));
        if (!params.useBias) bias = F(0.0f);
        bias = simd::select(apart, s * invH, bias);
        const F scaleM = simd::select(apart, F(1.0f), massScale);
        const F scaleI = simd::select(apart, F(0.0f), impulseScale);
        const F old = at<F>(p.normalImpulse, lane);
        const F vn = dot(pair.relativeVelocity(rA, rB), n);
        const F delta = F(0.0f) - at<F>(p.normalMass, lane) * scaleM * (vn + bias) - scaleI * old;
        const F updated = simd::max(old + delta, F(0.0f));
        put(p.normalImpulse, lane, updated);
        if (extras) {
            float* pushed = extras->points[i].maxNormalImpulse;
            put(pushed, lane, simd::max(at<F>(pushed, lane), updated - old));
        }
        pair.apply(rA, rB, n * (updated - old));
    }
    pair.store(rows.velocity);
}

/// Split impulses: the overlap beyond the slop is removed through pseudo-velocities, which move the bodies this
/// substep and are then forgotten, so that push-out never becomes kinetic energy.
template <class F>
void solvePositions(ContactBatch& b, ContactBatchExtras& extras, std::size_t lane, const BodyRows& rows,
                    const SolveParams& params) {
    Pair<F> pair(b, lane, rows.pseudo, rows.mass, rows.scratchRow);
    const Vec3W<F> n = at3<F>(b.nx, b.ny, b.nz, lane);
    const RowW<F> motionA = loadRows<F>(rows.motion, b.bodyA + lane);
    const RowW<F> motionB = loadRows<F>(rows.motion, b.bodyB + lane);
    const Vec3W<F>&dpA = motionA.linear, &daA = motionA.angular, &dpB = motionB.linear, &daB = motionB.angular;
    const F biasRate = at<F>(b.biasRate, lane), slop = at<F>(b.slop, lane);
    const F maxPush(params.maxPushOutVelocity);
    for (int i = 0; i < b.pointCount; ++i) {
        const ContactBatch::Point& p = b.points[i];
        float* pseudoImpulse = extras.points[i].pseudoImpulse;
        const Vec3W<F> rA = anchorA<F>(p, lane), rB = anchorB<F>(p, lane);
        const F s = separation(p, lane, n, rA, rB, dpA, daA, dpB, daB);
        const F target = simd::min(F(0.0f) - biasRate * simd::min(s + slop, F(0.0f)), maxPush);
        const F old = at<F>(pseudoImpulse, lane);
        const F vn = dot(pair.relativeVelocity(rA, rB), n);
        const F updated = simd::max(old + at<F>(p.normalMass, lane) * (target - vn), F(0.0f));
        put(pseudoImpulse, lane, updated);
        pair.apply(rA, rB, n * (updated - old));
    }
    pair.store(rows.pseudo);
}

/// Reverses approach speeds above the threshold by the restitution coefficient, at points that pushed this step.
/// The approach is the one measured at prepare(), before the solve took it away, carried under gravity to where
/// the point is now: a ball still apart from the ground at prepare() has fallen further and faster since, and is
/// stopped at the ground, or just above it where the relax iterations' speculative contact holds it back for the next
/// step. Reversing the speed at prepare() lost the last part-step's fall each bounce (2% of the height at 60 Hz);
/// reversing the speed at the ground while held above it would gain that much. Only gravity is carried: the other
/// forces are not known here, and a point that overlapped at prepare() keeps its speed.
template <class F>
void restitution(ContactBatch& b, const ContactBatchExtras& extras, std::size_t lane, const BodyRows& rows,
                 float threshold) {
    Pair<F> pair(b, lane, rows.velocity, rows.mass, rows.scratchRow);
    const Vec3W<F> n = at3<F>(b.nx, b.ny, b.nz, lane);
    const F e = at<F>(extras.restitution, lane);
    const F g = at<F>(extras.normalGravity, lane);
    const RowW<F> a = loadRows<F>(rows.motion, b.bodyA + lane), c = loadRows<F>(rows.motion, b.bodyB + lane);
    for (int i = 0; i < b.pointCount; ++i) {
        ContactBatch::Point& p = b.points[i];
        const F approachAtPrepare = at<F>(extras.points[i].relativeVelocity, lane);
        const Vec3W<F> rA = anchorA<F>(p, lane), rB = anchorB<F>(p, lane);
        const F gapThen = simd::max(at<F>(p.separation, lane), F(0.0f));
        const F gapNow = simd::min(
            simd::max(separation(p, lane, n, rA, rB, a.linear, a.angular, c.linear, c.angular), F(0.0f)), gapThen);
        const F fallen = approachAtPrepare * approachAtPrepare - F(2.0f) * g * (gapThen - gapNow);
        const F approach =
            simd::select(g < F(0.0f), F(0.0f) - simd::sqrt(simd::max(fallen, F(0.0f))), approachAtPrepare);
        const auto bounces =
            simd::andMask(approach<F(-threshold), at<F>(extras.points[i].maxNormalImpulse, lane)> F(0.0f));
        if (simd::none(bounces)) continue;
        const F vn = dot(pair.relativeVelocity(rA, rB), n);
        const F old = at<F>(p.normalImpulse, lane);
        const F delta = F(0.0f) - at<F>(p.normalMass, lane) * (vn + e * approach);
        const F updated = simd::select(bounces, simd::max(old + delta, F(0.0f)), old);
        put(p.normalImpulse, lane, updated);
        pair.apply(rA, rB, n * (updated - old));
    }
    pair.store(rows.velocity);
}

}  // namespace contact_kernels
}  // namespace rubble::detail
