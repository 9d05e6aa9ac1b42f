// Integration stage. Each kernel is written once over a lane type F (simd::FloatW for full batches, float for the
// tail and for the *Scalar reference), so the wide and scalar paths run the same formulas and, where no
// transcendental function is involved, agree bit for bit. Bodies are independent, so chunks run in parallel and
// only the order of the non-finite report needs care (per-chunk lists merged in chunk order).
//
// Integrators (velocities first, then the solver changes v and w, then positions):
//  - semi-implicit Euler (default): v += dt a, w += dt Iw^-1 t, gyroscopic term by one implicit Newton step in the
//    principal frame (Catto, GDC 2015), then damping v /= 1 + c dt; positions use the new velocity.
//  - explicit Euler: the same increments but the gyroscopic torque from the start-of-step w; positions use the
//    start-of-step velocity plus whatever the solver changed (offset d = v0 - v1 kept in the scratch).
//  - Verlet: velocities as semi-implicit; positions use the mean of the start and end velocities (offset
//    -(v1 - v0) / 2), which is exact for constant acceleration.
//  - RK4: classic four-stage Runge-Kutta of the free motion (x, v, q, w) with continuous damping. The offsets are
//    chosen so that integratePositions reproduces the RK4 pose when the solver changes nothing; the orientation
//    goes through the exponential map so the rotation vector round-trips.
#if defined(__GNUC__) && !defined(__clang__)
// GCC 12's SLP vectoriser turns alternating a*b - c / a*b + c lanes of the scalar quaternion product into a fused
// vfmsubadd even under -ffp-contract=off, which breaks scalar/SIMD agreement. The wide kernels are explicit SIMD and
// lose nothing without it. (Before the includes, so every inline function in this file gets the same options.)
#pragma GCC optimize("no-tree-slp-vectorize")
#endif
#include "integrate/integrate.h"

#include <algorithm>
#include <cstddef>

#include "core/parallel.h"
#include "rubble/limits.h"
#include "simd/simd.h"
#include "simd/vec.h"
#include "storage/flag_scan.h"

