#pragma once
// Ball joints of one colour in SIMD lanes: the large islands' joint colours (joint_solver.h) put their ball joints,
// kBatchLanes at a time, into batches that one kernel call solves together, as the contact solver does its
// manifolds. The lanes of a batch share no moving body, so the body rows are loaded and stored by the same
// transposes as the contacts' (contact_batch.h), the writes aimed at bodies the solver holds still going to the
// worker's scratch row. Empty lanes name the still row on both sides and carry zero masses: they compute a zero
// impulse and write only the scratch row.
//
// The rows follow JointSolver's scalar ones: begin() measures the substep's anchors, error and effective mass from the
// bodies' motion since the step's start (exact rotations) and applies the accumulated impulse (warm starting) or
// clears it; solve() is one sequential-impulse iteration of the three point rows with the step's softness.
#include <cstddef>
#include <cstdint>

#include "simd/vec.h"
#include "solver/contact_batch.h"

namespace rubble::detail {

struct alignas(64) BallJointBatch {
    std::int32_t bodyA[kBatchLanes], bodyB[kBatchLanes];  ///< body rows: the still row for static sides and empty lanes
    std::uint32_t joint[kBatchLanes];                     ///< the joint's row in JointSolver, ~0u for an empty lane
    /// At the step's start: the anchors from the centres of mass, and centre of mass of B - centre of mass of A.
    float frameAx[kBatchLanes], frameAy[kBatchLanes], frameAz[kBatchLanes];
    float frameBx[kBatchLanes], frameBy[kBatchLanes], frameBz[kBatchLanes];
    float centresX[kBatchLanes], centresY[kBatchLanes], centresZ[kBatchLanes];
    /// Inverse of the point rows' effective mass (symmetric: xx, yy, zz, xy, xz, yz), fixed for the step.
    float pointMass[6][kBatchLanes];
    /// This substep's anchors and error (anchor B - anchor A).
    float rAx[kBatchLanes], rAy[kBatchLanes], rAz[kBatchLanes];
    float rBx[kBatchLanes], rBy[kBatchLanes], rBz[kBatchLanes];
    float errorX[kBatchLanes], errorY[kBatchLanes], errorZ[kBatchLanes];
    float impulseX[kBatchLanes], impulseY[kBatchLanes], impulseZ[kBatchLanes];  ///< accumulated
};

/// What building a batch reads of its lanes' bodies (side 0 is A, 1 is B), gathered lane by lane from the body store:
/// the centre of mass, the orientation and the anchor from the centre of mass in the body's frame. An empty lane
/// holds zeros and the identity.
struct BallJointPoses {
    float px[2][kBatchLanes], py[2][kBatchLanes], pz[2][kBatchLanes];
    float qx[2][kBatchLanes], qy[2][kBatchLanes], qz[2][kBatchLanes], qw[2][kBatchLanes];
    float ax[2][kBatchLanes], ay[2][kBatchLanes], az[2][kBatchLanes];
};

/// The step's softness of the rigid rows: impulse = -massScale * K^-1 (J v + biasRate * C) - impulseScale * total.
struct BallJointSoftness {
    float biasRate = 0, massScale = 1, impulseScale = 0;
};

namespace ball_joint_kernels {

using contact_kernels::at3;
using contact_kernels::IndexOf;
using contact_kernels::loadMasses;
using contact_kernels::loadRows;
using contact_kernels::MassW;
using contact_kernels::RowW;
using contact_kernels::storeRows;
using simd::Vec3W;

template <class F>
void put3(float* x, float* y, float* z, std::size_t lane, const Vec3W<F>& v) {
    simd::store(x + lane, v.x);
    simd::store(y + lane, v.y);
    simd::store(z + lane, v.z);
}

/// The two bodies of a batch's lanes: velocities and masses in, impulses applied, velocities out.
template <class F>
struct Sides {
    IndexOf<F> writeA, writeB;
    Vec3W<F> vA, wA, vB, wB;
    MassW<F> massA, massB;

