#include "effect_costs.h"

#include <cmath>
#include <random>

#include "rubble/world.h"
#include "stepping.h"

namespace rubble::accuracy {
namespace {

/// Rain of boxes and balls (some bouncy) onto the ground, chains hanging from pins, and fast balls fired at the
/// ground: a scene in which each effect has something to do.
struct EffectScene {
    int bodies;  ///< boxes and balls of the rain
    int chains;
};

EffectRun runScene(const EffectScene& scene, EffectSet effects, int threads, long steps) {
    WorldSettings settings;
    settings.threads = threads;
    settings.effects = effects;
    World world(settings);
    addGround(world, 40.0f, 40.0f);
    const ShapeId box = world.createShape(BoxDef{{0.3f, 0.3f, 0.3f}});
    const ShapeId ball = world.createShape(SphereDef{0.3f});
    std::mt19937 random(7);
    std::uniform_real_distribution<float> jitter(-0.1f, 0.1f);
    // One layer, spread out: the bodies land within a second and then rest, so that sleeping has something to do.
    const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(scene.bodies))));
    const float spacing = 1.2f, offset = -0.5f * spacing * static_cast<float>(side - 1);
    for (int i = 0; i < scene.bodies; ++i) {
        BodyDef def;
        def.shape = i % 2 ? box : ball;
        def.position = {offset + spacing * static_cast<float>(i % side) + jitter(random),
                        1.0f + 5.0f * jitter(random) + 0.5f,
                        offset + spacing * static_cast<float>(i / side) + jitter(random)};
        def.orientation = Quat::fromAxisAngle({jitter(random), 1, jitter(random)}, jitter(random) * 5);
        if (i % 3 == 0) def.material.restitution = 0.5f;
        if (i % 50 == 0) def.linearVelocity = {0, -60.0f, 0};  // fast enough to need sweeping near the ground
        world.createBody(def);
    }
    const ShapeId link = world.createShape(SphereDef{0.1f});
    for (int c = 0; c < scene.chains; ++c) {
        BodyDef pin;
        pin.type = BodyType::Static;
        pin.shape = link;
        pin.position = {-20.0f + 1.0f * static_cast<float>(c), 6.0f, -30.0f};
        BodyId previous = world.createBody(pin);
        Vec3 previousCentre = pin.position;
        for (int k = 0; k < 10; ++k) {
            BodyDef def;
            def.shape = link;
            def.position = previousCentre + Vec3{0.25f, 0, 0};
            const BodyId body = world.createBody(def);
            BallJointDef j;
            j.bodyA = previous;
            j.bodyB = body;
            j.localAnchorA = {0.125f, 0, 0};
            j.localAnchorB = {-0.125f, 0, 0};
            world.createJoint(j);
            previous = body, previousCentre = def.position;
        }
    }
    EffectRun run;
    run.declared = effects;
    run.simulated = world.activeEffects();
    std::array<std::vector<double>, kStageCount> stageMs;
    std::vector<double> lastSeconds;
    Measured measured;
    stepTimed(world, steps, measured, [&](long s) {
        const Profile& p = world.lastProfile();
        if (s >= steps - 120) lastSeconds.push_back(p.stepMs);
        for (int k = 0; k < kStageCount; ++k)
            if (p.stages[static_cast<std::size_t>(k)].ran)
                stageMs[static_cast<std::size_t>(k)].push_back(p.stages[static_cast<std::size_t>(k)].ms);
    });
    run.msPerStep = measured.msPerStep;
    run.msPerStepAtEnd = median(std::move(lastSeconds));
    for (std::size_t k = 0; k < stageMs.size(); ++k) {
        run.stageRan[k] = !stageMs[k].empty();
        run.stageMs[k] = median(stageMs[k]);
    }
    run.sleepingAtEnd = world.lastProfile().sleepingBodies;
    return run;
}

}  // namespace

EffectCosts measureEffectCosts(int threads, Length length) {
    const EffectScene scene{length == Length::Full ? 2000 : 500, length == Length::Full ? 40 : 10};
    EffectCosts costs;
    costs.steps = length == Length::Full ? 600 : 180;
    costs.description = std::to_string(scene.bodies) +
                        " boxes and balls of 0.6 m (a third bouncy, one in fifty fired down at 60 m/s) dropped side by "
                        "side onto the ground, and " +
                        std::to_string(scene.chains) + " chains of ten balls ball-jointed to pins, for " +
                        std::to_string(costs.steps) + " steps of 1/60 s";
    costs.all = runScene(scene, EffectSet::all(), threads, costs.steps);
    for (int b = 0; b < kEffectCount; ++b) {
        const auto effect = static_cast<Effect>(1u << b);
        costs.without.emplace_back(effect, runScene(scene, EffectSet::all().without(effect), threads, costs.steps));
    }
    return costs;
}

}  // namespace rubble::accuracy
