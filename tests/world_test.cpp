// World API: handles across add/remove churn (against a brute-force model), validation of bad input, the state
// hash, and the frame of the step.
#include <gtest/gtest.h>

#include <bit>

#include <Eigen/Dense>

#include <cmath>
#include <limits>
#include <map>
#include <random>

#include "rubble/error.h"
#include "rubble/limits.h"
#include "rubble/world.h"
#include "storage/body_storage.h"
#include "support/error_of.h"

using namespace rubble;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

using rubble::test::errorOf;

BodyDef dynamicBox(ShapeId shape, Vec3 position) {
    BodyDef def;
    def.shape = shape;
    def.position = position;
    return def;
}

}  // namespace

TEST(WorldHandles, SurviveChurnAgainstAModel) {
    World world;
    const ShapeId box = world.createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    std::mt19937 rng(7);
    std::map<std::uint64_t, std::pair<BodyId, std::uint64_t>> model;  // user data -> (handle, user data)
    std::vector<BodyId> dead;
    std::uint64_t next = 1;
    for (int round = 0; round < 20000; ++round) {
        const bool add = model.empty() || rng() % 100 < 55;
        if (add) {
            BodyDef def = dynamicBox(box, {float(next % 100), float(next / 100 % 100), 0});
            def.userData = next;
            def.type = next % 3 == 0 ? BodyType::Static : (next % 3 == 1 ? BodyType::Dynamic : BodyType::Kinematic);
            model[next] = {world.createBody(def), next};
            ++next;
        } else {
            auto it = model.begin();
            std::advance(it, rng() % model.size());
            world.destroyBody(it->second.first);
            dead.push_back(it->second.first);
            model.erase(it);
        }
    }
    ASSERT_EQ(world.bodyCount(), model.size());
    for (const auto& [data, entry] : model) {
        ASSERT_TRUE(world.isValid(entry.first));
        ASSERT_EQ(world.userData(entry.first), data);
        const Vec3 p = world.position(entry.first);
        ASSERT_EQ(p.x, float(data % 100));
        ASSERT_EQ(p.y, float(data / 100 % 100));
    }
    for (BodyId id : dead) {
        ASSERT_FALSE(world.isValid(id));
        EXPECT_NE(errorOf([&] { world.position(id); }).find("stale"), std::string::npos);
    }
    EXPECT_EQ(world.bodies().size(), model.size());
}

TEST(WorldHandles, NullAndForeignHandlesAreRefused) {
    World world;
    EXPECT_NE(errorOf([&] { world.position(BodyId{}); }).find("null"), std::string::npos);
    EXPECT_NE(errorOf([&] {
                  world.position(BodyId{12345, 1});
              }).find("stale or not from this world"),
              std::string::npos);
    EXPECT_NE(errorOf([&] { world.createBody(BodyDef{}); }).find("shape handle is null"), std::string::npos);
}

TEST(WorldValidation, RefusesBadBodyDefinitions) {
    World world;
    const ShapeId box = world.createShape(BoxDef{});
    struct Case {
        const char* expected;
        void (*edit)(BodyDef&);
    };
    const Case cases[] = {
        {"BodyDef.position is not finite", [](BodyDef& d) { d.position.y = kNaN; }},
        {"BodyDef.position is not finite", [](BodyDef& d) { d.position.x = kInf; }},
        {"BodyDef.orientation is not a unit quaternion",
         [](BodyDef& d) {
             d.orientation = {0, 0, 0, 2};
         }},
        {"BodyDef.orientation is not finite", [](BodyDef& d) { d.orientation.w = kNaN; }},
        {"BodyDef.linearVelocity is not finite", [](BodyDef& d) { d.linearVelocity.z = kInf; }},
        {"BodyDef.angularVelocity is not finite", [](BodyDef& d) { d.angularVelocity.z = kNaN; }},
        {"material.friction must be >= 0", [](BodyDef& d) { d.material.friction = -0.1f; }},
        {"material.restitution must be in [0, 1]", [](BodyDef& d) { d.material.restitution = 1.5f; }},
        {"material.density must be in [0.001, 1e+06] kg/m^3 (got 0;", [](BodyDef& d) { d.material.density = 0; }},
        {"material.density must be in [0.001, 1e+06] kg/m^3 (got 1e+38;",
         [](BodyDef& d) { d.material.density = 1e38f; }},
        {"BodyDef.position (0, 200000, 0) lies farther than 100000 m from the origin on an axis (float spacing there "
         "is 0.0078125 m",
         [](BodyDef& d) {
             d.position = {0, 2e5f, 0};
         }},
        {"BodyDef.linearDamping must be >= 0", [](BodyDef& d) { d.linearDamping = -1; }},
        {"BodyDef.gravityScale is not finite", [](BodyDef& d) { d.gravityScale = kNaN; }},
        {"a static body cannot have a velocity",
         [](BodyDef& d) {
             d.type = BodyType::Static, d.linearVelocity = {1, 0, 0};
         }},
    };
    for (const Case& c : cases) {
        BodyDef def = dynamicBox(box, {});
        c.edit(def);
        const std::string message = errorOf([&] { world.createBody(def); });
        EXPECT_NE(message.find(c.expected), std::string::npos) << message;
        EXPECT_NE(message.find("World::createBody"), std::string::npos) << message;
    }
    EXPECT_EQ(world.bodyCount(), 0u) << "refused bodies must leave nothing behind";
}

