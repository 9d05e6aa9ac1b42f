// Free fall and damping against their closed forms, for every integrator, through the World API.
//
// The world integrates once per substep, h = dt / substeps (the default's four substeps: h = 1/240 s).
// Free fall x(t) = x0 + v0 t + g t^2 / 2. After n substeps of h (t = n h):
//  - semi-implicit Euler moves with the end-of-substep velocity v_k = v0 + g k h, so x_n = x0 + v0 t + g h^2 n(n+1)/2:
//    the error is exactly +g t h / 2 (with g = -9.81 m/s^2, t = 2 s, h = 1/240 s: 0.0409 m too low);
//  - explicit Euler moves with the start-of-substep velocity, x_n = x0 + v0 t + g h^2 n(n-1)/2: error -g t h / 2;
//  - Verlet (trapezoidal positions) and RK4 are exact for constant acceleration.
// What remains is float rounding: 480 additions to a position of ~10-20 m, each rounded to half an ulp (~1e-6 m),
// plus the rounding of v; measured below 3e-5 m, so the bound is 1e-4 m.
//
// Damping: the Euler family and Verlet apply v *= 1 / (1 + c h) per substep, so v_n = v0 / (1 + c h)^n exactly up to
// rounding; RK4 integrates v' = -c v and matches v0 e^{-c t} up to its truncation error n (c h)^5 / 120 (~1e-14,
// far below float rounding, so the bound is float rounding, 1.2e-7 relative per substep: 6e-5 over 480).
#include <gtest/gtest.h>

#include "support/print.h"

#include <cmath>
#include <cstdio>

#include "rubble/world.h"

namespace rubble {
namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr int kSteps = 120;  // 2 s
const int kSubsteps = WorldSettings{}.substeps;
const double kH = static_cast<double>(kDt) / kSubsteps;  // the integration step
constexpr float kG = -9.81f;
constexpr float kRoundingBound = 1e-4f;  // m, see above

struct Fall {
    Vec3 start, velocity;
};

/// Final centre of mass after kSteps of free fall.
Vec3 simulateFall(Integrator integrator, const Fall& fall) {
    WorldSettings settings;
    settings.integrator = integrator;
    settings.threads = 1;
    World world(settings);
    const ShapeId sphere = world.createShape(SphereDef{0.25f});
    BodyDef def;
    def.shape = sphere;
    def.position = fall.start;
    def.linearVelocity = fall.velocity;
    const BodyId body = world.createBody(def);
    for (int n = 0; n < kSteps; ++n) world.step(kDt);
    EXPECT_FALSE(world.isFrozen(body));
    return world.centerOfMass(body);
}

/// Closed form plus the integrator's known first-order error (in y only: gravity is along y).
Vec3 predicted(const Fall& fall, double systematicError) {
    const double t = kSteps * static_cast<double>(kDt);
    return {static_cast<float>(fall.start.x + fall.velocity.x * t),
            static_cast<float>(fall.start.y + fall.velocity.y * t + 0.5 * kG * t * t + systematicError),
            static_cast<float>(fall.start.z + fall.velocity.z * t)};
}

double systematicError(Integrator integrator) {
    const double t = kSteps * static_cast<double>(kDt);
    switch (integrator) {
        case Integrator::SemiImplicitEuler:
            return 0.5 * kG * t * kH;  // -0.0409 m
        case Integrator::ExplicitEuler:
            return -0.5 * kG * t * kH;  // +0.0409 m
        case Integrator::Verlet:
        case Integrator::RungeKutta4:
            return 0.0;
    }
    return 0.0;
}

class FreeFall : public ::testing::TestWithParam<Integrator> {};

TEST_P(FreeFall, FromRestMatchesClosedFormPlusKnownError) {
    const Fall fall{{1.0f, 20.0f, -2.0f}, {}};
    const Vec3 x = simulateFall(GetParam(), fall);
    const Vec3 expected = predicted(fall, systematicError(GetParam()));
    EXPECT_NEAR(x.x, expected.x, kRoundingBound);
    EXPECT_NEAR(x.y, expected.y, kRoundingBound);
    EXPECT_NEAR(x.z, expected.z, kRoundingBound);
    std::printf("%s from rest: y %.6f, closed form %.6f, known error %.6f, residual %.2e m\n",
                std::string(integratorName(GetParam())).c_str(), x.y, predicted(fall, 0).y, systematicError(GetParam()),
                x.y - expected.y);
}

TEST_P(FreeFall, WithInitialVelocityMatchesClosedFormPlusKnownError) {
    const Fall fall{{0.0f, 5.0f, 0.0f}, {3.0f, 8.0f, -1.5f}};
    const Vec3 x = simulateFall(GetParam(), fall);
    const Vec3 expected = predicted(fall, systematicError(GetParam()));
    EXPECT_NEAR(x.x, expected.x, kRoundingBound);
    EXPECT_NEAR(x.y, expected.y, kRoundingBound);
    EXPECT_NEAR(x.z, expected.z, kRoundingBound);
}

TEST_P(FreeFall, LinearDampingMatchesItsClosedForm) {
    WorldSettings settings;
    settings.integrator = GetParam();
    settings.gravity = {};
    settings.threads = 1;
    World world(settings);
    const ShapeId sphere = world.createShape(SphereDef{0.25f});
    BodyDef def;
    def.shape = sphere;
    def.linearVelocity = {10.0f, 0.0f, 0.0f};
    def.linearDamping = 0.5f;
    const BodyId body = world.createBody(def);
    for (int n = 0; n < kSteps; ++n) world.step(kDt);
    const double c = 0.5, t = kSteps * static_cast<double>(kDt);
    const double expected = GetParam() == Integrator::RungeKutta4 ? 10.0 * std::exp(-c * t)
                                                                  : 10.0 / std::pow(1.0 + c * kH, kSteps * kSubsteps);
    const float v = world.linearVelocity(body).x;
    // Float rounding: the factor 1 / (1 + c h) is rounded once, the same way every substep, so its error adds up over
    // the substeps (2 roundings of 6e-8 each), plus the last product's.
    EXPECT_NEAR(v, expected, (kSteps * kSubsteps * 1.2e-7 + 2e-6) * 10.0);
    // The Euler family is not e^{-ct}: the difference is first order in h (~0.1% here), and it is visible.
    if (GetParam() != Integrator::RungeKutta4) {
        EXPECT_GT(std::fabs(v - 10.0 * std::exp(-c * t)), 1e-3);
    }
}

INSTANTIATE_TEST_SUITE_P(AllIntegrators, FreeFall,
                         ::testing::Values(Integrator::SemiImplicitEuler, Integrator::ExplicitEuler, Integrator::Verlet,
                                           Integrator::RungeKutta4),
                         [](const auto& testParam) { return std::string(integratorName(testParam.param)); });

}  // namespace
}  // namespace rubble
