// Integration stage, tested on MovingBodies filled here: the wide (SIMD) and scalar kernels agree, threads do
// not change the result, kinematic bodies and accumulators behave, non-finite results are refused and reported,
// and the world inverse inertia matches an independent Eigen computation.
#include <gtest/gtest.h>

#include "support/print.h"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "core/parallel.h"
#include "integrate/integrate.h"
#include "simd/simd.h"
#include "simd/vec.h"
#include "storage/body_storage.h"

namespace rubble::detail {
namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr Integrator kIntegrators[] = {Integrator::SemiImplicitEuler, Integrator::ExplicitEuler, Integrator::Verlet,
                                       Integrator::RungeKutta4};

std::uint32_t addBody(MovingBodies& b) {
    const std::uint32_t i = b.pushBack();
    b.qw[i] = 1;
    b.irw[i] = 1;
    b.slot[i] = i;
    return i;
}

void setDynamic(MovingBodies& b, std::uint32_t i, float mass, Vec3 principalMoments) {
    b.invMass[i] = 1.0f / mass;
    b.invIx[i] = 1.0f / principalMoments.x;
    b.invIy[i] = 1.0f / principalMoments.y;
    b.invIz[i] = 1.0f / principalMoments.z;
    b.gravityScale[i] = 1;
}

Quat randomUnitQuat(std::mt19937& rng) {
    std::normal_distribution<float> n;
    Quat q{n(rng), n(rng), n(rng), n(rng)};
    const float len = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    return {q.x / len, q.y / len, q.z / len, q.w / len};
}

/// Dynamic bodies with random state, some with locked rotation axes, some kinematic.
MovingBodies randomBodies(std::size_t count, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), pos(0.1f, 1.0f);
    MovingBodies b;
    for (std::size_t k = 0; k < count; ++k) {
        const std::uint32_t i = addBody(b);
        b.px[i] = 50 * u(rng), b.py[i] = 50 * u(rng), b.pz[i] = 50 * u(rng);
        const Quat q = randomUnitQuat(rng);
        b.qx[i] = q.x, b.qy[i] = q.y, b.qz[i] = q.z, b.qw[i] = q.w;
        b.vx[i] = 5 * u(rng), b.vy[i] = 5 * u(rng), b.vz[i] = 5 * u(rng);
        b.wx[i] = 4 * u(rng), b.wy[i] = 4 * u(rng), b.wz[i] = 4 * u(rng);
        const int kind = static_cast<int>(k % 7);
        if (kind == 6) {  // kinematic
            b.flags[i] = kFlagKinematic;
            continue;
        }
        b.fx[i] = 20 * u(rng), b.fy[i] = 20 * u(rng), b.fz[i] = 20 * u(rng);
        b.tx[i] = 3 * u(rng), b.ty[i] = 3 * u(rng), b.tz[i] = 3 * u(rng);
        setDynamic(b, i, 0.5f + 10 * pos(rng), {pos(rng), pos(rng), pos(rng)});
        if (kind == 5) b.invIx[i] = b.invIz[i] = 0;  // rotation locked about two axes
        const Quat ir = randomUnitQuat(rng);
        b.irx[i] = ir.x, b.iry[i] = ir.y, b.irz[i] = ir.z, b.irw[i] = ir.w;
        b.linearDamping[i] = k % 3 == 0 ? 0.0f : pos(rng);
        b.angularDamping[i] = k % 4 == 0 ? 0.0f : pos(rng);
        b.gravityScale[i] = 2 * pos(rng);
    }
    return b;
}

IntegrationParams paramsFor(Integrator integrator, bool rotation = true) {
    IntegrationParams p;
    p.dt = kDt;
    p.gravity = {0.0f, -9.81f, 0.0f};
    p.rotation = rotation;
    p.integrator = integrator;
    return p;
}