TEST(WorldValidation, RefusesBadCallsOnBodies) {
    World world;
    const BodyId body = world.createBody(dynamicBox(world.createShape(BoxDef{}), {}));
    EXPECT_NE(errorOf([&] { world.addForce(body, {kNaN, 0, 0}); }).find("force is not finite"), std::string::npos);
    EXPECT_NE(errorOf([&] {
                  world.setTransform(body, {}, {1, 1, 0, 0});
              }).find("not a unit quaternion"),
              std::string::npos);
    EXPECT_EQ(errorOf([&] { world.step(0); }), "World::step: dt must be in [1e-05, 1] s (got 0; docs/limits.md)");
    EXPECT_EQ(errorOf([&] { world.step(1e-40f); }),
              "World::step: dt must be in [1e-05, 1] s (got 9.99995e-41; docs/limits.md)")
        << "a subnormal step, which flush-to-zero would read as 0";
    EXPECT_EQ(errorOf([&] { world.step(kNaN); }), "World::step: dt is not finite (nan)");
    EXPECT_EQ(errorOf([&] {
                  world.setTransform(body, {-3e5f, 0, 0}, {});
              }),
              "World::setTransform: position (-300000, 0, 0) lies farther than 100000 m from the origin on an axis "
              "(float spacing there is 0.0078125 m; docs/limits.md)");
    WorldSettings bad;
    bad.substeps = 0;
    EXPECT_NE(errorOf([&] { world.setSettings(bad); }).find("substeps must be in [1, 64]"), std::string::npos);
    WorldSettings badReuse;
    badReuse.manifoldReuseDistance = kNaN;
    EXPECT_NE(errorOf([&] { world.setSettings(badReuse); }).find("settings.manifoldReuseDistance"), std::string::npos);
    EXPECT_NE(errorOf([&] { World w(WorldSettings{.threads = -2}); }).find("threads"), std::string::npos);
}

TEST(WorldValidation, MeshesAreStaticOnly) {
    World world;
    TriangleMeshDef mesh;
    mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
    mesh.indices = {0, 2, 1};
    const ShapeId shape = world.createShape(mesh);
    BodyDef def;
    def.shape = shape;
    EXPECT_NE(errorOf([&] { world.createBody(def); }).find("static-only"), std::string::npos);
    def.type = BodyType::Static;
    EXPECT_TRUE(world.isValid(world.createBody(def)));
    EXPECT_NE(errorOf([&] { world.destroyShape(shape); }).find("still used by 1 bodies"), std::string::npos);
}

TEST(WorldBodies, OriginAndCentreOfMassStayApartForOffsetShapes) {
    // A compound whose mass sits off its origin: the body reports its origin where it was placed and its centre
    // of mass where the compound's centre of mass lies.
    World world;
    CompoundDef compound;
    compound.children.push_back({BoxDef{{0.5f, 0.5f, 0.5f}}, Transform{{2, 0, 0}, {}}});
    const ShapeId shape = world.createShape(compound);
    BodyDef def;
    def.shape = shape;
    def.position = {1, 2, 3};
    def.orientation = Quat::fromAxisAngle({0, 1, 0}, 3.14159265f / 2);
    const BodyId id = world.createBody(def);
    const Vec3 p = world.position(id);
    EXPECT_NEAR(p.x, 1, 1e-6);
    EXPECT_NEAR(p.y, 2, 1e-6);
    EXPECT_NEAR(p.z, 3, 1e-6);
    const Vec3 c = world.centerOfMass(id);  // local (2,0,0) turned 90 degrees about y is (0,0,-2)
    EXPECT_NEAR(c.x, 1, 1e-5);
    EXPECT_NEAR(c.z, 1, 1e-5);
    EXPECT_NEAR(world.massProperties(id).mass, 1000.0f, 1e-2);
}

