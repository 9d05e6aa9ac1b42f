// The joint solver and the joints' API: validation, handles, the store's bookkeeping, the coupling with the contact
// solver, and determinism across thread counts.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

#include "core/parallel.h"
#include "rubble/world.h"
#include "solver/joint_solver.h"
#include "storage/joint_storage.h"
#include "support/error_of.h"
#include "support/hanging_sheet.h"
#include "world/world_access.h"

namespace rubble {
namespace {

using test::errorOf;

constexpr float kDt = 1.0f / 60.0f;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

struct TwoBodies {
    World world{[] {
        WorldSettings s;
        s.threads = 1;
        return s;
    }()};
    BodyId ground, a, b;

    TwoBodies() {
        const ShapeId box = world.createShape(BoxDef{});
        BodyDef def;
        def.shape = box;
        def.type = BodyType::Static;
        ground = world.createBody(def);
        def.type = BodyType::Dynamic;
        def.position = {0, 3, 0};
        a = world.createBody(def);
        def.position = {2, 3, 0};
        b = world.createBody(def);
    }
};

TEST(JointApi, RefusesBadBodies) {
    TwoBodies t;
    BallJointDef def;
    def.bodyA = t.a;
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(def); }), "def.bodyB is null"));
    def.bodyB = t.a;
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(def); }), "same body"));
    def.bodyA = t.ground;
    def.bodyB = t.world.createBody([&] {
        BodyDef s;
        s.type = BodyType::Static;
        s.shape = t.world.bodyShape(t.ground);
        return s;
    }());
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(def); }), "both static"));
    def.bodyB = BodyId{999, 1};
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(def); }), "def.bodyB"));
    def.bodyB = t.b;
    def.localAnchorA = {kNaN, 0, 0};
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(def); }), "def.localAnchorA is not finite"));
    def.localAnchorA = {};
    def.breakForce = -1;
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(def); }), "def.breakForce"));
    def.breakForce = kInf;
    EXPECT_NO_THROW(t.world.createJoint(def));
}

TEST(JointApi, RefusesBadNumbers) {
    TwoBodies t;
    SpringJointDef spring;
    spring.bodyA = t.a;
    spring.bodyB = t.b;
    spring.stiffness = -5;
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(spring); }), "def.stiffness must be >= 0"));
    spring.stiffness = 10;
    spring.damping = kInf;
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(spring); }), "def.damping is not finite"));
    spring.damping = 0;
    spring.restLength = -1.0f;
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(spring); }), "def.restLength"));

    DistanceJointDef rod;
    rod.bodyA = t.a;
    rod.bodyB = t.b;
    rod.length = 0.0f;
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(rod); }), "def.length must be >= 0.001"));
    rod.length = {};
    rod.localAnchorB = {-2, 0, 0};  // both anchors at the same world point: no length to keep
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(rod); }), "ball joint"));

    HingeJointDef hinge;
    hinge.bodyA = t.a;
    hinge.bodyB = t.b;
    hinge.localAxisA = {0, 0, 0};
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(hinge); }), "def.localAxisA must not be zero"));
    hinge.localAxisA = {0, 1, 0};
    hinge.enableLimit = true;
    hinge.lowerAngle = 0.5f;
    hinge.upperAngle = -0.5f;
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(hinge); }), "def.lowerAngle (0.500000) is above"));
    hinge.lowerAngle = -4.0f;
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(hinge); }), "[-pi, pi]"));
    hinge.lowerAngle = -0.5f;
    hinge.maxMotorTorque = -1;
    EXPECT_TRUE(contains(errorOf([&] { t.world.createJoint(hinge); }), "def.maxMotorTorque"));
    hinge.maxMotorTorque = 0;
    const JointId ok = t.world.createJoint(hinge);
    EXPECT_TRUE(contains(errorOf([&] { t.world.setHingeMotor(ok, true, kNaN, 1); }), "speed is not finite"));
    EXPECT_EQ(t.world.jointCount(), 1u);  // nothing refused was half-created
}

