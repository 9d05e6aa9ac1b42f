// The resting-load guess for new contacts against statics worked by hand: weights, the lever rule, loads passed down a
// stack, impulses carried from last step passed on unchanged, and never a pulling contact. Tolerances are float
// rounding of sums of a few terms (1e-5 relative).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "contacts/resting_loads.h"
#include "core/parallel.h"

using namespace rubble;
using namespace rubble::detail;

namespace {

constexpr float kG = 9.81f;
constexpr float kH = 1.0f / 60.0f;
constexpr std::uint32_t kGround = 0;  ///< index of the one static body

struct Pile {
    MovingBodies bodies;
    Contacts contacts;
    std::vector<std::uint8_t> carried;
    std::vector<PointImpulse> impulses;
    Vec3 gravity{0, -kG, 0};

    std::uint32_t body(Vec3 centre, float mass) {
        bodies.px.push_back(centre.x), bodies.py.push_back(centre.y), bodies.pz.push_back(centre.z);
        for (AlignedVector<float>* v : {&bodies.vx, &bodies.vy, &bodies.vz, &bodies.wx, &bodies.wy, &bodies.wz})
            v->push_back(0.0f);
        bodies.invMass.push_back(1.0f / mass);
        bodies.gravityScale.push_back(1.0f);
        return static_cast<std::uint32_t>(bodies.px.size() - 1);
    }
    /// A manifold from `lower` (A) up to `upper` (B), its normal `normal`, its points at `points` (depth 0).
    std::size_t touch(std::uint32_t lower, bool lowerStatic, std::uint32_t upper, const std::vector<Vec3>& points,
                      Vec3 normal = {0, 1, 0}) {
        ContactPair pair;
        pair.a = lower, pair.aStatic = lowerStatic, pair.b = upper;
        Manifold m;
        m.normal = normal;
        for (const Vec3& p : points) m.points[m.pointCount++] = {p, 0.0f, static_cast<std::uint32_t>(m.pointCount)};
        contacts.pairs.push_back(pair);
        contacts.manifolds.push_back(m);
        carried.push_back(0);
        impulses.resize(contacts.manifolds.size() * kMaxManifoldPoints);
        return contacts.manifolds.size() - 1;
    }
    /// The velocity a body has after gravity's substep: at rest, it moves down by g h.
    void setVelocity(std::uint32_t body, Vec3 v) {
        bodies.vx[body] = v.x, bodies.vy[body] = v.y, bodies.vz[body] = v.z;
    }
    std::uint32_t seed(int threads = 1) {
        RestingLoads loads;
        TaskPool pool(threads);
        return loads.seed(contacts, carried, bodies, {gravity, kH, 0.005f}, pool, impulses);
    }
    float normal(std::size_t manifold, int point) const {
        return impulses[manifold * kMaxManifoldPoints + static_cast<std::size_t>(point)].normal;
    }
    float total(std::size_t manifold) const {
        float sum = 0;
        for (int i = 0; i < contacts.manifolds[manifold].pointCount; ++i) sum += normal(manifold, i);
        return sum;
    }
};

void expectNear(float actual, float expected) { EXPECT_NEAR(actual, expected, 1e-5f * std::fabs(expected) + 1e-9f); }

}  // namespace

TEST(RestingLoads, ABoxOnTheGroundGetsItsWeightSpreadEvenly) {
    Pile s;
    const std::uint32_t box = s.body({0, 0.5f, 0}, 10);
    const std::size_t m =
        s.touch(kGround, true, box, {{-0.5f, 0, -0.5f}, {0.5f, 0, -0.5f}, {0.5f, 0, 0.5f}, {-0.5f, 0, 0.5f}});
    EXPECT_EQ(s.seed(), 1u);
    for (int i = 0; i < 4; ++i) {
        expectNear(s.normal(m, i), 10 * kG * kH / 4);
        EXPECT_EQ(s.impulses[m * kMaxManifoldPoints + i].tangent1, 0.0f);
    }
}

