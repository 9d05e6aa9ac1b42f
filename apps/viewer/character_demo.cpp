// The character demo (see character_demo.h).
#include "character_demo.h"

#include <algorithm>
#include <cmath>

#include "rubble/world.h"

namespace rubble::viewer {

namespace {

constexpr float kPi = 3.14159265f;

BodyId addBox(World& world, Vec3 center, Vec3 half, Quat rotation = {}, BodyType type = BodyType::Static) {
    BodyDef def;
    def.type = type;
    def.shape = world.createShape(BoxDef{half});
    def.position = center;
    def.orientation = rotation;
    return world.createBody(def);
}

Quat aboutZ(float angle) { return {0, 0, std::sin(angle / 2), std::cos(angle / 2)}; }

}  // namespace

World CharacterDemo::makeWorld() {
    WorldSettings settings;
    settings.threads = 1;
    settings.effects = EffectSet::defaults();
    return World(settings);
}

void CharacterDemo::build(World& world) {
    // The floor: one mesh of 1 m squares.
    TriangleMeshDef mesh;
    constexpr int kX0 = -6, kX1 = 36, kZ0 = -6, kZ1 = 6;
    for (int x = kX0; x <= kX1; ++x)
        for (int z = kZ0; z <= kZ1; ++z) mesh.vertices.push_back({static_cast<float>(x), 0, static_cast<float>(z)});
    const auto at = [&](int x, int z) { return static_cast<std::uint32_t>((x - kX0) * (kZ1 - kZ0 + 1) + (z - kZ0)); };
    for (int x = kX0; x < kX1; ++x)
        for (int z = kZ0; z < kZ1; ++z)
            mesh.indices.insert(mesh.indices.end(),
                                {at(x, z), at(x, z + 1), at(x + 1, z), at(x + 1, z), at(x, z + 1), at(x + 1, z + 1)});
    BodyDef floorDef;
    floorDef.type = BodyType::Static;
    floorDef.shape = world.createShape(mesh);
    floor = world.createBody(floorDef);

    // A corridor 3 m wide from x = 0 to 8 with a pillar to walk round.
    addBox(world, {4, 1.25f, 1.6f}, {4, 1.25f, 0.1f});
    addBox(world, {4, 1.25f, -1.6f}, {4, 1.25f, 0.1f});
    addBox(world, {4, 1.25f, -0.65f}, {0.3f, 1.25f, 0.85f});
    // Six stairs of 0.2 m up to a landing 1.2 m high, then a 20 degree ramp down.
    for (int s = 0; s < 6; ++s) {
        const float top = 0.2f * static_cast<float>(s + 1), front = 10 + 0.35f * static_cast<float>(s);
        addBox(world, {0.5f * (front + 16), 0.5f * top, 0}, {0.5f * (16 - front), 0.5f * top, 1.5f});
    }
    const float ramp = 20 * kPi / 180, rampLength = 1.2f / std::sin(ramp);
    const Vec3 down{std::cos(ramp), -std::sin(ramp), 0}, rampNormal{std::sin(ramp), std::cos(ramp), 0};
    addBox(world, Vec3{16, 1.2f, 0} + down * (0.5f * rampLength) - rampNormal * 0.1f, {0.5f * rampLength, 0.1f, 1.5f},
           aboutZ(-ramp));
    // The lift and the ledge it serves.
    lift = addBox(world, {23, kLiftLow - 0.1f, 0}, {1, 0.1f, 1.5f}, {}, BodyType::Kinematic);
    ledge = addBox(world, {28, 1, 0}, {4, 1, 1.5f});
    // Crates beside the course to push about, and coins on it to pick up.
    const ShapeId crate = world.createShape(BoxDef{{0.3f, 0.3f, 0.3f}});
    for (int k = 0; k < 6; ++k) {
        BodyDef def;
        def.shape = crate;
        def.position = {18.5f + 0.7f * static_cast<float>(k % 3), 0.3f + 0.6f * static_cast<float>(k / 3), 3};
        def.material.density = 150;
        crates.push_back(world.createBody(def));
    }
    const ShapeId coin = world.createShape(SphereDef{0.25f});
    for (const Vec3 p : {Vec3{-0.5f, 1, 0}, Vec3{6, 1, 0.85f}, Vec3{13, 2, 0}, Vec3{20, 1, 0}, Vec3{30, 3, 0}}) {
        BodyDef def;
        def.type = BodyType::Static;
        def.shape = coin;
        def.position = p;
        def.sensor = true;
        coins.push_back(world.createBody(def));
    }
    path = {{-0.5f, 0, 0}, {3, 0, 0.85f}, {5, 0, 0.85f}, {9, 0, 0},    {14, 0, 0},
            {15.8f, 0, 0}, {21, 0, 0},    {23, 0, 0},    {kEndX, 0, 0}};
}

Vec3 CharacterDemo::walkVelocity(float right, float forward, Vec3 cameraForward) const {
    Vec3 ahead{cameraForward.x, 0, cameraForward.z};
    const float size = length(ahead);
    if (size < 1e-4f) return {};
    ahead = ahead / size;
    const Vec3 side{-ahead.z, 0, ahead.x};
    Vec3 walk = ahead * forward + side * right;
    const float speed = length(walk);
    return speed > 1 ? walk * (kWalkSpeed / speed) : walk * kWalkSpeed;
}

Vec3 CharacterDemo::autopilotWalk(const CharacterState& character) {
    while (nextWaypoint < path.size()) {
        const Vec3 to{path[nextWaypoint].x - character.feet.x, 0, path[nextWaypoint].z - character.feet.z};
        const float d = length(to);
        if (d > 0.1f) {
            // On the lift, wait until it is up.
            if (character.ground == lift && liftHeight < kLiftHigh - 1e-3f) return {};
            return to * (std::min(kWalkSpeed, 2 * d) / d);
        }
        ++nextWaypoint;
    }
    return {};
}

MoveKinematicCommand CharacterDemo::moveLift(const CharacterState& character, float dt) {
    const bool riding = character.ground == lift;
    const bool away = character.feet.x < 21 || (character.feet.x > 24.5f && character.feet.y > kLiftHigh - 0.1f);
    if (riding)
        liftHeight = std::min(kLiftHigh, liftHeight + kLiftSpeed * dt);
    else if (away)
        liftHeight = std::max(kLiftLow, liftHeight - kLiftSpeed * dt);
    return {lift, {23, liftHeight - 0.1f, 0}, {}, dt};
}

std::vector<BodyId> CharacterDemo::collect(const std::vector<StepEvents>& events, BodyId characterBody) {
    std::vector<BodyId> taken;
    for (const StepEvents& step : events)
        for (const SensorBeginEvent& e : step.sensors.begins)
            if (e.visitor == characterBody && std::find(coins.begin(), coins.end(), e.sensor) != coins.end() &&
                std::find(taken.begin(), taken.end(), e.sensor) == taken.end()) {
                taken.push_back(e.sensor);
                ++coinsCollected;
            }
    return taken;
}

}  // namespace rubble::viewer