TEST(JointApi, HandlesAndDestroyBody) {
    TwoBodies t;
    BallJointDef ball;
    ball.bodyA = t.a;
    ball.bodyB = t.b;
    const JointId ab = t.world.createJoint(ball);
    ball.bodyA = t.ground;
    const JointId gb = t.world.createJoint(ball);
    ball.bodyB = t.a;
    ball.localAnchorA = {0, 3, 0};  // at a's centre
    const JointId ga = t.world.createJoint(ball);
    EXPECT_EQ(t.world.jointCount(), 3u);
    EXPECT_EQ(t.world.jointType(ab), JointType::Ball);
    EXPECT_TRUE(contains(errorOf([&] { t.world.hingeAngle(ab); }), "not a hinge"));
    EXPECT_TRUE(contains(errorOf([&] { t.world.isJointBroken(JointId{}); }), "null"));

    // Destroying b destroys its two joints; the third stays and still works after b's swap-remove.
    t.world.destroyBody(t.b);
    EXPECT_FALSE(t.world.isValid(ab));
    EXPECT_FALSE(t.world.isValid(gb));
    EXPECT_TRUE(t.world.isValid(ga));
    EXPECT_EQ(t.world.jointCount(), 1u);
    EXPECT_TRUE(contains(errorOf([&] { t.world.jointReactionForce(ab); }), "stale"));
    EXPECT_EQ(t.world.jointBodies(ga).second, t.a);
    for (int i = 0; i < 10; ++i) t.world.step(kDt);
    EXPECT_NEAR(t.world.centerOfMass(t.a).y, 3.0f, 0.01f) << "a still hangs from the ground at its anchor";

    t.world.destroyJoint(ga);
    EXPECT_FALSE(t.world.isValid(ga));
    EXPECT_TRUE(contains(errorOf([&] { t.world.destroyJoint(ga); }), "stale"));
    // A new joint reuses the slot with a new generation: the old handle stays invalid.
    ball.bodyB = t.a;
    const JointId again = t.world.createJoint(ball);
    EXPECT_EQ(again.index, ga.index);
    EXPECT_NE(again, ga);
    EXPECT_FALSE(t.world.isValid(ga));
}

// A world without joints runs no joint code: the effect is off, no joint time is recorded.
TEST(JointSolver, WorldWithoutJointsRunsNoJointCode) {
    TwoBodies t;
    t.world.step(kDt);
    EXPECT_FALSE(t.world.activeEffects().has(Effect::Joints));
    EXPECT_EQ(t.world.lastProfile().jointMs, 0.0);
    EXPECT_EQ(t.world.lastProfile().joints, 0u);
    // With a joint, it runs and is timed; destroying it switches the effect off again.
    BallJointDef ball;
    ball.bodyA = t.a;
    ball.bodyB = t.b;
    const JointId j = t.world.createJoint(ball);
    t.world.step(kDt);
    EXPECT_TRUE(t.world.lastProfile().effects.has(Effect::Joints));
    EXPECT_GT(t.world.lastProfile().jointMs, 0.0);
    t.world.destroyJoint(j);
    t.world.step(kDt);
    EXPECT_FALSE(t.world.lastProfile().effects.has(Effect::Joints));
    EXPECT_EQ(t.world.lastProfile().jointMs, 0.0);
}

// Two overlapping boxes ball-jointed at a shared point: with collideConnected false their contact is not solved, so
// nothing pushes them apart (they fall together, still overlapping); with it true the contact separates them.
TEST(JointSolver, JointedBodiesDoNotCollideUnlessAsked) {
    for (bool collide : {false, true}) {
        WorldSettings s;
        s.threads = 1;
        s.gravity = {0, 0, 0};
        World world(s);
        BodyDef def;
        def.shape = world.createShape(BoxDef{});
        def.position = {0, 0, 0};
        const BodyId a = world.createBody(def);
        def.position = {0.5f, 0, 0};  // 0.5 m of overlap
        const BodyId b = world.createBody(def);
        BallJointDef ball;
        ball.bodyA = a;
        ball.bodyB = b;
        ball.localAnchorA = {0.25f, 0, 0};
        ball.localAnchorB = {-0.25f, 0, 0};
        ball.collideConnected = collide;
        world.createJoint(ball);
        for (int i = 0; i < 30; ++i) world.step(kDt);
        const float gap = world.centerOfMass(b).x - world.centerOfMass(a).x;
        if (!collide) {
            EXPECT_NEAR(gap, 0.5f, 1e-4f);
        } else {
            EXPECT_GT(std::fabs(gap - 0.5f) + std::fabs(world.centerOfMass(a).y - world.centerOfMass(b).y) +
                          length(world.angularVelocity(a)),
                      1e-3f)
                << "the contact fought the joint";
        }
    }
}