TEST(WorldBodies, ForcesReachOnlyDynamicBodies) {
    World world(WorldSettings{.gravity = {0, 0, 0}});
    const ShapeId box = world.createShape(BoxDef{});
    BodyDef def = dynamicBox(box, {});
    const BodyId dynamic = world.createBody(def);
    def.type = BodyType::Kinematic;
    def.linearVelocity = {1, 0, 0};
    def.position = {0, 5, 0};  // apart, so that no contact pushes either
    const BodyId kinematic = world.createBody(def);
    world.applyLinearImpulse(dynamic, {1000, 0, 0});  // 1 m/s on 1000 kg
    world.applyLinearImpulse(kinematic, {1000, 0, 0});
    EXPECT_FLOAT_EQ(world.linearVelocity(dynamic).x, 1.0f);
    EXPECT_FLOAT_EQ(world.linearVelocity(kinematic).x, 1.0f);
    world.step(0.5f);
    EXPECT_FLOAT_EQ(world.position(dynamic).x, 0.5f);
    EXPECT_FLOAT_EQ(world.position(kinematic).x, 0.5f);
}

TEST(WorldStep, ProfileListsTheStagesThatRan) {
    World world;
    const ShapeId ball = world.createShape(SphereDef{0.5f});
    world.createBody(dynamicBox(ball, {0, 10, 0}));
    world.step(1.0f / 60);
    const Profile& p = world.lastProfile();
    EXPECT_TRUE(p[Stage::IntegrateVelocities].ran);
    EXPECT_TRUE(p[Stage::IntegratePositions].ran);
    EXPECT_EQ(p.bodyCount, 1u);
    EXPECT_GT(p.stepMs, 0.0);
    EXPECT_EQ(world.stepCount(), 1u);

    // Frictionless spheres in zero gravity: nothing changes velocities, so that stage does not run.
    World still(WorldSettings{.gravity = {0, 0, 0}});
    const ShapeId s = still.createShape(SphereDef{0.5f});
    BodyDef def = dynamicBox(s, {});
    def.material.friction = 0;
    def.linearVelocity = {1, 0, 0};
    still.createBody(def);
    still.step(1.0f / 60);
    EXPECT_FALSE(still.lastProfile()[Stage::IntegrateVelocities].ran);
    EXPECT_TRUE(still.lastProfile()[Stage::IntegratePositions].ran);
}

TEST(WorldStep, StateHashIsTheSameForOneAndTwoThreads) {
    auto run = [](int threads) {
        World world(WorldSettings{.threads = threads});
        const ShapeId box = world.createShape(BoxDef{{0.3f, 0.2f, 0.5f}});
        std::mt19937 rng(3);
        std::uniform_real_distribution<float> u(-8, 8);
        // A loose cloud (a tenth of the volume filled): thousands of pairs every step, without the solver having to
        // pry apart a solid block (that is the stability tests' business, and slow under the sanitizers).
        for (int i = 0; i < 3000; ++i) {
            BodyDef def = dynamicBox(box, {u(rng), u(rng), u(rng)});
            def.linearVelocity = {u(rng), u(rng), u(rng)};
            def.angularVelocity = {u(rng), u(rng), u(rng)};
            def.linearDamping = 0.1f;
            world.createBody(def);
        }
        for (int s = 0; s < 30; ++s) world.step(1.0f / 60);
        return world.stateHash();
    };
    EXPECT_EQ(run(1), run(2));
}

TEST(WorldStep, StateHashSeesEveryBit) {
    World world;
    const BodyId id = world.createBody(dynamicBox(world.createShape(BoxDef{}), {1, 2, 3}));
    const std::uint64_t before = world.stateHash();
    world.setLinearVelocity(id, {0, 0, std::nextafter(0.0f, 1.0f)});
    EXPECT_NE(world.stateHash(), before);
}