std::vector<const AlignedVector<float>*> stateArrays(const MovingBodies& b) {
    return {&b.px, &b.py, &b.pz, &b.qx, &b.qy, &b.qz, &b.qw,   &b.vx,   &b.vy,   &b.vz,   &b.wx,   &b.wy,  &b.wz,
            &b.fx, &b.fy, &b.fz, &b.tx, &b.ty, &b.tz, &b.iwXX, &b.iwYY, &b.iwZZ, &b.iwXY, &b.iwXZ, &b.iwYZ};
}
const char* const kStateNames[] = {"px", "py",   "pz",   "qx",   "qy",   "qz",   "qw",  "vx", "vy",
                                   "vz", "wx",   "wy",   "wz",   "fx",   "fy",   "fz",  "tx", "ty",
                                   "tz", "iwXX", "iwYY", "iwZZ", "iwXY", "iwXZ", "iwYZ"};

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// Counts entries that differ in any bit; reports the first few.
int countBitDifferences(const MovingBodies& a, const MovingBodies& b) {
    const auto sa = stateArrays(a), sb = stateArrays(b);
    int differences = 0;
    for (std::size_t f = 0; f < sa.size(); ++f) {
        int inField = 0;
        for (std::size_t i = 0; i < sa[f]->size(); ++i)
            if (!sameBits((*sa[f])[i], (*sb[f])[i]) && ++inField <= 2)
                ADD_FAILURE() << kStateNames[f] << "[" << i << "]: " << (*sa[f])[i] << " vs " << (*sb[f])[i];
        differences += inField;
    }
    return differences;
}

void stepWide(MovingBodies& b, const IntegrationParams& p, IntegrationScratch& s, TaskPool& pool,
              std::vector<std::uint32_t>& bad) {
    integrateVelocities(b, p, s, pool, bad);
    integratePositions(b, p, s, pool, bad);
}

void stepScalar(MovingBodies& b, const IntegrationParams& p, IntegrationScratch& s, std::vector<std::uint32_t>& bad) {
    integrateVelocitiesScalar(b, p, s, bad);
    integratePositionsScalar(b, p, s, bad);
}

// ---------------------------------------------------------------------------------------------------------------

TEST(SimdVocabulary, WideOperationsMatchScalarLaneByLane) {
    using simd::FloatW;
    alignas(64) float a[simd::kLanes], b[simd::kLanes];
    const float specials[] = {
        0.0f,   -0.0f, 1.5f, -2.25f, std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN(),
        1e-40f, 3e38f};
    for (std::size_t k = 0; k < simd::kLanes; ++k) {
        a[k] = specials[k % 8];
        b[k] = specials[(k * 3 + 1) % 8];
    }
    const FloatW wa = simd::load<FloatW>(a), wb = simd::load<FloatW>(b);
    for (std::size_t k = 0; k < simd::kLanes; ++k) {
        EXPECT_TRUE(sameBits(simd::lane(simd::min(wa, wb), k), simd::min(a[k], b[k]))) << k;
        EXPECT_TRUE(sameBits(simd::lane(simd::max(wa, wb), k), simd::max(a[k], b[k]))) << k;
        EXPECT_TRUE(sameBits(simd::lane(simd::abs(wa), k), simd::abs(a[k]))) << k;
        EXPECT_TRUE(sameBits(simd::lane(simd::sqrt(simd::abs(wa)), k), simd::sqrt(simd::abs(a[k])))) << k;
        EXPECT_EQ(simd::lane(simd::isFinite(wa), k), simd::isFinite(a[k])) << k;
        EXPECT_TRUE(sameBits(simd::lane(simd::select(wa < wb, wa, wb), k), simd::select(a[k] < b[k], a[k], b[k])));
    }
    std::vector<std::size_t> lanes;
    simd::forEachSetLane(simd::laneIndices<FloatW>() > FloatW(static_cast<float>(simd::kLanes) - 3.5f),
                         [&](std::size_t k) { lanes.push_back(k); });
    EXPECT_EQ(lanes, (std::vector<std::size_t>{simd::kLanes - 3, simd::kLanes - 2, simd::kLanes - 1}));
    EXPECT_EQ(simd::reduceAdd(FloatW(1.0f)), static_cast<float>(simd::kLanes));
}