namespace rubble::detail {
namespace {

using simd::FloatW;
using simd::MaskOf;
using simd::Mat3W;
using simd::QuatW;
using simd::SymMat3W;
using simd::Vec3W;

/// Bodies per parallel chunk: a multiple of the lane count, so only the last chunk has a scalar tail and the
/// result never depends on how chunks are spread over threads.
constexpr std::size_t kChunkSize = 2048;
static_assert(kChunkSize % simd::kLanes == 0, "chunks must hold whole batches");

template <class F>
Vec3W<F> load3(const AlignedVector<float>& x, const AlignedVector<float>& y, const AlignedVector<float>& z,
               std::size_t i) {
    return Vec3W<F>::load(x.data(), y.data(), z.data(), i);
}
template <class F>
void store3(AlignedVector<float>& x, AlignedVector<float>& y, AlignedVector<float>& z, std::size_t i,
            const Vec3W<F>& v) {
    v.store(x.data(), y.data(), z.data(), i);
}

/// Principal frame of a body: rotation to world and the inverse principal moments.
template <class F>
struct Principal {
    Mat3W<F> r;
    Vec3W<F> invI;
    Vec3W<F> inertia;     ///< principal moments 1 / invI (0 where the axis is locked)
    MaskOf<F> allMobile;  ///< every axis free: the gyroscopic term applies
};

template <class F>
Principal<F> principalFrame(const QuatW<F>& q, const QuatW<F>& ir, const Vec3W<F>& invI) {
    Principal<F> p;
    p.r = simd::rotationMatrix(q * ir);
    p.invI = invI;
    const F zero(0.0f), one(1.0f);
    const auto mobileX = invI.x > zero, mobileY = invI.y > zero, mobileZ = invI.z > zero;
    // Divide by 1 on locked axes so no inf appears even in lanes that are later discarded.
    p.inertia = {simd::select(mobileX, one / simd::select(mobileX, invI.x, one), zero),
                 simd::select(mobileY, one / simd::select(mobileY, invI.y, one), zero),
                 simd::select(mobileZ, one / simd::select(mobileZ, invI.z, one), zero)};
    p.allMobile = simd::andMask(simd::andMask(mobileX, mobileY), mobileZ);
    return p;
}

/// Gyroscopic torque w x (I w) in world coordinates, zero where an axis is locked.
template <class F>
Vec3W<F> gyroscopicTorqueWorld(const Principal<F>& p, const Vec3W<F>& w) {
    const Vec3W<F> wp = transposeMultiply(p.r, w);
    const Vec3W<F> gp = cross(wp, p.inertia * wp);
    return simd::select(p.allMobile, p.r * gp, Vec3W<F>::zero());
}

/// One Newton step of the implicit gyroscopic update I (w2 - w1) + dt w2 x (I w2) = 0 from w1, in the principal
/// frame (Catto, "Numerical Methods", GDC 2015). Stable for long, thin bodies where the explicit term gains energy.
template <class F>
Vec3W<F> implicitGyroscopic(const Principal<F>& p, const Vec3W<F>& w1, const F& dt) {
    const Vec3W<F> w = transposeMultiply(p.r, w1);
    const Vec3W<F> i = p.inertia;
    const Vec3W<F> l = i * w;  // angular momentum, principal frame
    const Vec3W<F> residual = cross(w, l) * dt;
    // J = I + dt (skew(w) I - skew(I w)); skew(a) = [0 -az ay; az 0 -ax; -ay ax 0]
    Mat3W<F> j;
    j.m[0][0] = i.x;
    j.m[1][1] = i.y;
    j.m[2][2] = i.z;
    j.m[0][1] = dt * (l.z - w.z * i.y);
    j.m[0][2] = dt * (w.y * i.z - l.y);
    j.m[1][0] = dt * (w.z * i.x - l.z);
    j.m[1][2] = dt * (l.x - w.x * i.z);
    j.m[2][0] = dt * (l.y - w.y * i.x);
    j.m[2][1] = dt * (w.x * i.y - l.x);
    F det;
    const Vec3W<F> delta = simd::solve(j, residual, det);
    const Vec3W<F> w2 = p.r * (w - delta);
    return simd::select(simd::andMask(p.allMobile, isFinite(delta)), w2, w1);
}

/// Body parameters every velocity kernel reads.
template <class F>
struct VelocityInputs {
    Vec3W<F> v, w, f, t;
    QuatW<F> q, ir;
    Vec3W<F> invI;
    F invMass, gravityScale, linearDamping, angularDamping;
};

template <class F>
VelocityInputs<F> loadVelocityInputs(const MovingBodies& b, bool forces, std::size_t i) {
    VelocityInputs<F> in;
    in.v = load3<F>(b.vx, b.vy, b.vz, i);
    in.w = load3<F>(b.wx, b.wy, b.wz, i);
    if (forces) {
        in.f = load3<F>(b.fx, b.fy, b.fz, i);
        in.t = load3<F>(b.tx, b.ty, b.tz, i);
    } else {
        in.f = in.t = Vec3W<F>::zero();
    }
    in.q = QuatW<F>::load(b.qx.data(), b.qy.data(), b.qz.data(), b.qw.data(), i);
    in.ir = QuatW<F>::load(b.irx.data(), b.iry.data(), b.irz.data(), b.irw.data(), i);
    in.invI = load3<F>(b.invIx, b.invIy, b.invIz, i);
    in.invMass = simd::load<F>(b.invMass.data() + i);
    in.gravityScale = simd::load<F>(b.gravityScale.data() + i);
    in.linearDamping = simd::load<F>(b.linearDamping.data() + i);
    in.angularDamping = simd::load<F>(b.angularDamping.data() + i);
    return in;
}

/// Result of a velocity kernel before it is committed.
template <class F>
struct VelocityResult {
    Vec3W<F> v, w;
    Vec3W<F> d, e;  ///< offsets for integratePositions (unused by the default integrator)
};

/// Semi-implicit / explicit Euler and Verlet share everything but the gyroscopic term and the offsets.
template <class F, Integrator I>
VelocityResult<F> eulerVelocities(const VelocityInputs<F>& in, const Principal<F>& p, const SymMat3W<F>& iw,
                                  const Vec3W<F>& gravity, const F& dt, bool rotation) {
    const F one(1.0f);
    VelocityResult<F> r;
    const Vec3W<F> a = gravity * in.gravityScale + in.f * in.invMass;
    r.v = (in.v + a * dt) * (one / (one + dt * in.linearDamping));
    if (rotation) {
        Vec3W<F> w;
        if constexpr (I == Integrator::ExplicitEuler) {
            w = in.w + (iw * (in.t - gyroscopicTorqueWorld(p, in.w))) * dt;
        } else {
            w = implicitGyroscopic(p, in.w + (iw * in.t) * dt, dt);
        }
        r.w = w * (one / (one + dt * in.angularDamping));
    } else {
        r.w = in.w;
    }
    if constexpr (I == Integrator::ExplicitEuler) {
        r.d = in.v - r.v;
        r.e = in.w - r.w;
    } else if constexpr (I == Integrator::Verlet) {
        const F half(0.5f);
        r.d = (in.v - r.v) * half;
        r.e = (in.w - r.w) * half;
    } else {
        r.d = r.e = Vec3W<F>::zero();
    }
    return r;
}

/// Time derivative of (v, q, w) for RK4 (x' = v needs no evaluation).
template <class F>
struct Rk4Derivative {
    Vec3W<F> dv, dw;
    QuatW<F> dq;
};

template <class F>
Rk4Derivative<F> rk4Derivative(const VelocityInputs<F>& in, const Vec3W<F>& accel, const Vec3W<F>& v, const QuatW<F>& q,
                               const Vec3W<F>& w, bool rotation) {
    Rk4Derivative<F> k;
    k.dv = accel - v * in.linearDamping;
    if (rotation) {
        // Intermediate stages are not unit quaternions; the inertia uses the rotation they represent.
        const Principal<F> p = principalFrame(simd::normalize(q), in.ir, in.invI);
        const Vec3W<F> wp = transposeMultiply(p.r, w);
        const Vec3W<F> gyro = simd::select(p.allMobile, cross(wp, p.inertia * wp), Vec3W<F>::zero());
        const Vec3W<F> tp = transposeMultiply(p.r, in.t);
        k.dw = p.r * (p.invI * (tp - gyro)) - w * in.angularDamping;
        k.dq = (QuatW<F>::pure(w) * q) * F(0.5f);
    } else {
        k.dw = Vec3W<F>::zero();
        k.dq = QuatW<F>(F(0.0f), F(0.0f), F(0.0f), F(0.0f));
    }
    return k;
}

/// Rotation vector of the unit quaternion q (axis times angle, angle in [0, pi]).
template <class F>
Vec3W<F> rotationVector(QuatW<F> q) {
    const F zero(0.0f), two(2.0f);
    q = simd::select(q.w < zero, QuatW<F>(-q.x, -q.y, -q.z, -q.w), q);
    const Vec3W<F> u = q.vec();
    const F s = length(u);
    // angle / s = 2 atan2(s, w) / s, which tends to 2 / w as s -> 0 (w -> 1).
    const F scale = simd::select(s > zero, two * simd::atan2(s, q.w) / simd::select(s > zero, s, F(1.0f)), two / q.w);
    return u * scale;
}

/// exp of the pure quaternion h (half the rotation vector): (sin|h| h/|h|, cos|h|).
template <class F>
QuatW<F> expPure(const Vec3W<F>& h) {
    const F zero(0.0f), one(1.0f);
    const F theta = length(h);
    const F sinc = simd::select(theta > zero, simd::sin(theta) / simd::select(theta > zero, theta, one), one);
    return {h.x * sinc, h.y * sinc, h.z * sinc, simd::cos(theta)};
}

template <class F>
VelocityResult<F> rk4Velocities(const VelocityInputs<F>& in, const Vec3W<F>& gravity, const F& dt, bool rotation) {
    const F half(0.5f), two(2.0f), sixth(1.0f / 6.0f);
    const F h = dt * half;
    const Vec3W<F> accel = gravity * in.gravityScale + in.f * in.invMass;

    const Vec3W<F> v1 = in.v;
    const QuatW<F> q1 = in.q;
    const Vec3W<F> w1 = in.w;
    const Rk4Derivative<F> k1 = rk4Derivative(in, accel, v1, q1, w1, rotation);
    const Vec3W<F> v2 = in.v + k1.dv * h;
    const QuatW<F> q2 = in.q + k1.dq * h;
    const Vec3W<F> w2 = in.w + k1.dw * h;
    const Rk4Derivative<F> k2 = rk4Derivative(in, accel, v2, q2, w2, rotation);
    const Vec3W<F> v3 = in.v + k2.dv * h;
    const QuatW<F> q3 = in.q + k2.dq * h;
    const Vec3W<F> w3 = in.w + k2.dw * h;
    const Rk4Derivative<F> k3 = rk4Derivative(in, accel, v3, q3, w3, rotation);
    const Vec3W<F> v4 = in.v + k3.dv * dt;
    const QuatW<F> q4 = in.q + k3.dq * dt;
    const Vec3W<F> w4 = in.w + k3.dw * dt;
    const Rk4Derivative<F> k4 = rk4Derivative(in, accel, v4, q4, w4, rotation);

    const F step = dt * sixth;
    VelocityResult<F> r;
    r.v = in.v + (k1.dv + (k2.dv + k3.dv) * two + k4.dv) * step;
    // Mean velocity over the step (x_rk4 - x0) / dt, kept as an offset from the end velocity.
    const Vec3W<F> meanV = (v1 + (v2 + v3) * two + v4) * sixth;
    r.d = meanV - r.v;
    if (rotation) {
        r.w = in.w + (k1.dw + (k2.dw + k3.dw) * two + k4.dw) * step;
        const QuatW<F> q = simd::normalize(in.q + (k1.dq + (k2.dq + k3.dq) * two + k4.dq) * step);
        r.e = rotationVector(q * simd::conjugate(in.q)) / dt - r.w;
    } else {
        r.w = in.w;
        r.e = Vec3W<F>::zero();
    }
    return r;
}

/// Integrates the velocities of the bodies [i, i + lanes) and commits the lanes whose result is finite.
/// Returns the mask of lanes left unchanged because something became non-finite.
// flatten: GCC otherwise keeps some of the small helpers out of line and passes whole batches through memory.
template <class F, Integrator I>
RUBBLE_FLATTEN MaskOf<F> velocityKernel(MovingBodies& b, const IntegrationParams& params, IntegrationScratch& s,
                                        std::size_t i) {
    const VelocityInputs<F> in = loadVelocityInputs<F>(b, params.forces, i);
    const F dt(params.dt);
    const Vec3W<F> gravity = Vec3W<F>::broadcast(params.gravity.x, params.gravity.y, params.gravity.z);

    const Principal<F> p = principalFrame(in.q, in.ir, in.invI);
    const SymMat3W<F> iw = simd::rotateDiagonal(p.r, in.invI);

    VelocityResult<F> r;
    if constexpr (I == Integrator::RungeKutta4) {
        r = rk4Velocities(in, gravity, dt, params.rotation);
    } else {
        r = eulerVelocities<F, I>(in, p, iw, gravity, dt, params.rotation);
    }

    MaskOf<F> ok = simd::andMask(simd::andMask(isFinite(r.v), isFinite(r.w)), isFinite(iw));
    if constexpr (I != Integrator::SemiImplicitEuler)
        ok = simd::andMask(ok, simd::andMask(isFinite(r.d), isFinite(r.e)));

    const Vec3W<F> zero = Vec3W<F>::zero();
    store3(b.vx, b.vy, b.vz, i, select(ok, r.v, in.v));
    store3(b.wx, b.wy, b.wz, i, select(ok, r.w, in.w));
    if (params.forces && params.clearForces) {
        store3(b.fx, b.fy, b.fz, i, select(ok, zero, in.f));
        store3(b.tx, b.ty, b.tz, i, select(ok, zero, in.t));
    }
    const SymMat3W<F> iwOld =
        SymMat3W<F>::load(b.iwXX.data(), b.iwYY.data(), b.iwZZ.data(), b.iwXY.data(), b.iwXZ.data(), b.iwYZ.data(), i);
    select(ok, iw, iwOld)
        .store(b.iwXX.data(), b.iwYY.data(), b.iwZZ.data(), b.iwXY.data(), b.iwXZ.data(), b.iwYZ.data(), i);
    if constexpr (I != Integrator::SemiImplicitEuler) {
        store3(s.dx, s.dy, s.dz, i, select(ok, r.d, zero));
        store3(s.ex, s.ey, s.ez, i, select(ok, r.e, zero));
    }
    return simd::notMask(ok);
}

/// Moves the bodies [i, i + lanes); Offsets: add the scratch offsets to v and w; ExpMap: RK4's orientation update.
template <class F, bool Offsets, bool ExpMap>
RUBBLE_FLATTEN MaskOf<F> positionKernel(MovingBodies& b, const IntegrationParams& params, const IntegrationScratch& s,
                                        std::size_t i) {
    const F dt(params.dt);
    const Vec3W<F> x0 = load3<F>(b.px, b.py, b.pz, i);
    Vec3W<F> v = load3<F>(b.vx, b.vy, b.vz, i);
    if constexpr (Offsets) v += Vec3W<F>::load(s.dx.data(), s.dy.data(), s.dz.data(), i);
    const Vec3W<F> x1 = x0 + v * dt;
    // A body leaving the coordinate limit (docs/limits.md) is frozen there as a non-finite one is: farther out, float
    // spacing exceeds the contact slop and the broad phase's cells lose their meaning.
    const MaskOf<F> ok = isWithin(x1, limits::kMaxCoordinate);
    if (!params.rotation) {
        store3(b.px, b.py, b.pz, i, select(ok, x1, x0));
        return simd::notMask(ok);
    }

    const QuatW<F> q0 = QuatW<F>::load(b.qx.data(), b.qy.data(), b.qz.data(), b.qw.data(), i);
    Vec3W<F> w = load3<F>(b.wx, b.wy, b.wz, i);
    if constexpr (Offsets) w += Vec3W<F>::load(s.ex.data(), s.ey.data(), s.ez.data(), i);
    const F h = dt * F(0.5f);
    QuatW<F> q1;
    if constexpr (ExpMap) {
        q1 = simd::normalize(expPure(w * h) * q0);
    } else {
        q1 = simd::normalize(q0 + (QuatW<F>::pure(w) * q0) * h);
    }
    const MaskOf<F> qOk = isFinite(q1);
    // A body is all or nothing: a finite orientation is not applied when the position failed, and vice versa.
    const MaskOf<F> bothOk = simd::andMask(ok, qOk);
    store3(b.px, b.py, b.pz, i, select(bothOk, x1, x0));
    select(bothOk, q1, q0).store(b.qx.data(), b.qy.data(), b.qz.data(), b.qw.data(), i);
    return simd::notMask(bothOk);
}

/// Runs kernel over [begin, end): full batches wide, the tail one body at a time. Flagged indices are appended
/// in ascending order. With `asleep` (the bodies' flags), sleeping bodies are skipped: a batch of sleepers costs one
/// look at its flags, a batch with some runs its awake lanes one at a time.
template <class WideKernel, class ScalarKernel>
void runRange(std::size_t begin, std::size_t end, bool wide, const std::uint8_t* asleep, WideKernel&& wideKernel,
              ScalarKernel&& scalarKernel, std::vector<std::uint32_t>& flagged) {
    const auto scalar = [&](std::size_t i) {
        if (asleep != nullptr && (asleep[i] & kFlagAsleep)) return;
        if (scalarKernel(i)) flagged.push_back(static_cast<std::uint32_t>(i));
    };
    std::size_t i = begin;
    if (wide) {
        const std::size_t wideEnd = begin + simd::roundDownToLanes<FloatW>(end - begin);
        for (; i < wideEnd; i += simd::kLanes) {
            if (asleep != nullptr) {
                const std::size_t sleepers = countWith(asleep + i, simd::kLanes, kFlagAsleep);
                if (sleepers == simd::kLanes) continue;
                if (sleepers != 0) {
                    for (std::size_t k = 0; k < simd::kLanes; ++k) scalar(i + k);
                    continue;
                }
            }
            const auto bad = wideKernel(i);
            simd::forEachSetLane(bad, [&](std::size_t k) { flagged.push_back(static_cast<std::uint32_t>(i + k)); });
        }
    }
    for (; i < end; ++i) scalar(i);
}

/// Splits [0, count) into chunks on the pool (inline when it is one chunk) and merges the flagged indices of
/// the chunks in chunk order.
template <class Body>
void runChunks(std::size_t count, TaskPool* pool, Body&& body, std::vector<std::uint32_t>& nonFinite) {
    if (pool == nullptr || count <= kChunkSize) {
        body(std::size_t{0}, count, nonFinite);
        return;
    }
    std::vector<std::vector<std::uint32_t>> perChunk(TaskPool::chunkCount(count, kChunkSize));
    pool->forChunks(count, kChunkSize, [&](std::size_t chunk, std::size_t begin, std::size_t end, int) {
        body(begin, end, perChunk[chunk]);
    });
    for (const auto& c : perChunk) nonFinite.insert(nonFinite.end(), c.begin(), c.end());
}

template <Integrator I>
void velocities(MovingBodies& b, const IntegrationParams& params, IntegrationScratch& s, TaskPool* pool, bool wide,
                std::vector<std::uint32_t>& nonFinite) {
    runChunks(
        b.size(), pool,
        [&](std::size_t begin, std::size_t end, std::vector<std::uint32_t>& flagged) {
            runRange(
                begin, end, wide, params.skipAsleep ? b.flags.data() : nullptr,
                [&](std::size_t i) { return velocityKernel<FloatW, I>(b, params, s, i); },
                [&](std::size_t i) { return velocityKernel<float, I>(b, params, s, i); }, flagged);
        },
        nonFinite);
}

template <bool Offsets, bool ExpMap>
void positions(MovingBodies& b, const IntegrationParams& params, const IntegrationScratch& s, TaskPool* pool, bool wide,
               std::vector<std::uint32_t>& nonFinite) {
    runChunks(
        b.size(), pool,
        [&](std::size_t begin, std::size_t end, std::vector<std::uint32_t>& flagged) {
            runRange(
                begin, end, wide, params.skipAsleep ? b.flags.data() : nullptr,
                [&](std::size_t i) { return positionKernel<FloatW, Offsets, ExpMap>(b, params, s, i); },
                [&](std::size_t i) { return positionKernel<float, Offsets, ExpMap>(b, params, s, i); }, flagged);
        },
        nonFinite);
}

void integrateVelocitiesImpl(MovingBodies& b, const IntegrationParams& params, IntegrationScratch& s, TaskPool* pool,
                             bool wide, std::vector<std::uint32_t>& nonFinite) {
    if (params.integrator != Integrator::SemiImplicitEuler) {
        const std::size_t n = b.size();
        for (auto* a : {&s.dx, &s.dy, &s.dz, &s.ex, &s.ey, &s.ez}) a->resize(n);
    }
    switch (params.integrator) {
        case Integrator::SemiImplicitEuler:
            velocities<Integrator::SemiImplicitEuler>(b, params, s, pool, wide, nonFinite);
            break;
        case Integrator::ExplicitEuler:
            velocities<Integrator::ExplicitEuler>(b, params, s, pool, wide, nonFinite);
            break;
        case Integrator::Verlet:
            velocities<Integrator::Verlet>(b, params, s, pool, wide, nonFinite);
            break;
        case Integrator::RungeKutta4:
            velocities<Integrator::RungeKutta4>(b, params, s, pool, wide, nonFinite);
            break;
    }
}

void integratePositionsImpl(MovingBodies& b, const IntegrationParams& params, const IntegrationScratch& s,
                            TaskPool* pool, bool wide, std::vector<std::uint32_t>& nonFinite) {
    // Offsets exist only when integrateVelocities ran with the same non-default integrator on the same bodies.
    const bool offsets =
        params.integrator != Integrator::SemiImplicitEuler && s.dx.size() == b.size() && s.ex.size() == b.size();
    const bool expMap = params.integrator == Integrator::RungeKutta4;
    if (offsets) {
        if (expMap)
            positions<true, true>(b, params, s, pool, wide, nonFinite);
        else
            positions<true, false>(b, params, s, pool, wide, nonFinite);
    } else {
        if (expMap)
            positions<false, true>(b, params, s, pool, wide, nonFinite);
        else
            positions<false, false>(b, params, s, pool, wide, nonFinite);
    }
}

}  // namespace

void integrateVelocities(MovingBodies& bodies, const IntegrationParams& params, IntegrationScratch& scratch,
                         TaskPool& pool, std::vector<std::uint32_t>& nonFinite) {
    integrateVelocitiesImpl(bodies, params, scratch, &pool, true, nonFinite);
}

void integratePositions(MovingBodies& bodies, const IntegrationParams& params, const IntegrationScratch& scratch,
                        TaskPool& pool, std::vector<std::uint32_t>& nonFinite) {
    integratePositionsImpl(bodies, params, scratch, &pool, true, nonFinite);
}

void integrateVelocitiesScalar(MovingBodies& bodies, const IntegrationParams& params, IntegrationScratch& scratch,
                               std::vector<std::uint32_t>& nonFinite) {
    integrateVelocitiesImpl(bodies, params, scratch, nullptr, false, nonFinite);
}

void integratePositionsScalar(MovingBodies& bodies, const IntegrationParams& params, const IntegrationScratch& scratch,
                              std::vector<std::uint32_t>& nonFinite) {
    integratePositionsImpl(bodies, params, scratch, nullptr, false, nonFinite);
}

}  // namespace rubble::detail