TEST(WorldStep, NonFiniteStateFreezesTheBodyAndReportsIt) {
    World world(WorldSettings{.gravity = {0, 0, 0}});
    const ShapeId box = world.createShape(BoxDef{});
    const BodyId good = world.createBody(dynamicBox(box, {}));
    const BodyId bad = world.createBody(dynamicBox(box, {5, 0, 0}));
    // Each force is finite, but their sum is not: the velocity update overflows to infinity.
    world.addForce(bad, {3e38f, 0, 0});
    world.addForce(bad, {3e38f, 0, 0});
    world.step(1.0f / 60);
    EXPECT_TRUE(world.isFrozen(bad));
    EXPECT_FALSE(world.isFrozen(good));
    const std::vector<BodyId> frozen = world.takeFrozenBodies();
    ASSERT_EQ(frozen.size(), 1u);
    EXPECT_EQ(frozen[0], bad);
    EXPECT_TRUE(isFinite(world.position(bad)));
    EXPECT_EQ(world.position(bad).x, 5.0f);
    EXPECT_EQ(world.lastProfile().frozenCount, 1u);
}

// A body the simulation carries past the coordinate limit (docs/limits.md) is frozen where it last was inside it and
// reported once, as a non-finite one is; a body inside goes on moving.
TEST(WorldStep, ABodyLeavingTheCoordinateLimitIsFrozenAtItsEdge) {
    World world(WorldSettings{.gravity = {0, 0, 0}});
    const ShapeId box = world.createShape(BoxDef{});
    const BodyId stays = world.createBody(dynamicBox(box, {0, 0, 0}));
    world.setLinearVelocity(stays, {0, 0, 1});
    const BodyId leaves = world.createBody(dynamicBox(box, {0, 0, limits::kMaxCoordinate - 100}));
    world.setLinearVelocity(leaves, {0, 0, 1000});  // 16.7 m a step: over the edge in the seventh
    std::vector<BodyId> reported;
    int frozenAt = -1;
    for (int step = 0; step < 20; ++step) {
        world.step(1.0f / 60);
        const std::vector<BodyId> frozen = world.takeFrozenBodies();
        reported.insert(reported.end(), frozen.begin(), frozen.end());
        if (frozenAt < 0 && world.isFrozen(leaves)) frozenAt = step;
    }
    EXPECT_EQ(reported, std::vector<BodyId>{leaves});
    EXPECT_EQ(frozenAt, 6);
    EXPECT_LE(world.position(leaves).z, limits::kMaxCoordinate);
    EXPECT_GT(world.position(leaves).z, limits::kMaxCoordinate - 1000.0f / 60);
    EXPECT_EQ(world.linearVelocity(leaves).z, 0.0f);
    EXPECT_FALSE(world.isFrozen(stays));
    EXPECT_NEAR(world.position(stays).z, 20.0f / 60, 1e-4f);
}

// A body whose state goes non-finite is frozen and reported, and the rest of the world moves bit for bit as it would
// have without it: here a pile of boxes landing on the ground (contacts forming as they move), on one and two threads,
// with a body far off pushed to infinity in the sixth step.
TEST(WorldStep, AFrozenBodyLeavesTheRestOfTheWorldBitForBit) {
    for (const int threads : {1, 2}) {
        const auto run = [&](bool withRunaway) {
            World world(WorldSettings{.threads = threads});
            const ShapeId box = world.createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
            BodyDef ground;
            ground.type = BodyType::Static;
            ground.shape = world.createShape(BoxDef{{20, 0.5f, 20}});
            ground.position = {0, -0.5f, 0};
            world.createBody(ground);
            std::vector<BodyId> pile;
            for (int i = 0; i < 24; ++i)
                pile.push_back(world.createBody(
                    dynamicBox(box, {0.3f * static_cast<float>(i % 3), 0.6f + 1.1f * static_cast<float>(i / 3),
                                     0.2f * static_cast<float>(i % 2)})));
            BodyId runaway;
            if (withRunaway) runaway = world.createBody(dynamicBox(box, {15, 3, 15}));
            for (int step = 0; step < 90; ++step) {
                if (withRunaway && step == 5) {
                    world.addForce(runaway, {3e38f, 0, 0});
                    world.addForce(runaway, {3e38f, 0, 0});
                }
                world.step(1.0f / 60);
            }
            if (withRunaway) {
                EXPECT_TRUE(world.isFrozen(runaway));
                EXPECT_EQ(world.takeFrozenBodies(), std::vector<BodyId>{runaway});
            }
            std::vector<float> state;
            for (const BodyId id : pile) {
                const Vec3 p = world.position(id), v = world.linearVelocity(id), w = world.angularVelocity(id);
                const Quat q = world.orientation(id);
                state.insert(state.end(), {p.x, p.y, p.z, q.x, q.y, q.z, q.w, v.x, v.y, v.z, w.x, w.y, w.z});
            }
            return state;
        };
        const std::vector<float> without = run(false), with = run(true);
        ASSERT_EQ(with.size(), without.size());
        for (std::size_t i = 0; i < with.size(); ++i)
            ASSERT_EQ(std::bit_cast<std::uint32_t>(with[i]), std::bit_cast<std::uint32_t>(without[i]))
                << "value " << i << " of the pile, " << threads << " thread(s)";
    }
}