TEST(SimdVocabulary, QuaternionRotationMatchesMatrix) {
    std::mt19937 rng(7);
    for (int n = 0; n < 100; ++n) {
        const Quat q = randomUnitQuat(rng);
        const simd::QuatW<float> qw{q.x, q.y, q.z, q.w};
        const simd::Vec3W<float> v{0.3f, -1.2f, 2.0f};
        const auto a = simd::rotate(qw, v);
        const auto b = simd::rotationMatrix(qw) * v;
        const Vec3 c = rotate(q, Vec3{0.3f, -1.2f, 2.0f});
        EXPECT_NEAR(a.x, b.x, 1e-5f);
        EXPECT_NEAR(a.y, b.y, 1e-5f);
        EXPECT_NEAR(a.z, b.z, 1e-5f);
        EXPECT_TRUE(sameBits(a.x, c.x) && sameBits(a.y, c.y) && sameBits(a.z, c.z));
        const auto back = simd::rotateInverse(qw, a);
        EXPECT_NEAR(back.x, v.x, 1e-5f);
        EXPECT_NEAR(back.y, v.y, 1e-5f);
        EXPECT_NEAR(back.z, v.z, 1e-5f);
    }
}

// ---------------------------------------------------------------------------------------------------------------

class IntegratorAgreement : public ::testing::TestWithParam<Integrator> {};

// 10,007 bodies: not a multiple of any lane width, more than two chunks, so batches, the scalar tail and the
// chunked parallel path all run. Euler family and Verlet are bit-identical; RK4 differs only where sin, cos and
// atan2 are involved (the angular offset and the exponential map of the orientation).
TEST_P(IntegratorAgreement, WideAndScalarPathsAgree) {
    const Integrator integrator = GetParam();
    const IntegrationParams p = paramsFor(integrator);
    MovingBodies wide = randomBodies(10007, 42);
    MovingBodies scalar = wide;
    IntegrationScratch sw, ss;
    TaskPool pool(2);
    std::vector<std::uint32_t> badWide, badScalar;
    const int steps = integrator == Integrator::RungeKutta4 ? 1 : 3;
    for (int step = 0; step < steps; ++step) {
        stepWide(wide, p, sw, pool, badWide);
        stepScalar(scalar, p, ss, badScalar);
    }
    EXPECT_TRUE(badWide.empty());
    EXPECT_TRUE(badScalar.empty());
    if (integrator != Integrator::RungeKutta4) {
        EXPECT_EQ(countBitDifferences(wide, scalar), 0);
        return;
    }
    // RK4, one step: velocities, positions and inertia are bit-identical; the orientation (exponential map: sin,
    // cos) and the angular offset (atan2) differ by a few ulps. Measured: |dq| <= 9e-8 (about an ulp of components
    // near 1) and |de| <= 1e-6 rad/s (ulps of the ~0.07 rad rotation vector divided by dt); bounds 1e-6, 1e-4.
    const auto sa = stateArrays(wide), sb = stateArrays(scalar);
    float maxQ = 0, maxE = 0;
    for (std::size_t f = 0; f < sa.size(); ++f) {
        const bool orientation = f >= 3 && f <= 6;
        for (std::size_t i = 0; i < sa[f]->size(); ++i) {
            const float a = (*sa[f])[i], b = (*sb[f])[i];
            if (orientation)
                maxQ = std::max(maxQ, std::fabs(a - b));
            else if (!sameBits(a, b))
                ADD_FAILURE() << kStateNames[f] << "[" << i << "]: " << a << " vs " << b;
        }
    }
    for (std::size_t i = 0; i < wide.size(); ++i) {
        ASSERT_TRUE(sameBits(sw.dx[i], ss.dx[i]) && sameBits(sw.dy[i], ss.dy[i]) && sameBits(sw.dz[i], ss.dz[i]));
        maxE = std::max(
            {maxE, std::fabs(sw.ex[i] - ss.ex[i]), std::fabs(sw.ey[i] - ss.ey[i]), std::fabs(sw.ez[i] - ss.ez[i])});
    }
    EXPECT_LT(maxQ, 1e-6f);
    EXPECT_LT(maxE, 1e-4f);
    std::printf("RK4 wide vs scalar after one step: max |dq| = %g, max |de| = %g\n", maxQ, maxE);
    // Later steps start from orientations that differ by those ulps, so everything then agrees only closely.
    for (int step = 0; step < 9; ++step) {
        stepWide(wide, p, sw, pool, badWide);
        stepScalar(scalar, p, ss, badScalar);
    }
    float maxRel = 0;
    for (std::size_t f = 0; f < sa.size(); ++f)
        for (std::size_t i = 0; i < sa[f]->size(); ++i) {
            const float a = (*sa[f])[i], b = (*sb[f])[i];
            maxRel = std::max(maxRel, std::fabs(a - b) / std::max(1.0f, std::fabs(b)));
        }
    std::printf("RK4 wide vs scalar after ten steps: max relative difference %g\n", maxRel);
    EXPECT_LT(maxRel, 1e-5f);
}