// The island builder's edges (JointSolver::couple): moving pairs of unbroken joints, by current dense index.
TEST(JointStore, EdgesFollowDenseIndicesAndSkipStaticAndBroken) {
    detail::BodyStorage bodies;
    std::uint32_t dense;
    const BodyId s = bodies.allocate(detail::BodySet::Static, dense);
    std::vector<BodyId> m;
    for (int i = 0; i < 4; ++i) m.push_back(bodies.allocate(detail::BodySet::Moving, dense));
    detail::JointStore store;
    const auto join = [&](BodyId a, BodyId b) {
        detail::Joint j;
        j.bodyA = a, j.bodyB = b;
        return store.add(j);
    };
    join(m[0], m[1]);
    join(s, m[2]);
    const JointId broken = join(m[2], m[3]);
    join(m[3], m[1]);
    store.markBroken(1 + 1);
    detail::JointSolver solver;
    detail::JointCoupling coupling;
    detail::TaskPool pool(1);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
    const auto listEdges = [&] {
        edges.clear();
        solver.couple(store, bodies, coupling, pool);
        coupling.appendEdges(edges);
    };
    listEdges();
    ASSERT_EQ(edges.size(), 2u);
    EXPECT_EQ(edges[0], (std::pair<std::uint32_t, std::uint32_t>{0, 1}));
    EXPECT_EQ(edges[1], (std::pair<std::uint32_t, std::uint32_t>{3, 1}));
    EXPECT_EQ(store.brokenReports().size(), 1u);
    EXPECT_EQ(store.brokenReports()[0], broken);
    EXPECT_EQ(store.activeCount(), 3u);
    // Removing body 0 and its joint: body 3 is swapped into dense index 0, and the edges follow it.
    EXPECT_EQ(store.removeAttachedTo(m[0]), 1u);
    bodies.release(m[0]);
    listEdges();
    ASSERT_EQ(edges.size(), 1u);
    EXPECT_EQ(edges[0], (std::pair<std::uint32_t, std::uint32_t>{0, 1}));
    EXPECT_EQ(store.size(), 3u);
    EXPECT_EQ(store.activeCount(), 2u);
    EXPECT_EQ(store.removeAttachedTo(m[1]), 1u);
    EXPECT_EQ(store.size(), 2u);
}

/// A scene with joints and contacts: a rope bridge of boxes on ball joints between two posts, springs holding
/// weights, a hinged flap, and a shower of boxes landing on all of it and on the ground.
std::uint64_t jointSceneHash(int threads) {
    WorldSettings s;
    s.threads = threads;
    World world(s);
    BodyDef def;
    def.type = BodyType::Static;
    def.shape = world.createShape(BoxDef{{30, 0.5f, 30}});
    def.position = {0, -0.5f, 0};
    const BodyId ground = world.createBody(def);
    def.shape = world.createShape(BoxDef{{0.2f, 2, 0.2f}});
    def.position = {-6, 2, 0};
    const BodyId left = world.createBody(def);
    def.position = {6, 2, 0};
    const BodyId right = world.createBody(def);
    def.type = BodyType::Dynamic;
    const ShapeId plank = world.createShape(BoxDef{{0.25f, 0.05f, 0.6f}});
    BodyId previous = left;
    Vec3 previousAnchor{0.2f, 2, 0};
    for (int i = 0; i < 22; ++i) {
        def.shape = plank;
        def.position = {-5.5f + 0.5f * float(i), 4, 0};
        const BodyId p = world.createBody(def);
        for (float z : {-0.5f, 0.5f}) {
            BallJointDef ball;
            ball.bodyA = previous;
            ball.bodyB = p;
            ball.localAnchorA = previousAnchor + Vec3{0, 0, z};
            ball.localAnchorB = {-0.25f, 0, z};
            world.createJoint(ball);
        }
        previous = p;
        previousAnchor = {0.25f, 0, 0};
    }
    BallJointDef last;
    last.bodyA = previous;
    last.bodyB = right;
    last.localAnchorA = {0.25f, 0, 0};
    last.localAnchorB = {-0.2f, 2, 0};
    world.createJoint(last);
    def.shape = world.createShape(SphereDef{0.3f});
    for (int i = 0; i < 5; ++i) {
        def.position = {-8.0f + 4.0f * float(i), 1.5f, 4};
        const BodyId weight = world.createBody(def);
        SpringJointDef spring;
        spring.bodyA = ground;
        spring.bodyB = weight;
        spring.localAnchorA = {-8.0f + 4.0f * float(i), 4.5f, 4};
        spring.stiffness = 200;
        spring.damping = 2;
        spring.restLength = 2;
        world.createJoint(spring);
    }
    def.shape = world.createShape(BoxDef{{0.5f, 0.05f, 0.5f}});
    def.position = {0, 1, -4};
    const BodyId flap = world.createBody(def);
    HingeJointDef hinge;
    hinge.bodyA = ground;
    hinge.bodyB = flap;
    hinge.localAnchorA = {-0.5f, 1.5f, -4};
    hinge.localAnchorB = {-0.5f, 0, 0};
    hinge.localAxisA = hinge.localAxisB = {0, 0, 1};
    hinge.enableLimit = true;
    hinge.lowerAngle = -0.6f;
    hinge.upperAngle = 0.3f;
    world.createJoint(hinge);
    def.shape = world.createShape(BoxDef{{0.15f, 0.15f, 0.15f}});
    for (int i = 0; i < 400; ++i) {
        def.position = {-7.0f + 0.7f * float(i % 20), 6.0f + 0.5f * float(i / 80),
                        -4.0f + 0.5f * float(i / 20 % 4) * 2.5f};
        world.createBody(def);
    }
    for (int i = 0; i < 150; ++i) world.step(kDt);
    EXPECT_GT(world.lastProfile().constraints, 100u);
    EXPECT_EQ(world.lastProfile().joints, 22u * 2 + 1 + 5 + 1);
    return world.stateHash();
}