// A plank of weight W with its centre 1 m from one support and 3 m from the other: the lever rule gives 3/4 W and
// 1/4 W, split evenly between each support's two points (they sit symmetrically about the plank's axis).
TEST(RestingLoads, APlankOnTwoSupportsSplitsByTheLeverRule) {
    Pile s;
    const std::uint32_t plank = s.body({0, 1, 0}, 20);
    const std::size_t near = s.touch(kGround, true, plank, {{-1, 0.5f, -0.5f}, {-1, 0.5f, 0.5f}});
    const std::size_t far = s.touch(kGround, true, plank, {{3, 0.5f, -0.5f}, {3, 0.5f, 0.5f}});
    EXPECT_EQ(s.seed(), 2u);
    const float weight = 20 * kG * kH;
    expectNear(s.normal(near, 0), 0.75f * weight / 2);
    expectNear(s.normal(near, 1), 0.75f * weight / 2);
    expectNear(s.normal(far, 0), 0.25f * weight / 2);
    expectNear(s.normal(far, 1), 0.25f * weight / 2);
}

// Three boxes of 4, 2 and 1 kg from the bottom: each contact carries everything above it. The top contact's impulses
// are written before the middle body is balanced, or the loads would not add up.
TEST(RestingLoads, LoadsPassDownAStackTopFirst) {
    Pile s;
    const std::uint32_t top = s.body({0, 2.5f, 0}, 1), bottom = s.body({0, 0.5f, 0}, 4),
                        middle = s.body({0, 1.5f, 0}, 2);
    const auto face = [](float y) {
        return std::vector<Vec3>{{-0.5f, y, -0.5f}, {0.5f, y, -0.5f}, {0.5f, y, 0.5f}, {-0.5f, y, 0.5f}};
    };
    // In an order unlike the stack's, as the narrow phase would list them.
    const std::size_t middleTop = s.touch(middle, false, top, face(2));
    const std::size_t groundBottom = s.touch(kGround, true, bottom, face(0));
    const std::size_t bottomMiddle = s.touch(bottom, false, middle, face(1));
    EXPECT_EQ(s.seed(), 3u);
    expectNear(s.total(middleTop), 1 * kG * kH);
    expectNear(s.total(bottomMiddle), 3 * kG * kH);
    expectNear(s.total(groundBottom), 7 * kG * kH);
}

// Last step's impulses stay as they were, and what they carry reaches the contacts below: a 2 kg box on the ground
// under a contact that carried 1.2 N s from last step gets 1.2 N s plus its own weight.
TEST(RestingLoads, CarriedContactsKeepTheirImpulsesAndPassThemDown) {
    Pile s;
    const std::uint32_t lower = s.body({0, 0.5f, 0}, 2), upper = s.body({0, 1.5f, 0}, 5);
    const std::size_t above = s.touch(lower, false, upper, {{-0.5f, 1, 0}, {0.5f, 1, 0}});
    s.carried[above] = 1;
    s.impulses[above * kMaxManifoldPoints + 0].normal = 0.5f;
    s.impulses[above * kMaxManifoldPoints + 1].normal = 0.7f;
    const std::size_t ground = s.touch(kGround, true, lower, {{-0.5f, 0, -0.5f}, {0.5f, 0, 0.5f}});
    EXPECT_EQ(s.seed(), 1u);
    EXPECT_EQ(s.normal(above, 0), 0.5f);
    EXPECT_EQ(s.normal(above, 1), 0.7f);
    expectNear(s.total(ground), 1.2f + 2 * kG * kH);
    // The load from above sits off the centre (0.7 on the right, 0.5 on the left), and the ground takes the torque.
    EXPECT_GT(s.normal(ground, 1), s.normal(ground, 0));
}

// Both supports to one side of the centre: balance would need the farther one to pull. It is dropped, and the nearer
// one takes the load alone (the iterations then let the plank tip, as it should).
TEST(RestingLoads, ContactsOnlyPush) {
    Pile s;
    const std::uint32_t plank = s.body({0, 1, 0}, 10);
    const std::size_t nearer = s.touch(kGround, true, plank, {{1, 0.5f, 0}});
    const std::size_t farther = s.touch(kGround, true, plank, {{2, 0.5f, 0}});
    s.seed();
    EXPECT_EQ(s.normal(farther, 0), 0.0f);
    EXPECT_GT(s.normal(nearer, 0), 0.0f);
    EXPECT_TRUE(std::isfinite(s.normal(nearer, 0)));
}