TEST_P(IntegratorAgreement, ThreadCountDoesNotChangeTheResult) {
    const IntegrationParams p = paramsFor(GetParam());
    MovingBodies one = randomBodies(10007, 3);
    MovingBodies two = one;
    IntegrationScratch s1, s2;
    TaskPool pool1(1), pool2(2);
    std::vector<std::uint32_t> bad;
    for (int step = 0; step < 2; ++step) {
        stepWide(one, p, s1, pool1, bad);
        stepWide(two, p, s2, pool2, bad);
    }
    EXPECT_EQ(countBitDifferences(one, two), 0);
}

TEST_P(IntegratorAgreement, RotationOffLeavesAngularStateAlone) {
    const IntegrationParams p = paramsFor(GetParam(), /*rotation=*/false);
    MovingBodies b = randomBodies(101, 5);
    const MovingBodies before = b;
    IntegrationScratch s;
    TaskPool pool(1);
    std::vector<std::uint32_t> bad;
    stepWide(b, p, s, pool, bad);
    EXPECT_EQ(b.wx, before.wx);
    EXPECT_EQ(b.wy, before.wy);
    EXPECT_EQ(b.wz, before.wz);
    EXPECT_EQ(b.qx, before.qx);
    EXPECT_EQ(b.qw, before.qw);
    EXPECT_NE(b.vy, before.vy);
    // The world inverse inertia is refreshed all the same.
    EXPECT_NE(b.iwXX, before.iwXX);
}

INSTANTIATE_TEST_SUITE_P(AllIntegrators, IntegratorAgreement, ::testing::ValuesIn(kIntegrators),
                         [](const auto& testParam) { return std::string(integratorName(testParam.param)); });

// ---------------------------------------------------------------------------------------------------------------

class IntegratorBehaviour : public ::testing::TestWithParam<Integrator> {};

TEST_P(IntegratorBehaviour, KinematicBodyMovesAtConstantVelocityIgnoringGravityAndForces) {
    MovingBodies b;
    const std::uint32_t i = addBody(b);
    b.flags[i] = kFlagKinematic;
    b.px[i] = 1, b.py[i] = 2, b.pz[i] = 3;
    b.vx[i] = 0.5f, b.vy[i] = -1, b.vz[i] = 2;
    b.wx[i] = 0, b.wy[i] = 1, b.wz[i] = 0;
    IntegrationScratch s;
    TaskPool pool(1);
    std::vector<std::uint32_t> bad;
    const IntegrationParams p = paramsFor(GetParam());
    for (int step = 0; step < 60; ++step) {
        b.fx[i] = 100, b.ty[i] = 100;  // ignored: invMass and invI are 0
        stepWide(b, p, s, pool, bad);
    }
    EXPECT_TRUE(bad.empty());
    EXPECT_EQ(b.vx[i], 0.5f);
    EXPECT_EQ(b.vy[i], -1.0f);
    EXPECT_EQ(b.vz[i], 2.0f);
    EXPECT_EQ(b.wy[i], 1.0f);
    // One second: 60 additions of v dt, each rounded.
    EXPECT_NEAR(b.px[i], 1.5f, 1e-5f);
    EXPECT_NEAR(b.py[i], 1.0f, 1e-5f);
    EXPECT_NEAR(b.pz[i], 5.0f, 1e-5f);
    // One radian about y.
    EXPECT_NEAR(b.qy[i], std::sin(0.5f), 1e-4f);
    EXPECT_NEAR(b.qw[i], std::cos(0.5f), 1e-4f);
}