TEST(JointSolver, StateIsIdenticalForOneAndTwoThreads) { EXPECT_EQ(jointSceneHash(1), jointSceneHash(2)); }

// The large islands' joints split into two slabs when few of them cross the middle, whatever order they were built
// in, and stay one colouring when many do (the braces cross the cut: 435 of 2,146 joints). Each way, every ball
// joint runs in SIMD lanes. (Their results: tests/physics/joint_physics_test.cpp, HangingSheet*.)
TEST(JointSolver, LargeJointIslandsSplitInTwoWhenFewJointsCrossTheMiddle) {
    for (const auto& [scattered, braced, slabs] :
         {std::tuple{false, false, true}, std::tuple{true, false, true}, std::tuple{false, true, false}}) {
        test::Sheet sheet(2, scattered, braced);
        for (int i = 0; i < 3; ++i) sheet.world.step(kDt);
        const detail::JointSolver& solver = detail::WorldAccess::of(sheet.world).jointSolver;
        EXPECT_EQ(solver.slabs(), slabs) << "scattered " << scattered << " braced " << braced;
        EXPECT_EQ(solver.batchedJoints(), sheet.down.size() + sheet.across.size() + sheet.braces.size());
    }
}

// A joint joins its bodies' islands even when they do not touch: they count as one island, fall asleep together and
// wake together (the joint's edge reaches the island builder).
TEST(JointSolver, JointedBodiesShareAnIslandAndSleepTogether) {
    World world;
    BodyDef ground;
    ground.type = BodyType::Static;
    ground.shape = world.createShape(BoxDef{{20, 0.5f, 20}});
    ground.position = {0, -0.5f, 0};
    world.createBody(ground);
    BodyDef ball;
    ball.shape = world.createShape(SphereDef{0.5f});
    ball.position = {-1.5f, 0.5f, 0};
    const BodyId left = world.createBody(ball);
    ball.position = {1.5f, 0.5f, 0};
    const BodyId right = world.createBody(ball);
    ball.position = {6, 0.5f, 0};
    world.createBody(ball);
    DistanceJointDef rod;
    rod.bodyA = left;
    rod.bodyB = right;
    world.createJoint(rod);
    world.step(1.0f / 60);
    EXPECT_EQ(world.lastProfile().islands, 2u);
    EXPECT_EQ(world.lastProfile().largestIsland, 2u);
    for (int i = 0; i < 120; ++i) world.step(1.0f / 60);
    ASSERT_FALSE(world.isAwake(left));
    ASSERT_FALSE(world.isAwake(right));
    world.wakeUp(right);
    world.step(1.0f / 60);
    EXPECT_TRUE(world.isAwake(left));
}

}  // namespace
}  // namespace rubble
