// Measurement scenes whose answer is not a trajectory: structures that should stand where they were built or come to
// rest where statics puts them, joints that should keep their length, walls that nothing may pass, a gas whose
// energy is kept, and the stability suite's hard cases with the figures they declare.
#include <cmath>
#include <limits>
#include <random>

#include "analytic_scenes.h"
#include "rubble/error.h"
#include "rubble/scene.h"
#include "spinning_rods.h"
#include "stepping.h"

namespace rubble::accuracy {
namespace {

double distance(Vec3 a, Vec3 b) { return static_cast<double>(rubble::length(a - b)); }

EffectSet stackingEffects() { return EffectSet{}.with(Effect::Gravity).with(Effect::Rotation).with(Effect::Friction); }

/// Bodies and the poses statics puts them at; the error is the worst distance from it at the end.
struct Structure {
    std::vector<BodyId> bodies;
    std::vector<Vec3> rest;

    void measure(const World& world, Measured& out) const {
        for (std::size_t i = 0; i < bodies.size(); ++i) {
            out.error = std::max(out.error, distance(world.centerOfMass(bodies[i]), rest[i]));
            out.secondaryError =
                std::max(out.secondaryError, static_cast<double>(rubble::length(world.linearVelocity(bodies[i]))));
        }
    }
};

Measured tower(const WorldSettings& sweep, Length length) {
    // Ten 1 m cubes built touching: each should stay where it was put.
    const int copies = copiesFor(length, 8);
    World world(withSceneEffects(sweep, stackingEffects()));
    addGround(world, 40.0f, 40.0f);
    const ShapeId cube = world.createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    Structure tower;
    for (int c = 0; c < copies; ++c)
        for (int level = 0; level < 10; ++level) {
            BodyDef def;
            def.shape = cube;
            def.position = {3.0f * static_cast<float>(c) - 12.0f, 0.5f + static_cast<float>(level), 0};
            tower.bodies.push_back(world.createBody(def));
            tower.rest.push_back(def.position);
        }
    Measured out;
    stepTimed(world, stepsFor(length == Length::Full ? 5.0 : 2.0, sweep.timeStep), out);
    tower.measure(world, out);
    // Penetration: how far each cube's bottom face sits inside what is under it (the cube below, or the ground at
    // y = 0), from the lowest corner, so that a tilted cube counts by its deepest point.
    out.secondaryError = 0;
    const auto lowest = [&](BodyId id) {
        const Transform t = world.transform(id);
        float y = std::numeric_limits<float>::infinity();
        for (int corner = 0; corner < 8; ++corner)
            y = std::min(y,
                         apply(t, {corner & 1 ? 0.5f : -0.5f, corner & 2 ? 0.5f : -0.5f, corner & 4 ? 0.5f : -0.5f}).y);
        return static_cast<double>(y);
    };
    for (std::size_t i = 0; i < tower.bodies.size(); ++i) {
        const double support = i % 10 == 0 ? 0.0 : static_cast<double>(world.centerOfMass(tower.bodies[i - 1]).y) + 0.5;
        out.secondaryError = std::max(out.secondaryError, support - lowest(tower.bodies[i]));
    }
    return out;
}

Measured pyramidDropped(const WorldSettings& sweep, Length length) {
    // A pyramid of ten rows of 1 m cubes (5 cm apart in a row), each row created 3 cm above where it rests, so that
    // contacts form as the rows land: statics puts every cube straight below where it was created.
    constexpr int kRows = 10;
    constexpr float kPitch = 1.05f, kDrop = 0.03f;
    const int copies = length == Length::Full ? 3 : 1;
    World world(withSceneEffects(sweep, stackingEffects()));
    addGround(world, 40.0f, 40.0f);
    const ShapeId cube = world.createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    Structure pyramid;
    for (int c = 0; c < copies; ++c)
        for (int row = 0; row < kRows; ++row)
            for (int k = 0; k < kRows - row; ++k) {
                const float x = kPitch * (static_cast<float>(k) + 0.5f * static_cast<float>(row) - 4.5f);
                const Vec3 rest{x, 0.5f + static_cast<float>(row), 15.0f * static_cast<float>(c) - 15.0f};
                BodyDef def;
                def.shape = cube;
                def.position = rest + Vec3{0, kDrop * static_cast<float>(row + 1), 0};
                pyramid.bodies.push_back(world.createBody(def));
                pyramid.rest.push_back(rest);
            }
    Measured out;
    stepTimed(world, stepsFor(length == Length::Full ? 4.0 : 2.0, sweep.timeStep), out);
    pyramid.measure(world, out);
    return out;
}

Measured chainStretch(const WorldSettings& sweep, Length length, float massRatio) {
    // Twenty 8 cm balls ball-jointed 10 cm apart from a static pin, a ball of `massRatio` times a link's mass at the
    // end, released horizontally: the largest gap any joint opens while it falls and swings.
    constexpr int kLinks = 20;
    constexpr float kLinkRadius = 0.04f, kPitch = 0.1f;
    const float kBallRadius = kLinkRadius * std::cbrt(massRatio);
    const int copies = copiesFor(length, 8);
    World world(withSceneEffects(sweep, EffectSet{}.with(Effect::Gravity).with(Effect::Rotation).with(Effect::Joints)));
    const ShapeId link = world.createShape(SphereDef{kLinkRadius});
    const ShapeId ball = world.createShape(SphereDef{kBallRadius});
    const ShapeId pinShape = world.createShape(SphereDef{0.01f});
    struct Anchors {
        BodyId a, b;
        Vec3 localA, localB;
    };
    std::vector<Anchors> joints;
    for (int c = 0; c < copies; ++c) {
        const Vec3 pin{0, 5, 1.0f * static_cast<float>(c)};
        BodyDef pinDef;
        pinDef.type = BodyType::Static;
        pinDef.shape = pinShape;
        pinDef.position = pin;
        BodyId previous = world.createBody(pinDef);
        Vec3 previousCentre = pin;
        for (int k = 0; k <= kLinks; ++k) {
            const bool last = k == kLinks;
            const Vec3 joint = previousCentre + Vec3{k == 0 ? 0.0f : 0.5f * kPitch, 0, 0};
            const float reach = last ? kBallRadius + 0.01f : 0.5f * kPitch;
            BodyDef def;
            def.shape = last ? ball : link;
            def.position = joint + Vec3{reach, 0, 0};
            const BodyId body = world.createBody(def);
            BallJointDef j;
            j.bodyA = previous;
            j.bodyB = body;
            j.localAnchorA = joint - previousCentre;
            j.localAnchorB = joint - def.position;
            world.createJoint(j);
            joints.push_back({previous, body, j.localAnchorA, j.localAnchorB});
            previous = body, previousCentre = def.position;
        }
    }
    Measured out;
    stepTimed(world, stepsFor(3.0, sweep.timeStep), out, [&](long) {
        for (const Anchors& j : joints)
            out.error = std::max(
                out.error, distance(apply(world.transform(j.a), j.localA), apply(world.transform(j.b), j.localB)));
    });
    for (const Anchors& j : joints)
        out.secondaryError = std::max(
            out.secondaryError, distance(apply(world.transform(j.a), j.localA), apply(world.transform(j.b), j.localB)));
    return out;
}

Measured spinningRods(const WorldSettings& sweep, Length length) {
    // A rod counts as tunnelled once a tip ends a step beyond its wall, through the wall's face.
    World world(withSceneEffects(sweep, EffectSet{}.with(Effect::Rotation).with(Effect::Friction)));
    const SpinningRods scene = buildSpinningRods(world, copiesFor(length, 128));
    std::vector<bool> through(scene.rods.size(), false);
    Measured out;
    stepTimed(world, stepsFor(1.0, sweep.timeStep), out, [&](long) {
        for (std::size_t i = 0; i < scene.rods.size(); ++i) through[i] = through[i] || scene.tipPassedWall(world, i);
    });
    out.error = static_cast<double>(std::count(through.begin(), through.end(), true));
    out.secondaryError = 100.0 * out.error / static_cast<double>(scene.rods.size());
    return out;
}

Measured gas(const WorldSettings& sweep, Length length) {
    // Balls at 3 m/s in random directions in a closed box, restitution 1 everywhere, no friction or gravity: every
    // collision above the 1 m/s bounce threshold keeps the kinetic energy; the error is what the run lost or gained.
    const int side = length == Length::Full ? 16 : 10;
    World world(withSceneEffects(sweep, EffectSet{}.with(Effect::Rotation).with(Effect::Restitution)));
    Material elastic;
    elastic.friction = 0;
    elastic.restitution = 1;
    const float half = 0.5f * static_cast<float>(side) * 0.6f + 0.5f;
    const ShapeId wall = world.createShape(BoxDef{{half + 0.5f, half + 0.5f, 0.5f}});
    for (int axis = 0; axis < 3; ++axis)
        for (const float sign : {-1.0f, 1.0f}) {
            BodyDef def;
            def.type = BodyType::Static;
            def.shape = wall;
            def.material = elastic;
            Vec3 offset{};
            offset[axis] = sign * (half + 0.5f);
            def.position = offset;
            // The wall's thin axis is z: turn it onto the axis it closes.
            if (axis == 0) def.orientation = Quat::fromAxisAngle({0, 1, 0}, 1.5707964f);
            if (axis == 1) def.orientation = Quat::fromAxisAngle({1, 0, 0}, 1.5707964f);
            world.createBody(def);
        }
    const ShapeId ball = world.createShape(SphereDef{0.15f});
    std::mt19937 random(20);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    std::vector<BodyId> balls;
    for (int i = 0; i < side * side * side; ++i) {
        BodyDef def;
        def.shape = ball;
        def.material = elastic;
        const auto cell = [&](int k) { return 0.6f * (static_cast<float>(k) - 0.5f * static_cast<float>(side - 1)); };
        def.position = {cell(i % side), cell((i / side) % side), cell(i / (side * side))};
        Vec3 direction{unit(random), unit(random), unit(random)};
        def.linearVelocity = direction * (3.0f / std::max(rubble::length(direction), 1e-3f));
        balls.push_back(world.createBody(def));
    }
    const auto energy = [&] {
        double sum = 0;
        for (const BodyId id : balls) {
            const Vec3 v = world.linearVelocity(id);
            sum += 0.5 * static_cast<double>(world.massProperties(id).mass * dot(v, v));
        }
        return sum;
    };
    const double energy0 = energy();
    Measured out;
    stepTimed(world, stepsFor(length == Length::Full ? 4.0 : 1.0, sweep.timeStep), out);
    out.error = 100.0 * std::abs(energy() - energy0) / energy0;
    return out;
}

/// A case of the stability suite (scenes/hard/), run with the sweep's solver settings over its own gravity, effects
/// and sleep settings, for as long as its file says in seconds; the error is the first figure it declares.
Measured hardCase(const std::string& path, const WorldSettings& sweep, Length length) {
    Scene scene = loadScene(path);
    const double seconds =
        scene.steps * static_cast<double>(scene.settings.timeStep) * (length == Length::Full ? 1 : 0.25);
    WorldSettings settings = withSceneEffects(sweep, scene.settings.effects);
    settings.gravity = scene.settings.gravity;
    settings.sleep = scene.settings.sleep;
    scene.settings = settings;
    World world(settings);
    const std::vector<BodyId> ids = instantiate(scene, world);
    SceneFigureMeter figures(scene, world, ids);
    Measured out;
    stepTimed(world, stepsFor(seconds, settings.timeStep), out, [&](long) { figures.record(world); });
    const std::vector<SceneFigureMeter::Result> results = figures.results(world);
    if (results.empty()) throw Error(path + ": a hard case for the accuracy report must declare a figure");
    out.error = results[0].value;
    if (results.size() > 1) out.secondaryError = results[1].value;
    return out;
}

}  // namespace

std::vector<MeasurementScene> referenceScenes(const std::string& scenesDir) {
    using K = Knob;
    const std::vector<Knob> solver{K::TimeStep,           K::Substeps,     K::VelocityIterations, K::PositionIterations,
                                   K::PositionCorrection, K::WarmStarting, K::SeedRestingLoads,   K::ManifoldReuse};
    std::vector<Knob> structure = solver;
    structure.push_back(K::Threads);
    const std::vector<Knob> joints{K::TimeStep,           K::Substeps,           K::Integrator,  K::VelocityIterations,
                                   K::PositionIterations, K::PositionCorrection, K::WarmStarting};
    std::vector<MeasurementScene> scenes;
    scenes.push_back({"tower", "Tower of ten cubes, built touching",
                      "Eight towers of ten 1 m cubes on the ground, built touching, for 5 s (2 s in --quick); statics "
                      "says nothing moves.",
                      "largest displacement", "m", "deepest penetration at the end", "m", 0.01, structure, true,
                      tower});
    scenes.push_back({"pyramid_dropped", "Pyramid dropped row by row",
                      "Three pyramids of ten rows of 1 m cubes (55 each), every row created 3 cm above where it rests, "
                      "after 4 s (one pyramid for 2 s in --quick); statics puts every cube 3 cm per row below where it "
                      "started.",
                      "largest distance from rest", "m", "largest speed at the end", "m/s", 0.01, structure, true,
                      pyramidDropped});
    scenes.push_back({"chain", "Chain with a weight",
                      "Eight chains of twenty 8 cm balls ball-jointed 10 cm apart from a pin, a ball of 10 times a "
                      "link's mass at the end, released horizontally, for 3 s; a joint's anchors should coincide.",
                      "largest joint gap during the run", "m", "largest joint gap at the end", "m", 0.01, joints, true,
                      [](const WorldSettings& s, Length l) { return chainStretch(s, l, 10.0f); }});
    scenes.push_back({"chain_heavy", "Chain with a heavy ball (100:1)",
                      "The same chains with a ball of 100 times a link's mass: the links' small inertia against the "
                      "ball's weight is the hard case for an iterative joint solver.",
                      "largest joint gap during the run", "m", "largest joint gap at the end", "m", 0.01, joints, true,
                      [](const WorldSettings& s, Length l) { return chainStretch(s, l, 100.0f); }});
    scenes.push_back({"tunnelling",
                      "Spinning rods at thin walls",
                      "128 rods 2 m long spinning at 60-120 rad/s 0.3-0.9 m in front of 2 cm walls for 1 s (32 in "
                      "--quick); no tip may end a step beyond the wall's far face, through the face (a tip that swung "
                      "round the wall's edge did not pass it), the criterion of the solver's spinning-rod test.",
                      "rods whose tip ended a step beyond the wall",
                      "rods",
                      "the same, share",
                      "%",
                      0.5,
                      {K::ContinuousCollision, K::TimeStep, K::Substeps},
                      false,
                      spinningRods});
    scenes.push_back(
        {"gas",
         "Elastic gas in a box",
         "4,096 balls at 3 m/s in random directions in a closed box, restitution 1, no friction or gravity, "
         "for 4 s (1,000 balls for 1 s in --quick): kinetic energy is kept but for collisions slower than "
         "the 1 m/s bounce threshold. Broad-phase choice and thread count must not change the state.",
         "kinetic energy change",
         "%",
         "",
         "",
         1.0,
         {K::BroadPhase, K::Threads, K::TimeStep, K::Substeps, K::VelocityIterations},
         false,
         gas});

    const std::vector<Knob> hardKnobs{K::TimeStep,           K::Substeps,           K::VelocityIterations,
                                      K::PositionIterations, K::PositionCorrection, K::WarmStarting,
                                      K::SeedRestingLoads};
    struct HardCase {
        const char* file;
        const char* description;
        const char* errorName;
        const char* unit;
        double target;
    };
    // The suite's cases whose first figure is an error against statics or a conserved quantity (the dropped ones
    // report the drop in their displacement, and the large ones are measured by the runner instead).
    const HardCase cases[] = {
        {"arch", "An arch of 11 voussoirs held by friction and its own thrust, built touching.", "largest displacement",
         "m", 0.01},
        {"card_house", "Cards 2 cm thick leaning in pairs, two storeys, built touching.", "largest displacement", "m",
         0.01},
        {"far_pyramid", "A pyramid of ten rows of 1 m cubes 10 km from the origin (float spacing 1 mm there).",
         "largest displacement", "m", 0.01},
        {"overlap_recovery", "A pyramid of ten rows created with every cube 25% into its neighbours and the ground.",
         "largest speed of the push-out", "m/s", 1.0},
        {"container_overfilled", "125 cubes filling 116% of a closed box of static walls, overlapping.",
         "cubes that escaped", "cubes", 0.5},
        {"chain_heavy_ball",
         "20 capsule links from a pin and a ball of 100 times a link's mass, released horizontally.",
         "joint stretch at the end", "m", 0.01},
    };
    for (const HardCase& c : cases) {
        const std::string path = scenesDir + "/hard/" + c.file + ".json";
        const Scene scene = loadScene(path);  // refuses a missing or broken file before any run
        scenes.push_back({std::string("hard_") + c.file, "Hard case: " + scene.name,
                          std::string(c.description) + " (scenes/hard/" + c.file + ".json)", c.errorName, c.unit, "",
                          "", c.target, hardKnobs, false,
                          [path](const WorldSettings& s, Length l) { return hardCase(path, s, l); }});
    }
    return scenes;
}

}  // namespace rubble::accuracy