TEST_P(IntegratorBehaviour, ForceForOneStepChangesVelocityByForceTimesDtOverMass) {
    MovingBodies b;
    const std::uint32_t i = addBody(b);
    setDynamic(b, i, 2.0f, {1, 1, 1});
    b.fx[i] = 10, b.fy[i] = -4, b.fz[i] = 6;
    b.tx[i] = 1, b.ty[i] = 2, b.tz[i] = 3;
    IntegrationParams p = paramsFor(GetParam());
    p.gravity = {};
    IntegrationScratch s;
    TaskPool pool(1);
    std::vector<std::uint32_t> bad;
    integrateVelocities(b, p, s, pool, bad);
    EXPECT_FLOAT_EQ(b.vx[i], 10 * kDt / 2);
    EXPECT_FLOAT_EQ(b.vy[i], -4 * kDt / 2);
    EXPECT_FLOAT_EQ(b.vz[i], 6 * kDt / 2);
    // Unit inertia sphere: w changes by t dt / I (gyroscopic term vanishes for equal moments, up to RK4's
    // second-order terms from the rotating frame which are zero for a sphere as well).
    EXPECT_NEAR(b.wx[i], 1 * kDt, 1e-6f);
    EXPECT_NEAR(b.wy[i], 2 * kDt, 1e-6f);
    EXPECT_NEAR(b.wz[i], 3 * kDt, 1e-6f);
    EXPECT_EQ(b.fx[i], 0.0f);
    EXPECT_EQ(b.fy[i], 0.0f);
    EXPECT_EQ(b.fz[i], 0.0f);
    EXPECT_EQ(b.tx[i], 0.0f);
    EXPECT_EQ(b.ty[i], 0.0f);
    EXPECT_EQ(b.tz[i], 0.0f);
    // The next step, without a force, leaves the velocity alone.
    const float vx = b.vx[i];
    integrateVelocities(b, p, s, pool, bad);
    EXPECT_EQ(b.vx[i], vx);
    EXPECT_TRUE(bad.empty());
}

TEST_P(IntegratorBehaviour, ScratchIsUsedOnlyByNonDefaultIntegrators) {
    MovingBodies b = randomBodies(20, 9);
    IntegrationScratch s;
    TaskPool pool(1);
    std::vector<std::uint32_t> bad;
    integrateVelocities(b, paramsFor(GetParam()), s, pool, bad);
    EXPECT_EQ(s.dx.size(), GetParam() == Integrator::SemiImplicitEuler ? 0u : 20u);
    EXPECT_EQ(s.ez.size(), GetParam() == Integrator::SemiImplicitEuler ? 0u : 20u);
}

// Non-finite results are not written: the body keeps its state (accumulators included) and is reported in
// ascending dense order, from wide batches, the scalar tail and several parallel chunks alike.
TEST_P(IntegratorBehaviour, NonFiniteVelocityLeavesStateUnchangedAndIsReported) {
    const IntegrationParams p = paramsFor(GetParam());
    for (const std::size_t count : {std::size_t{37}, std::size_t{10007}}) {
        for (const bool wide : {true, false}) {
            MovingBodies b = randomBodies(count, 11);
            const std::vector<std::uint32_t> broken = {3, 20, static_cast<std::uint32_t>(count - 2)};
            // A force that overflows to inf once divided by the mass, and a NaN torque.
            b.fx[3] = 1e38f, b.invMass[3] = 10.0f;
            b.ty[20] = std::numeric_limits<float>::quiet_NaN();
            b.invIx[20] = b.invIy[20] = b.invIz[20] = 1.0f;
            b.fz[count - 2] = -1e38f, b.invMass[count - 2] = 100.0f;
            const MovingBodies before = b;
            IntegrationScratch s;
            TaskPool pool(2);
            std::vector<std::uint32_t> bad;
            if (wide)
                integrateVelocities(b, p, s, pool, bad);
            else
                integrateVelocitiesScalar(b, p, s, bad);
            EXPECT_EQ(bad, broken) << count << (wide ? " wide" : " scalar");
            const auto sa = stateArrays(b), sb = stateArrays(before);
            for (const std::uint32_t i : broken)
                for (std::size_t f = 0; f < sa.size(); ++f)
                    EXPECT_TRUE(sameBits((*sa[f])[i], (*sb[f])[i])) << kStateNames[f] << "[" << i << "]";
            EXPECT_NE(b.vy[4], before.vy[4]);  // a neighbour in the same batch moved on
        }
    }
}