TEST(WorldHandles, StorageInvariantsHoldAfterChurn) {
    // Reaches the storage directly: the slot map and the dense rows must agree after arbitrary churn.
    rubble::detail::BodyStorage storage;
    std::vector<BodyId> live;
    std::mt19937 rng(11);
    for (int i = 0; i < 5000; ++i) {
        if (live.empty() || rng() % 3 != 0) {
            std::uint32_t dense;
            live.push_back(
                storage.allocate(rng() % 2 ? rubble::detail::BodySet::Moving : rubble::detail::BodySet::Static, dense));
        } else {
            const std::size_t k = rng() % live.size();
            storage.release(live[k]);
            live[k] = live.back();
            live.pop_back();
        }
    }
    EXPECT_EQ(storage.checkInvariants(), "");
    EXPECT_EQ(storage.count(), live.size());
}

TEST(WorldStep, ForcesActOverEverySubstep) {
    // A constant force F over one step of dt gives dv = F dt / m whatever the substep count.
    for (int substeps : {1, 4}) {
        World world(WorldSettings{.gravity = {0, 0, 0}, .substeps = substeps});
        const BodyId id = world.createBody(dynamicBox(world.createShape(BoxDef{}), {}));
        world.addForce(id, {1000, 0, 0});  // 1000 kg box: 1 m/s^2
        world.step(0.5f);
        EXPECT_FLOAT_EQ(world.linearVelocity(id).x, 0.5f) << substeps << " substeps";
        world.step(0.5f);  // the accumulator was cleared after the step
        EXPECT_FLOAT_EQ(world.linearVelocity(id).x, 0.5f) << substeps << " substeps";
    }
}

TEST(WorldBodies, AngularImpulseFollowsTheWorldInertiaTensor) {
    // An asymmetric hull (off-diagonal inertia), turned arbitrarily: the angular velocity change from an angular
    // impulse L must be (R I R^T)^-1 L, inverted here by Eigen from the body's own mass properties.
    World world(WorldSettings{.gravity = {0, 0, 0}});
    ConvexHullDef hull;
    hull.points = {{0, 0, 0}, {2, 0, 0}, {0, 1, 0}, {0, 0, 0.5f}, {1.5f, 0.8f, 0.3f}, {0.2f, 0.1f, 0.9f}};
    BodyDef def;
    def.shape = world.createShape(hull);
    def.material.density = 700;
    def.orientation = Quat::fromAxisAngle({1, 2, 3}, 0.7f);
    const BodyId id = world.createBody(def);

    const MassProperties mp = world.massProperties(id);
    Eigen::Matrix3d inertia, rotation;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) inertia(r, c) = mp.inertia(r, c);
    const Quat q = world.orientation(id);
    rotation = Eigen::Quaterniond(q.w, q.x, q.y, q.z).toRotationMatrix();
    const Eigen::Vector3d impulse(3, -1, 2);
    const Eigen::Vector3d expected = (rotation * inertia * rotation.transpose()).inverse() * impulse;

    world.applyAngularImpulse(id, {3, -1, 2});
    const Vec3 w = world.angularVelocity(id);
    const double scale = expected.norm();
    EXPECT_NEAR(w.x, expected.x(), 1e-4 * scale);  // float storage of a tensor with entries ~1e2: 1e-4 relative
    EXPECT_NEAR(w.y, expected.y(), 1e-4 * scale);
    EXPECT_NEAR(w.z, expected.z(), 1e-4 * scale);
}