    [[gnu::always_inline]] Sides(const BallJointBatch& b, std::size_t lane, const BodyRows& rows) {
        massA = loadMasses<F>(rows.mass, b.bodyA + lane);
        massB = loadMasses<F>(rows.mass, b.bodyB + lane);
        const IndexOf<F> scratch(rows.scratchRow);
        writeA = simd::select(massA.inverseMass > F(0.0f), simd::loadInt<IndexOf<F>>(b.bodyA + lane), scratch);
        writeB = simd::select(massB.inverseMass > F(0.0f), simd::loadInt<IndexOf<F>>(b.bodyB + lane), scratch);
        const RowW<F> a = loadRows<F>(rows.velocity, b.bodyA + lane), c = loadRows<F>(rows.velocity, b.bodyB + lane);
        vA = a.linear, wA = a.angular, vB = c.linear, wB = c.angular;
    }
    /// Impulse p on B at rB, -p on A at rA.
    void apply(const Vec3W<F>& rA, const Vec3W<F>& rB, const Vec3W<F>& p) {
        vA -= p * massA.inverseMass;
        wA -= massA.inverseInertia * cross(rA, p);
        vB += p * massB.inverseMass;
        wB += massB.inverseInertia * cross(rB, p);
    }
    void store(const BodyRows& rows) const {
        // A before B: when both are the scratch row the value written there does not matter.
        storeRows<F>(rows.velocity, writeA, vA, wA);
        storeRows<F>(rows.velocity, writeB, vB, wB);
    }
};

/// A body's rotation since the step's start from its motion row (2 x the vector part of the unit quaternion, w >= 0).
template <class F>
simd::QuatW<F> rotationOf(const Vec3W<F>& motion) {
    const Vec3W<F> u = motion * F(0.5f);
    return {u.x, u.y, u.z, simd::sqrt(simd::max(F(1.0f) - dot(u, u), F(0.0f)))};
}

/// K += m 1 - [r]x I [r]x: how an impulse at the anchor r changes the anchor's velocity (the scalar rows' formula,
/// operation for operation, so both agree bit for bit).
template <class F>
void addPointMass(simd::SymMat3W<F>& k, const MassW<F>& mass, const Vec3W<F>& r) {
    const F zero(0.0f), one(1.0f);
    const simd::SymMat3W<F>& inertia = mass.inverseInertia;
    const Vec3W<F> cx = cross(inertia * cross(r, Vec3W<F>{one, zero, zero}), r);
    const Vec3W<F> cy = cross(inertia * cross(r, Vec3W<F>{zero, one, zero}), r);
    const Vec3W<F> cz = cross(inertia * cross(r, Vec3W<F>{zero, zero, one}), r);
    k.xx += mass.inverseMass + cx.x, k.yy += mass.inverseMass + cy.y, k.zz += mass.inverseMass + cz.z;
    k.xy += cy.x, k.xz += cz.x, k.yz += cz.y;
}

/// The step's frames of a batch whose body rows are set, from its lanes' poses (the effective masses follow the
/// anchors: begin()).
template <class F>
RUBBLE_FLATTEN void build(BallJointBatch& b, const BallJointPoses& p) {
    Vec3W<F> r[2], centre[2];
    for (int side = 0; side < 2; ++side) {
        const simd::QuatW<F> q = simd::QuatW<F>::load(p.qx[side], p.qy[side], p.qz[side], p.qw[side], 0);
        r[side] = rotate(q, Vec3W<F>::load(p.ax[side], p.ay[side], p.az[side], 0));
        centre[side] = Vec3W<F>::load(p.px[side], p.py[side], p.pz[side], 0);
    }
    put3(b.frameAx, b.frameAy, b.frameAz, 0, r[0]);
    put3(b.frameBx, b.frameBy, b.frameBz, 0, r[1]);
    put3(b.centresX, b.centresY, b.centresZ, 0, centre[1] - centre[0]);
}

/// The inverse of the point rows' effective mass at the anchors rA, rB into the batch's lanes from `lane`.
template <class F>
void storePointMass(BallJointBatch& b, std::size_t lane, const MassRow* mass, const Vec3W<F>& rA, const Vec3W<F>& rB) {
    const F zero(0.0f);
    simd::SymMat3W<F> k{zero, zero, zero, zero, zero, zero};
    addPointMass(k, loadMasses<F>(mass, b.bodyA + lane), rA);
    addPointMass(k, loadMasses<F>(mass, b.bodyB + lane), rB);
    // Its inverse by cofactors; zero where K is singular (no mass on either side: an empty lane).
    const F c00 = k.yy * k.zz - k.yz * k.yz;
    const F c01 = k.xz * k.yz - k.xy * k.zz;
    const F c02 = k.xy * k.yz - k.xz * k.yy;
    const F det = k.xx * c00 + k.xy * c01 + k.xz * c02;
    const auto positive = det > zero;
    const F inv = F(1.0f) / simd::select(positive, det, F(1.0f));
    const F entries[6] = {c00 * inv, (k.xx * k.zz - k.xz * k.xz) * inv, (k.xx * k.yy - k.xy * k.xy) * inv, c01 * inv,
                          c02 * inv, (k.xy * k.xz - k.xx * k.yz) * inv};
    for (int e = 0; e < 6; ++e) simd::store(b.pointMass[e] + lane, simd::select(positive, entries[e], zero));
}

template <class F>
RUBBLE_FLATTEN void begin(BallJointBatch& b, std::size_t lane, const BodyRows& rows, bool warm) {
    const RowW<F> motionA = loadRows<F>(rows.motion, b.bodyA + lane);
    const RowW<F> motionB = loadRows<F>(rows.motion, b.bodyB + lane);
    const Vec3W<F> rA = rotate(rotationOf(motionA.angular), at3<F>(b.frameAx, b.frameAy, b.frameAz, lane));
    const Vec3W<F> rB = rotate(rotationOf(motionB.angular), at3<F>(b.frameBx, b.frameBy, b.frameBz, lane));
    const Vec3W<F> error =
        at3<F>(b.centresX, b.centresY, b.centresZ, lane) + (motionB.linear - motionA.linear) + (rB - rA);
    put3(b.rAx, b.rAy, b.rAz, lane, rA);
    put3(b.rBx, b.rBy, b.rBz, lane, rB);
    put3(b.errorX, b.errorY, b.errorZ, lane, error);
    // The effective mass at this substep's anchors: a light body on a long lever (a cloth of small spheres) turns its
    // anchor far within a step, and the step's first K would then push the wrong way.
    storePointMass<F>(b, lane, rows.mass, rA, rB);
    if (!warm) {
        put3(b.impulseX, b.impulseY, b.impulseZ, lane, Vec3W<F>{F(0.0f), F(0.0f), F(0.0f)});
        return;
    }
    Sides<F> s(b, lane, rows);
    s.apply(rA, rB, at3<F>(b.impulseX, b.impulseY, b.impulseZ, lane));
    s.store(rows);
}

template <class F>
RUBBLE_FLATTEN void solve(BallJointBatch& b, std::size_t lane, const BodyRows& rows, const BallJointSoftness& soft) {
    Sides<F> s(b, lane, rows);
    const Vec3W<F> rA = at3<F>(b.rAx, b.rAy, b.rAz, lane), rB = at3<F>(b.rBx, b.rBy, b.rBz, lane);
    const Vec3W<F> error = at3<F>(b.errorX, b.errorY, b.errorZ, lane);
    const Vec3W<F> total = at3<F>(b.impulseX, b.impulseY, b.impulseZ, lane);
    const simd::SymMat3W<F> mass{
        contact_kernels::at<F>(b.pointMass[0], lane), contact_kernels::at<F>(b.pointMass[1], lane),
        contact_kernels::at<F>(b.pointMass[2], lane), contact_kernels::at<F>(b.pointMass[3], lane),
        contact_kernels::at<F>(b.pointMass[4], lane), contact_kernels::at<F>(b.pointMass[5], lane)};
    const Vec3W<F> velocity = (s.vB + cross(s.wB, rB)) - (s.vA + cross(s.wA, rA));
    const Vec3W<F> rhs = velocity + error * F(soft.biasRate);
    const Vec3W<F> impulse = (mass * rhs) * F(-soft.massScale) - total * F(soft.impulseScale);
    put3(b.impulseX, b.impulseY, b.impulseZ, lane, total + impulse);
    s.apply(rA, rB, impulse);
    s.store(rows);
}

}  // namespace ball_joint_kernels
}  // namespace rubble::detail