TEST(RestingLoads, SideContactsFarPointsAndWeightlessWorldsGetNothing) {
    Pile s;
    const std::uint32_t left = s.body({0, 0.5f, 0}, 1), right = s.body({1, 0.5f, 0}, 1);
    const std::size_t side = s.touch(left, false, right, {{0.5f, 0.2f, 0}, {0.5f, 0.8f, 0}}, {1, 0, 0});
    const std::size_t ground = s.touch(kGround, true, left, {{0, 0, -0.5f}, {0, 0, 0.5f}, {0.4f, 0, 0}});
    s.contacts.manifolds[ground].points[2].depth = -0.1f;  // speculative, 10 cm away
    EXPECT_EQ(s.seed(), 1u);
    EXPECT_EQ(s.total(side), 0.0f);
    expectNear(s.normal(ground, 0), kG * kH / 2);
    expectNear(s.normal(ground, 1), kG * kH / 2);
    EXPECT_EQ(s.normal(ground, 2), 0.0f);

    Pile weightless;
    weightless.gravity = {0, 0, 0};
    const std::size_t m = weightless.touch(kGround, true, weightless.body({0, 0.5f, 0}, 1), {{0, 0, 0}});
    EXPECT_EQ(weightless.seed(), 0u);
    EXPECT_EQ(weightless.normal(m, 0), 0.0f);
}

// A manifold point that is not finite spoils its body's balance; that body's points start from zero, and the other
// bodies' guesses stand.
TEST(RestingLoads, ANonFinitePointLeavesItsBodyWithoutAGuess) {
    Pile s;
    const std::uint32_t bad = s.body({0, 0.5f, 0}, 1), good = s.body({5, 0.5f, 0}, 1);
    const std::size_t spoilt = s.touch(kGround, true, bad, {{0, 0, -0.5f}, {NAN, 0, 0.5f}});
    const std::size_t fine = s.touch(kGround, true, good, {{5, 0, -0.5f}, {5, 0, 0.5f}});
    s.seed();
    EXPECT_EQ(s.normal(spoilt, 0), 0.0f);
    EXPECT_EQ(s.normal(spoilt, 1), 0.0f);
    expectNear(s.total(fine), kG * kH);
}

// Columns of three boxes (4, 2 and 1 kg from the bottom) on a 40 x 40 grid: 4,800 new manifolds, listed by layer as a
// narrow phase would, so the scan for supports runs in several parallel chunks. Each contact carries what is above
// it, and two threads write the same impulses as one.
TEST(RestingLoads, APileOfColumnsSeedsTheSameOnAnyThreadCount) {
    Pile s;
    constexpr int kSide = 40;
    const auto face = [](float x, float y, float z) {
        return std::vector<Vec3>{
            {x - 0.5f, y, z - 0.5f}, {x + 0.5f, y, z - 0.5f}, {x + 0.5f, y, z + 0.5f}, {x - 0.5f, y, z + 0.5f}};
    };
    std::vector<std::uint32_t> layers[3];
    const float masses[3] = {4, 2, 1};
    for (int layer = 0; layer < 3; ++layer)
        for (int i = 0; i < kSide * kSide; ++i)
            layers[layer].push_back(s.body(
                {static_cast<float>(i % kSide) * 2, layer + 0.5f, static_cast<float>(i / kSide) * 2}, masses[layer]));
    std::vector<std::size_t> contactsOf[3];
    for (int layer = 0; layer < 3; ++layer)
        for (int i = 0; i < kSide * kSide; ++i) {
            const float x = static_cast<float>(i % kSide) * 2, z = static_cast<float>(i / kSide) * 2;
            contactsOf[layer].push_back(layer == 0 ? s.touch(kGround, true, layers[0][i], face(x, 0, z))
                                                   : s.touch(layers[layer - 1][i], false, layers[layer][i],
                                                             face(x, static_cast<float>(layer), z)));
        }
    Pile twoThreads = s;
    EXPECT_EQ(s.seed(1), 3u * kSide * kSide);
    EXPECT_EQ(twoThreads.seed(2), 3u * kSide * kSide);
    for (std::size_t k = 0; k < s.impulses.size(); ++k) ASSERT_EQ(s.impulses[k].normal, twoThreads.impulses[k].normal);
    const float carried[3] = {7, 3, 1};  // kg above each layer's contact, its own body included
    for (int layer = 0; layer < 3; ++layer)
        for (const std::size_t m : contactsOf[layer]) expectNear(s.total(m), carried[layer] * kG * kH);
}

