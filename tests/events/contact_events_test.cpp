// Contact events and World::contactsOf through the public API, each checked against something the events code does
// not compute: momentum balance for hit impulses (a body touching only one other changes its momentum by gravity's
// impulse plus the contact's), free-fall kinematics for when a drop touches, the geometry of spheres (exact distances)
// for which pairs touch, and a second run on another thread count for the order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "rubble/error.h"
#include "rubble/world.h"

namespace rubble {
namespace {

constexpr float kDt = 1.0f / 60.0f;

BodyId addFloor(World& world, bool listen = false) {
    BodyDef def;
    def.type = BodyType::Static;
    def.shape = world.createShape(BoxDef{{50, 0.5f, 50}});
    def.position = {0, -0.5f, 0};
    def.contactEvents = listen;
    return world.createBody(def);
}

BodyId addBall(World& world, Vec3 position, float radius, bool listen, float restitution = 0) {
    BodyDef def;
    def.shape = world.createShape(SphereDef{radius});
    def.position = position;
    def.contactEvents = listen;
    def.material.restitution = restitution;
    return world.createBody(def);
}

std::pair<BodyId, BodyId> ordered(BodyId x, BodyId y) { return x.index < y.index ? std::pair{x, y} : std::pair{y, x}; }

TEST(ContactEvents, DroppedBallBeginsTouchWhenFreeFallSaysAndReportsItsHitImpulse) {
    World world;
    const BodyId floor = addFloor(world);
    // Dropped from 1.25 m (centre 1.5 m): lands at t = sqrt(2 h / g) = 0.505 s, at 4.95 m/s.
    const BodyId ball = addBall(world, {0, 1.5f, 0}, 0.25f, true, 0.5f);
    const float g = 9.81f, mass = world.massProperties(ball).mass;
    int beginStep = -1, hits = 0;
    for (int i = 0; i < 90; ++i) {
        const float vBefore = world.linearVelocity(ball).y;
        world.step(kDt);
        const ContactEvents& e = world.contactEvents();
        if (!e.begins.empty() && beginStep < 0) {
            beginStep = i;
            ASSERT_EQ(e.begins.size(), 1u);
            EXPECT_EQ(ordered(e.begins[0].a, e.begins[0].b), ordered(ball, floor));
        }
        for (const ContactHitEvent& hit : e.hits) {
            ++hits;
            EXPECT_EQ(ordered(hit.a, hit.b), ordered(ball, floor));
            // The only contact of the ball: its momentum change less gravity's impulse is the contact's.
            const float contactImpulse = mass * (world.linearVelocity(ball).y - vBefore) + mass * g * kDt;
            EXPECT_NEAR(hit.impulse, contactImpulse, 0.02f * contactImpulse) << "step " << i;
            // The approach speed is the ball's before the solve: what it fell to, within one step of gravity.
            EXPECT_NEAR(hit.approachSpeed, -vBefore, g * kDt) << "step " << i;
            const Vec3 up = hit.a == floor ? hit.normal : -hit.normal;
            EXPECT_NEAR(up.y, 1.0f, 1e-4f);
            EXPECT_NEAR(hit.point.y, 0.0f, 0.03f);
        }
    }
    // First touch in the step during which free fall reaches the floor: 0.505 s, give or take a step (the substeps'
    // Euler falls a little ahead of the parabola).
    EXPECT_NEAR((static_cast<float>(beginStep) + 0.5f) * kDt, std::sqrt(2 * 1.25f / g), kDt);
    // Restitution 0.5: it bounces (2.5 m/s, then 1.2 m/s, both above the 1 m/s hit speed) and lands again.
    EXPECT_GE(hits, 2);
}

TEST(ContactEvents, ProjectileHitReportsTheImpulseThatStoppedIt) {
    World world;
    addFloor(world);
    BodyDef wall;
    wall.shape = world.createShape(BoxDef{{0.5f, 1.0f, 1.0f}});
    wall.position = {5, 1.0f, 0};
    wall.material.density = 5000;
    const BodyId target = world.createBody(wall);
    BodyDef shot;
    shot.shape = world.createShape(SphereDef{0.05f});
    shot.position = {0, 1.0f, 0};
    shot.linearVelocity = {40, 0, 0};
    shot.gravityScale = 0;
    shot.contactEvents = true;
    shot.material.density = 7800;
    const BodyId bullet = world.createBody(shot);
    const float mass = world.massProperties(bullet).mass;
    bool hit = false;
    for (int i = 0; i < 20 && !hit; ++i) {
        const Vec3 before = world.linearVelocity(bullet);
        world.step(kDt);
        for (const ContactHitEvent& e : world.contactEvents().hits) {
            hit = true;
            EXPECT_EQ(ordered(e.a, e.b), ordered(bullet, target));
            EXPECT_NEAR(e.approachSpeed, 40.0f, 0.5f);
            // Only the wall touched the bullet (no gravity on it): its momentum change is the hit's impulse.
            const float stopped = mass * (before.x - world.linearVelocity(bullet).x);
            EXPECT_GT(stopped, 0.5f * mass * 40.0f);
            EXPECT_NEAR(e.impulse, stopped, 0.02f * stopped);
            const Vec3 towardWall = e.a == bullet ? e.normal : -e.normal;
            EXPECT_NEAR(towardWall.x, 1.0f, 1e-3f);
        }
    }
    EXPECT_TRUE(hit);
}

TEST(ContactEvents, BodiesNobodyListensToReportNothingAndCostNoEventStage) {
    World world;
    addFloor(world);
    addBall(world, {0, 0.6f, 0}, 0.25f, false);
    for (int i = 0; i < 60; ++i) world.step(kDt);
    EXPECT_TRUE(world.contactEvents().begins.empty());
    EXPECT_TRUE(world.contactEvents().hits.empty());
    EXPECT_FALSE(world.lastProfile()[Stage::Events].ran);
}

/// Spheres of equal radius dropped into a walled pit, all listening. After every step the pairs the events say touch
/// (begins less ends so far) are checked against the exact distances of the sphere centres by brute force over every
/// pair: a pair within the linear slop at the start of the step touches (contacts are found where the bodies start
/// it); a pair apart by more than the contact margin at the start, whose speeds then could not close its gap within
/// the step (gravity included) and that did not close in by half of it, does not. Pairs in between are not judged: the
/// events also count a pair whose contact pushed in the step (a speculative contact acts when the approach would close
/// the gap within a substep, and a pair that touched in the last step may keep some push while it parts by a few
/// millimetres), which a test of the step's two ends cannot see; nor are pairs within 0.2 mm of the slop (the kernel's
/// float depth may fall either side).
TEST(ContactEvents, TouchingPairsMatchSphereGeometryEveryStep) {
    WorldSettings settings;
    settings.threads = 2;
    World world(settings);
    const BodyId floor = addFloor(world);
    const ShapeId wallShape = world.createShape(BoxDef{{0.25f, 2, 2}});
    for (int side = 0; side < 2; ++side) {
        BodyDef wall;
        wall.type = BodyType::Static;
        wall.shape = wallShape;
        wall.position = {side == 0 ? -1.75f : 1.75f, 2, 0};
        world.createBody(wall);
    }
    const float r = 0.2f;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> jitter(-0.05f, 0.05f);
    std::vector<BodyId> balls;
    for (int k = 0; k < 48; ++k) {
        const float x = -1.2f + 0.45f * static_cast<float>(k % 6) + jitter(rng);
        const float y = 0.4f + 0.5f * static_cast<float>(k / 6);
        const float z = jitter(rng);
        balls.push_back(addBall(world, {x, y, z}, r, true));
    }
    const float slop = world.settings().solver.linearSlop, margin = world.settings().contactMargin, band = 2e-4f;
    std::set<std::pair<unsigned, unsigned>> held;
    const auto key = [](BodyId x, BodyId y) {
        return std::pair{std::min(x.index, y.index), std::max(x.index, y.index)};
    };
    int judged = 0, touchingSeen = 0;
    const auto judge = [&](BodyId x, BodyId y, float startGap, float approach, float endGap, int step) {
        const bool touching = startGap <= slop - band;
        const bool reachable = startGap <= approach * kDt + 0.5f * 9.81f * kDt * kDt;
        const bool apart = startGap > margin && !reachable && endGap > 0.5f * startGap;
        if (!touching && !apart) return;
        EXPECT_EQ(held.count(key(x, y)) == 1, touching)
            << "step " << step << " bodies " << x.index << ", " << y.index << " gaps " << startGap << ", " << endGap;
        touchingSeen += touching;
        ++judged;
    };
    for (int i = 0; i < 150; ++i) {
        std::vector<Vec3> start, velocity;
        for (const BodyId b : balls) start.push_back(world.position(b)), velocity.push_back(world.linearVelocity(b));
        world.step(kDt);
        for (const ContactBeginEvent& e : world.contactEvents().begins) EXPECT_TRUE(held.insert(key(e.a, e.b)).second);
        for (const ContactEndEvent& e : world.contactEvents().ends) EXPECT_EQ(held.erase(key(e.a, e.b)), 1u);
        for (std::size_t p = 0; p < balls.size(); ++p) {
            // Against the floor (top at y = 0); the pit's columns do not reach the walls.
            judge(balls[p], floor, start[p].y - r, -velocity[p].y, world.position(balls[p]).y - r, i);
            for (std::size_t q = p + 1; q < balls.size(); ++q) {
                const Vec3 between = start[q] - start[p];
                const float approach = dot(velocity[p] - velocity[q], between) / length(between);
                judge(balls[p], balls[q], length(between) - 2 * r, approach,
                      length(world.position(balls[p]) - world.position(balls[q])) - 2 * r, i);
            }
        }
    }
    EXPECT_GT(touchingSeen, 1000);
    EXPECT_GT(judged, 150000);
}

struct Recorded {
    std::vector<std::tuple<int, unsigned, unsigned>> begins, ends;
    std::vector<std::tuple<int, unsigned, unsigned, float, float, float, float>> hits;
    friend bool operator==(const Recorded&, const Recorded&) = default;
};

Recorded dropPile(int threads) {
    WorldSettings settings;
    settings.threads = threads;
    World world(settings);
    addFloor(world, true);
    const ShapeId box = world.createShape(BoxDef{{0.3f, 0.2f, 0.25f}});
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> offset(-0.5f, 0.5f), angle(-3.14f, 3.14f);
    for (int k = 0; k < 120; ++k) {
        BodyDef def;
        def.shape = box;
        def.position = {offset(rng), 0.5f + 0.45f * static_cast<float>(k), offset(rng)};
        const float a = angle(rng);
        def.orientation = {0, std::sin(a / 2), 0, std::cos(a / 2)};
        def.contactEvents = k % 2 == 0;
        world.createBody(def);
    }
    Recorded r;
    for (int i = 0; i < 200; ++i) {
        world.step(kDt);
        const ContactEvents& e = world.contactEvents();
        for (const auto& b : e.begins) r.begins.emplace_back(i, b.a.index, b.b.index);
        for (const auto& b : e.ends) r.ends.emplace_back(i, b.a.index, b.b.index);
        for (const auto& h : e.hits)
            r.hits.emplace_back(i, h.a.index, h.b.index, h.approachSpeed, h.impulse, h.point.y, h.normal.y);
    }
    return r;
}

TEST(ContactEvents, SameEventsInTheSameOrderOnOneAndTwoThreads) {
    const Recorded one = dropPile(1), two = dropPile(2);
    EXPECT_GT(one.begins.size(), 100u);
    EXPECT_GT(one.hits.size(), 50u);
    EXPECT_GT(one.ends.size(), 10u);
    EXPECT_TRUE(one == two);
    // Each step's events come sorted by the pair's slots.
    for (std::size_t k = 1; k < one.begins.size(); ++k) EXPECT_LE(one.begins[k - 1], one.begins[k]);
}

TEST(ContactEvents, SleepingPairKeepsTouchingUntilItWakesAndParts) {
    WorldSettings settings;
    settings.effects = EffectSet::defaults().with(Effect::Sleeping);
    World world(settings);
    const BodyId floor = addFloor(world);
    BodyDef def;
    def.shape = world.createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    def.position = {0, 0.6f, 0};
    def.contactEvents = true;
    const BodyId box = world.createBody(def);
    int begins = 0, ends = 0;
    for (int i = 0; i < 180; ++i) {
        world.step(kDt);
        begins += static_cast<int>(world.contactEvents().begins.size());
        ends += static_cast<int>(world.contactEvents().ends.size());
    }
    ASSERT_FALSE(world.isAwake(box));
    EXPECT_EQ(begins, 1);
    EXPECT_EQ(ends, 0);
    std::vector<BodyContact> contacts;
    ASSERT_EQ(world.contactsOf(box, contacts), 1u);
    EXPECT_EQ(contacts[0].other, floor);
    world.applyLinearImpulse(box, {0, 5.0f * world.massProperties(box).mass, 0});
    for (int i = 0; i < 10; ++i) {
        world.step(kDt);
        ends += static_cast<int>(world.contactEvents().ends.size());
    }
    EXPECT_EQ(ends, 1);
}

TEST(ContactEvents, DestroyedOrSilencedBodyEndsItsPairs) {
    World world;
    const BodyId floor = addFloor(world);
    const BodyId a = addBall(world, {-1, 0.25f, 0}, 0.25f, true);
    const BodyId b = addBall(world, {1, 0.25f, 0}, 0.25f, true);
    world.step(kDt);
    ASSERT_EQ(world.contactEvents().begins.size(), 2u);
    world.destroyBody(a);
    world.step(kDt);
    ASSERT_EQ(world.contactEvents().ends.size(), 1u);
    EXPECT_EQ(ordered(world.contactEvents().ends[0].a, world.contactEvents().ends[0].b), ordered(a, floor));
    EXPECT_FALSE(world.isValid(a));
    world.setContactEvents(b, false);
    EXPECT_FALSE(world.contactEventsEnabled(b));
    world.step(kDt);
    ASSERT_EQ(world.contactEvents().ends.size(), 1u);
    EXPECT_EQ(ordered(world.contactEvents().ends[0].a, world.contactEvents().ends[0].b), ordered(b, floor));
    world.step(kDt);
    EXPECT_TRUE(world.contactEvents().ends.empty());
    EXPECT_FALSE(world.lastProfile()[Stage::Events].ran);
}

TEST(ContactsOf, RestingBoxCarriesItsWeightThroughItsContact) {
    World world;
    const BodyId floor = addFloor(world);
    BodyDef def;
    def.shape = world.createShape(BoxDef{{0.5f, 0.25f, 0.5f}});
    def.position = {0, 0.25f, 0};
    const BodyId box = world.createBody(def);
    for (int i = 0; i < 60; ++i) world.step(kDt);
    std::vector<BodyContact> contacts;
    ASSERT_EQ(world.contactsOf(box, contacts), 1u);
    const BodyContact& c = contacts[0];
    EXPECT_EQ(c.other, floor);
    EXPECT_NEAR(c.normal.y, -1.0f, 1e-4f);
    EXPECT_EQ(c.pointCount, 4);
    EXPECT_EQ(c.triangle, kNoIndex);
    // At rest the contact carries the weight: over the last substep, m g h (2%: the soft contact still breathes).
    const float h = kDt / static_cast<float>(world.settings().substeps);
    float impulse = 0;
    for (int i = 0; i < c.pointCount; ++i) {
        impulse += c.points[i].normalImpulse;
        EXPECT_NEAR(c.points[i].depth, 0.0f, 0.01f);
        EXPECT_LT(c.points[i].frictionImpulse, 1e-3f * c.points[i].normalImpulse + 1e-6f);
    }
    EXPECT_NEAR(impulse, world.massProperties(box).mass * 9.81f * h,
                0.02f * world.massProperties(box).mass * 9.81f * h);
    // The floor sees the same contact, its normal turned towards the box.
    std::vector<BodyContact> fromFloor;
    ASSERT_EQ(world.contactsOf(floor, fromFloor), 1u);
    EXPECT_EQ(fromFloor[0].other, box);
    EXPECT_NEAR(fromFloor[0].normal.y, 1.0f, 1e-4f);
    // A body created since the step has none; a stale handle is refused.
    const BodyId fresh = addBall(world, {3, 0.25f, 0}, 0.25f, false);
    contacts.clear();
    EXPECT_EQ(world.contactsOf(fresh, contacts), 0u);
    world.destroyBody(fresh);
    EXPECT_THROW(world.contactsOf(fresh, contacts), Error);
}

TEST(ContactEvents, HitSpeedSettingIsValidated) {
    WorldSettings settings;
    settings.hitEventSpeed = -1;
    EXPECT_THROW(World{settings}, Error);
}

}  // namespace
}  // namespace rubble