TEST_P(IntegratorBehaviour, NonFinitePositionLeavesPoseUnchangedAndIsReported) {
    IntegrationParams p = paramsFor(GetParam());
    p.dt = 1.0f;
    for (const bool wide : {true, false}) {
        MovingBodies b = randomBodies(41, 13);
        b.px[2] = 3e38f, b.vx[2] = 3e38f;  // x + v dt overflows
        b.wz[39] = std::numeric_limits<float>::infinity();
        IntegrationScratch s;
        if (GetParam() != Integrator::SemiImplicitEuler)
            for (auto* a : {&s.dx, &s.dy, &s.dz, &s.ex, &s.ey, &s.ez}) a->assign(b.size(), 0.0f);
        const MovingBodies before = b;
        TaskPool pool(1);
        std::vector<std::uint32_t> bad;
        if (wide)
            integratePositions(b, p, s, pool, bad);
        else
            integratePositionsScalar(b, p, s, bad);
        EXPECT_EQ(bad, (std::vector<std::uint32_t>{2, 39}));
        for (const std::uint32_t i : {2u, 39u}) {
            EXPECT_TRUE(sameBits(b.px[i], before.px[i]) && sameBits(b.py[i], before.py[i]));
            EXPECT_TRUE(sameBits(b.qx[i], before.qx[i]) && sameBits(b.qw[i], before.qw[i]));
        }
        EXPECT_NE(b.px[3], before.px[3]);
    }
}

INSTANTIATE_TEST_SUITE_P(AllIntegrators, IntegratorBehaviour, ::testing::ValuesIn(kIntegrators),
                         [](const auto& testParam) { return std::string(integratorName(testParam.param)); });

// ---------------------------------------------------------------------------------------------------------------

// Iw^-1 = R diag(invI) R^T with R the rotation of q * ir, computed in double precision with Eigen.
TEST(IntegrateVelocities, WorldInverseInertiaMatchesEigen) {
    MovingBodies b = randomBodies(53, 17);
    IntegrationScratch s;
    TaskPool pool(1);
    std::vector<std::uint32_t> bad;
    const MovingBodies before = b;
    integrateVelocities(b, paramsFor(Integrator::SemiImplicitEuler), s, pool, bad);
    for (std::uint32_t i = 0; i < b.size(); ++i) {
        const Eigen::Quaterniond q(before.qw[i], before.qx[i], before.qy[i], before.qz[i]);
        const Eigen::Quaterniond ir(before.irw[i], before.irx[i], before.iry[i], before.irz[i]);
        const Eigen::Matrix3d r = (q * ir).toRotationMatrix();
        const Eigen::Matrix3d iw =
            r * Eigen::Vector3d(before.invIx[i], before.invIy[i], before.invIz[i]).asDiagonal() * r.transpose();
        const double scale =
            1e-6 * std::max({1.0, static_cast<double>(before.invIx[i]), static_cast<double>(before.invIy[i]),
                             static_cast<double>(before.invIz[i])});
        EXPECT_NEAR(b.iwXX[i], iw(0, 0), scale) << i;
        EXPECT_NEAR(b.iwYY[i], iw(1, 1), scale) << i;
        EXPECT_NEAR(b.iwZZ[i], iw(2, 2), scale) << i;
        EXPECT_NEAR(b.iwXY[i], iw(0, 1), scale) << i;
        EXPECT_NEAR(b.iwXZ[i], iw(0, 2), scale) << i;
        EXPECT_NEAR(b.iwYZ[i], iw(1, 2), scale) << i;
    }
}

// Without a solver in between, RK4's positions reproduce its own pose update: constant acceleration is exact.
TEST(IntegrateVelocities, Rk4OffsetsReproduceConstantAccelerationExactly) {
    MovingBodies b;
    const std::uint32_t i = addBody(b);
    setDynamic(b, i, 1.0f, {1, 1, 1});
    b.vx[i] = 3;
    IntegrationScratch s;
    TaskPool pool(1);
    std::vector<std::uint32_t> bad;
    const IntegrationParams p = paramsFor(Integrator::RungeKutta4);
    stepWide(b, p, s, pool, bad);
    EXPECT_NEAR(b.py[i], -0.5f * 9.81f * kDt * kDt, 1e-7f);
    EXPECT_NEAR(b.px[i], 3 * kDt, 1e-7f);
}

}  // namespace
}  // namespace rubble::detail