// A body at rest has gained g h toward its support before the solve; one landing approaches faster. The landing one
// gets no guess (the iterations stop it), the resting one its weight.
TEST(RestingLoads, ALandingBodyGetsNoGuess) {
    Pile s;
    const std::uint32_t resting = s.body({0, 0.5f, 0}, 1), landing = s.body({5, 0.5f, 0}, 1);
    s.setVelocity(resting, {0, -kG * kH, 0});
    s.setVelocity(landing, {0, -0.5f, 0});  // dropped from 1.3 cm
    const std::size_t rests = s.touch(kGround, true, resting, {{0, 0, -0.5f}, {0, 0, 0.5f}});
    const std::size_t lands = s.touch(kGround, true, landing, {{5, 0, -0.5f}, {5, 0, 0.5f}});
    EXPECT_EQ(s.seed(), 1u);
    expectNear(s.total(rests), kG * kH);
    EXPECT_EQ(s.total(lands), 0.0f);
}

// The impulse that stopped a body landing on a resting one last step is an impact, not a load: the resting body's new
// support below gets its own weight, not the 50 N s of the impact.
TEST(RestingLoads, AnImpactAboveIsNoLoad) {
    Pile s;
    const std::uint32_t lower = s.body({0, 0.5f, 0}, 2), upper = s.body({0, 1.5f, 0}, 1);
    s.setVelocity(upper, {0, -3, 0});  // still pressing in at 3 m/s
    const std::size_t above = s.touch(lower, false, upper, {{-0.5f, 1, 0}, {0.5f, 1, 0}});
    s.carried[above] = 1;
    s.impulses[above * kMaxManifoldPoints + 0].normal = 25;
    s.impulses[above * kMaxManifoldPoints + 1].normal = 25;
    const std::size_t ground = s.touch(kGround, true, lower, {{-0.5f, 0, 0}, {0.5f, 0, 0}});
    EXPECT_EQ(s.seed(), 1u);
    expectNear(s.total(ground), 2 * kG * kH);
    EXPECT_EQ(s.normal(above, 0), 25.0f);
}

// A support kept from last step already holds what it carried: a new one beside it takes only the rest. Here the kept
// support carried the whole weight, and the new one gets nothing (a body with a support too many would be lifted).
TEST(RestingLoads, KeptSupportsCountAsTheyAre) {
    Pile s;
    const std::uint32_t box = s.body({0, 0.5f, 0}, 4);
    const std::size_t kept = s.touch(kGround, true, box, {{-0.5f, 0, -0.5f}, {-0.5f, 0, 0.5f}});
    s.carried[kept] = 1;
    for (int i = 0; i < 2; ++i) s.impulses[kept * kMaxManifoldPoints + i].normal = 2 * kG * kH;
    const std::size_t added = s.touch(kGround, true, box, {{0.5f, 0, -0.5f}, {0.5f, 0, 0.5f}});
    s.seed();
    EXPECT_NEAR(s.total(added), 0.0f, 1e-5f * kG * kH);
    EXPECT_EQ(s.total(kept), 4 * kG * kH);
}

// Regression (the dropped pyramid thrown a kilometre): two supports whose normals differ by a hair cannot take a
// sideways load but by pushing against each other with huge forces, which the least-squares answer used to do (30 x
// the load in the pyramid). The guess now leaves what the supports cannot balance to the iterations and lifts the body
// by no more than 1.5 x its weight.
TEST(RestingLoads, NearlyParallelSupportsGetNoHugeForces) {
    Pile s;
    const std::uint32_t box = s.body({0, 0.5f, 0}, 10);
    const float tilt = 1e-3f;
    const Vec3 left = Vec3{tilt, 1, 0} * (1.0f / length(Vec3{tilt, 1, 0}));
    const Vec3 right = Vec3{-tilt, 1, 0} * (1.0f / length(Vec3{-tilt, 1, 0}));
    const std::size_t a =
        s.touch(kGround, true, box, {{-0.5f, 0, -0.5f}, {0.5f, 0, -0.5f}, {0.5f, 0, 0.5f}, {-0.5f, 0, 0.5f}}, left);
    const std::size_t b =
        s.touch(kGround, true, box, {{-0.5f, 0, -0.5f}, {0.5f, 0, -0.5f}, {0.5f, 0, 0.5f}, {-0.5f, 0, 0.5f}}, right);
    s.gravity = {2, -kG, 0};  // a sideways pull that only friction could hold
    s.seed();
    const float weight = 10 * kG * kH;
    EXPECT_LE(s.total(a) + s.total(b), 1.5f * weight * 1.0001f);
    EXPECT_GE(s.total(a) + s.total(b), 0.9f * weight);
}
