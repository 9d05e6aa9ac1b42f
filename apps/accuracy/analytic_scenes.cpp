// Measurement scenes with closed-form answers: ballistic flight, a pendulum, a spring, rolling, sliding, a tumbling
// box, an elastic collision and bounces. Each builds its copies on a grid far enough apart never to touch.
#include <cmath>
#include <numbers>

#include "analytic_scenes.h"
#include "stepping.h"

namespace rubble::accuracy {
namespace {

constexpr double kG = 9.81;
constexpr double kPi = std::numbers::pi;

/// Where copy `i` of `count` stands: a square grid in x and z, `spacing` apart.
Vec3 gridSpot(int i, int count, float spacing) {
    const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count))));
    return {spacing * static_cast<float>(i % side), 0.0f, spacing * static_cast<float>(i / side)};
}

double distance(Vec3 a, Vec3 b) { return static_cast<double>(rubble::length(a - b)); }

/// Times at which a sampled signal crosses zero upwards, linearly interpolated between samples.
class UpwardCrossings {
public:
    void add(double t, double value) {
        if (started_ && last_ < 0 && value >= 0) times_.push_back(lastT_ + (t - lastT_) * (-last_) / (value - last_));
        started_ = true, last_ = value, lastT_ = t;
    }
    /// Mean period over the whole run; NaN when fewer than two crossings were seen.
    double period() const {
        if (times_.size() < 2) return std::nan("");
        return (times_.back() - times_.front()) / static_cast<double>(times_.size() - 1);
    }

private:
    std::vector<double> times_;
    bool started_ = false;
    double last_ = 0, lastT_ = 0;
};

/// Ballistic flight from `start` at `velocity` for `seconds`: the worst copy's distance from the closed form.
Measured ballistic(const WorldSettings& sweep, Length length, Vec3 velocity, double seconds) {
    World world(withSceneEffects(sweep, EffectSet{}.with(Effect::Gravity).with(Effect::Rotation)));
    const ShapeId ball = world.createShape(SphereDef{0.1f});
    const int copies = copiesFor(length, 256);
    std::vector<BodyId> bodies;
    std::vector<Vec3> starts;
    for (int i = 0; i < copies; ++i) {
        BodyDef def;
        def.shape = ball;
        def.position = gridSpot(i, copies, 1.0f) + Vec3{0, 100, 0};
        def.linearVelocity = velocity;
        bodies.push_back(world.createBody(def));
        starts.push_back(def.position);
    }
    Measured out;
    stepTimed(world, stepsFor(seconds, sweep.timeStep), out);
    const double t = static_cast<double>(out.steps) * static_cast<double>(sweep.timeStep);
    for (int i = 0; i < copies; ++i) {
        const Vec3 s = starts[static_cast<std::size_t>(i)];
        const Vec3 exact{static_cast<float>(s.x + velocity.x * t),
                         static_cast<float>(s.y + velocity.y * t - 0.5 * kG * t * t),
                         static_cast<float>(s.z + velocity.z * t)};
        out.error = std::max(out.error, distance(world.centerOfMass(bodies[static_cast<std::size_t>(i)]), exact));
    }
    return out;
}

/// Complete elliptic integral of the first kind K(k) by the arithmetic-geometric mean.
double ellipticK(double k) {
    double a = 1, b = std::sqrt(1 - k * k);
    for (int i = 0; i < 30 && std::abs(a - b) > 1e-16 * a; ++i) {
        const double m = 0.5 * (a + b);
        b = std::sqrt(a * b);
        a = m;
    }
    return kPi / (2 * a);
}

Measured pendulum(const WorldSettings& sweep, Length length) {
    // A ball of radius r hung by its anchor point L from its centre swings as a compound pendulum of equivalent
    // length (L^2 + 2/5 r^2) / L; at amplitude a its period is 4 sqrt(Leq / g) K(sin(a / 2)).
    constexpr float kRadius = 0.05f, kArm = 0.5f;
    const double amplitude = 30.0 * kPi / 180.0;
    const double equivalentLength = (kArm * kArm + 0.4 * kRadius * kRadius) / kArm;
    const double exactPeriod = 4 * std::sqrt(equivalentLength / kG) * ellipticK(std::sin(amplitude / 2));
    const int periods = length == Length::Full ? 100 : 10;

    World world(withSceneEffects(sweep, EffectSet{}.with(Effect::Gravity).with(Effect::Rotation).with(Effect::Joints)));
    const ShapeId ball = world.createShape(SphereDef{kRadius});
    const ShapeId pivotShape = world.createShape(SphereDef{0.01f});
    const int copies = copiesFor(length, 16);  // 100 periods are long: fewer copies than the other scenes
    std::vector<BodyId> bobs;
    std::vector<Vec3> pivots;
    for (int i = 0; i < copies; ++i) {
        const Vec3 pivot = gridSpot(i, copies, 1.5f) + Vec3{0, 2, 0};
        BodyDef pivotDef;
        pivotDef.type = BodyType::Static;
        pivotDef.shape = pivotShape;
        pivotDef.position = pivot;
        const BodyId fixed = world.createBody(pivotDef);
        BodyDef bobDef;
        bobDef.shape = ball;
        const Vec3 arm{static_cast<float>(std::sin(amplitude)), static_cast<float>(-std::cos(amplitude)), 0};
        bobDef.position = pivot + arm * kArm;
        const BodyId bob = world.createBody(bobDef);
        BallJointDef joint;
        joint.bodyA = fixed;
        joint.bodyB = bob;
        joint.localAnchorB = arm * -kArm;
        world.createJoint(joint);
        bobs.push_back(bob);
        pivots.push_back(pivot);
    }
    // Each copy's angle from the vertical, sampled every step: period from its upward zero crossings, amplitude from
    // its largest swing over the last period.
    std::vector<UpwardCrossings> crossings(static_cast<std::size_t>(copies));
    std::vector<double> lastSwing(static_cast<std::size_t>(copies), 0.0);
    const long steps = stepsFor(periods * exactPeriod, sweep.timeStep);
    const long lastPeriodFrom = steps - stepsFor(exactPeriod, sweep.timeStep);
    const double dt = sweep.timeStep;
    Measured out;
    stepTimed(world, steps, out, [&](long s) {
        for (std::size_t i = 0; i < bobs.size(); ++i) {
            const Vec3 d = world.centerOfMass(bobs[i]) - pivots[i];
            const double angle = std::atan2(static_cast<double>(d.x), -static_cast<double>(d.y));
            crossings[i].add(static_cast<double>(s + 1) * dt, angle);
            if (s >= lastPeriodFrom) lastSwing[i] = std::max(lastSwing[i], std::abs(angle));
        }
    });
    for (std::size_t i = 0; i < bobs.size(); ++i) {
        out.error = std::max(out.error, std::abs(lastSwing[i] - amplitude) * 180.0 / kPi);
        const double period = crossings[i].period();
        const double periodError = std::isnan(period) ? 100.0 : 100.0 * std::abs(period - exactPeriod) / exactPeriod;
        out.secondaryError = std::max(out.secondaryError, periodError);
    }
    return out;
}

Measured spring(const WorldSettings& sweep, Length length) {
    // A ball on an undamped spring, no gravity: x(t) = x0 cos(sqrt(k / m) t), energy k x0^2 / 2 for ever.
    constexpr float kRadius = 0.1f, kStiffness = 200.0f, kRest = 0.5f, kStretch = 0.1f;
    World world(withSceneEffects(sweep, EffectSet{}.with(Effect::Rotation).with(Effect::Joints)));
    const ShapeId ball = world.createShape(SphereDef{kRadius});
    const ShapeId pivotShape = world.createShape(SphereDef{0.01f});
    const int copies = copiesFor(length, 64);
    std::vector<BodyId> balls;
    std::vector<Vec3> pivots;
    for (int i = 0; i < copies; ++i) {
        const Vec3 pivot = gridSpot(i, copies, 2.0f);
        BodyDef pivotDef;
        pivotDef.type = BodyType::Static;
        pivotDef.shape = pivotShape;
        pivotDef.position = pivot;
        const BodyId fixed = world.createBody(pivotDef);
        BodyDef ballDef;
        ballDef.shape = ball;
        ballDef.position = pivot + Vec3{kRest + kStretch, 0, 0};
        const BodyId b = world.createBody(ballDef);
        SpringJointDef joint;
        joint.bodyA = fixed;
        joint.bodyB = b;
        joint.stiffness = kStiffness;
        joint.restLength = kRest;
        world.createJoint(joint);
        balls.push_back(b);
        pivots.push_back(pivot);
    }
    const double mass = world.massProperties(balls[0]).mass;
    const double exactPeriod = 2 * kPi * std::sqrt(mass / kStiffness);
    const double energy0 = 0.5 * kStiffness * kStretch * kStretch;
    const int periods = length == Length::Full ? 20 : 5;
    std::vector<UpwardCrossings> crossings(static_cast<std::size_t>(copies));
    const double dt = sweep.timeStep;
    Measured out;
    stepTimed(world, stepsFor(periods * exactPeriod, sweep.timeStep), out, [&](long s) {
        for (std::size_t i = 0; i < balls.size(); ++i)
            crossings[i].add(static_cast<double>(s + 1) * dt,
                             distance(world.centerOfMass(balls[i]), pivots[i]) - static_cast<double>(kRest));
    });
    for (std::size_t i = 0; i < balls.size(); ++i) {
        const double x = distance(world.centerOfMass(balls[i]), pivots[i]) - kRest;
        const Vec3 v = world.linearVelocity(balls[i]);
        const double energy = 0.5 * mass * static_cast<double>(dot(v, v)) + 0.5 * kStiffness * x * x;
        out.error = std::max(out.error, 100.0 * std::abs(energy - energy0) / energy0);
        const double period = crossings[i].period();
        const double periodError = std::isnan(period) ? 100.0 : 100.0 * std::abs(period - exactPeriod) / exactPeriod;
        out.secondaryError = std::max(out.secondaryError, periodError);
    }
    return out;
}

Measured incline(const WorldSettings& sweep, Length length) {
    // A solid ball rolling without slipping down a slope of angle a accelerates at 5/7 g sin a (friction 0.6 is well
    // above the 2/7 tan a that rolling needs). The ramp is one static box; the balls start on it, touching, at rest.
    const double slope = 20.0 * kPi / 180.0;
    constexpr float kRadius = 0.1f;
    constexpr double kSeconds = 1.0;
    const int copies = copiesFor(length, 64);
    World world(
        withSceneEffects(sweep, EffectSet{}.with(Effect::Gravity).with(Effect::Rotation).with(Effect::Friction)));
    const float width = 0.5f * static_cast<float>(copies) + 1.0f;
    const Quat tilt = Quat::fromAxisAngle({0, 0, 1}, static_cast<float>(-slope));  // downhill towards +x
    BodyDef rampDef;
    rampDef.type = BodyType::Static;
    rampDef.shape = world.createShape(BoxDef{{10.0f, 0.5f, width}});
    rampDef.orientation = tilt;
    const BodyId ramp = world.createBody(rampDef);
    (void)ramp;
    const Vec3 normal = rotate(tilt, {0, 1, 0}), downhill = rotate(tilt, {1, 0, 0});
    const ShapeId ball = world.createShape(SphereDef{kRadius});
    std::vector<BodyId> balls;
    std::vector<Vec3> starts;
    for (int i = 0; i < copies; ++i) {
        BodyDef def;
        def.shape = ball;
        const Vec3 onSurface = normal * 0.5f + downhill * -6.0f + Vec3{0, 0, 0.5f * static_cast<float>(i) - width + 1};
        def.position = onSurface + normal * kRadius;
        balls.push_back(world.createBody(def));
        starts.push_back(def.position);
    }
    Measured out;
    stepTimed(world, stepsFor(kSeconds, sweep.timeStep), out);
    const double t = static_cast<double>(out.steps) * static_cast<double>(sweep.timeStep);
    const double exact = 0.5 * (5.0 / 7.0) * kG * std::sin(slope) * t * t;
    for (std::size_t i = 0; i < balls.size(); ++i) {
        const Vec3 moved = world.centerOfMass(balls[i]) - starts[i];
        out.error = std::max(out.error, std::abs(static_cast<double>(dot(moved, downhill)) - exact));
        // How far the ball left the surface's line (sinking into it or hopping off).
        out.secondaryError = std::max(out.secondaryError, std::abs(static_cast<double>(dot(moved, normal))));
    }
    return out;
}

Measured slidingBlock(const WorldSettings& sweep, Length length) {
    // A cube sliding at v0 on flat ground with friction mu stops after v0^2 / (2 mu g) (mu = 0.5 on both sides; the
    // engine combines them by their geometric mean). A cube cannot tip at mu < 1.
    constexpr float kHalf = 0.25f, kSpeed = 5.0f, kFriction = 0.5f;
    const int copies = copiesFor(length, 64);
    World world(
        withSceneEffects(sweep, EffectSet{}.with(Effect::Gravity).with(Effect::Rotation).with(Effect::Friction)));
    const float width = static_cast<float>(copies) + 1.0f;
    Material material;
    material.friction = kFriction;
    addGround(world, 10.0f, width, material);
    const ShapeId cube = world.createShape(BoxDef{{kHalf, kHalf, kHalf}});
    std::vector<BodyId> blocks;
    std::vector<Vec3> starts;
    for (int i = 0; i < copies; ++i) {
        BodyDef def;
        def.shape = cube;
        def.position = {-5.0f, kHalf, static_cast<float>(i) - width + 1};
        def.linearVelocity = {kSpeed, 0, 0};
        def.material = material;
        blocks.push_back(world.createBody(def));
        starts.push_back(def.position);
    }
    Measured out;
    stepTimed(world, stepsFor(1.5, sweep.timeStep), out);  // it stops after v0 / (mu g) = 1.02 s
    const double exact = static_cast<double>(kSpeed * kSpeed) / (2 * kFriction * kG);
    for (std::size_t i = 0; i < blocks.size(); ++i) {
        const double slid = static_cast<double>(world.centerOfMass(blocks[i]).x - starts[i].x);
        out.error = std::max(out.error, std::abs(slid - exact));
        out.secondaryError =
            std::max(out.secondaryError, static_cast<double>(rubble::length(world.linearVelocity(blocks[i]))));
    }
    return out;
}

/// Inertia tensor in the world frame: R I R^T, from the body-frame tensor and the orientation.
Mat3 worldInertia(const Mat3& body, Quat q) {
    Mat3 r;
    for (int c = 0; c < 3; ++c) {
        Vec3 e{};
        e[c] = 1;
        const Vec3 col = rotate(q, e);
        r(0, c) = col.x, r(1, c) = col.y, r(2, c) = col.z;
    }
    Mat3 out = Mat3::zero();
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double sum = 0;
            for (int k = 0; k < 3; ++k)
                for (int l = 0; l < 3; ++l)
                    sum +=
                        static_cast<double>(r(i, k)) * static_cast<double>(body(k, l)) * static_cast<double>(r(j, l));
            out(i, j) = static_cast<float>(sum);
        }
    return out;
}

Measured tumblingBox(const WorldSettings& sweep, Length length) {
    // Torque-free motion keeps the kinetic energy and the angular momentum exactly. Spun about its intermediate
    // axis (y, the unstable one) with a small disturbance, the box flips over and back every few seconds (the
    // Dzhanibekov effect), which is the hard case for an integrator.
    const int copies = copiesFor(length, 64);
    World world(withSceneEffects(sweep, EffectSet{}.with(Effect::Rotation)));
    const ShapeId box = world.createShape(BoxDef{{0.05f, 0.15f, 0.25f}});
    const Vec3 spin{0.02f, 5.0f, 0.02f};
    std::vector<BodyId> boxes;
    for (int i = 0; i < copies; ++i) {
        BodyDef def;
        def.shape = box;
        def.position = gridSpot(i, copies, 1.0f);
        def.angularVelocity = spin;
        boxes.push_back(world.createBody(def));
    }
    const Mat3 inertia = world.massProperties(boxes[0]).inertia;
    const auto energyAndMomentum = [&](BodyId id) {
        const Vec3 w = world.angularVelocity(id);
        const Vec3 l = worldInertia(inertia, world.orientation(id)) * w;
        return std::pair{0.5 * static_cast<double>(dot(w, l)), static_cast<double>(rubble::length(l))};
    };
    const auto [energy0, momentum0] = energyAndMomentum(boxes[0]);
    Measured out;
    stepTimed(world, stepsFor(length == Length::Full ? 10.0 : 4.0, sweep.timeStep), out);
    for (const BodyId id : boxes) {
        const auto [energy, momentum] = energyAndMomentum(id);
        out.error = std::max(out.error, 100.0 * std::abs(energy - energy0) / energy0);
        out.secondaryError = std::max(out.secondaryError, 100.0 * std::abs(momentum - momentum0) / momentum0);
    }
    return out;
}

Measured elasticSwap(const WorldSettings& sweep, Length length) {
    // Two equal balls, restitution 1, no friction or gravity: the moving one stops and the other leaves at its speed.
    constexpr float kRadius = 0.1f, kSpeed = 2.0f;
    const int copies = copiesFor(length, 128);
    World world(withSceneEffects(sweep, EffectSet{}.with(Effect::Rotation).with(Effect::Restitution)));
    const ShapeId ball = world.createShape(SphereDef{kRadius});
    Material elastic;
    elastic.friction = 0;
    elastic.restitution = 1;
    std::vector<std::pair<BodyId, BodyId>> pairs;
    for (int i = 0; i < copies; ++i) {
        BodyDef def;
        def.shape = ball;
        def.material = elastic;
        def.position = gridSpot(i, copies, 2.0f);
        def.linearVelocity = {kSpeed, 0, 0};
        const BodyId striker = world.createBody(def);
        def.position += Vec3{0.6f, 0, 0};
        def.linearVelocity = {};
        pairs.emplace_back(striker, world.createBody(def));
    }
    Measured out;
    stepTimed(world, stepsFor(0.5, sweep.timeStep), out);  // they meet after 0.2 s
    for (const auto& [striker, struck] : pairs) {
        const double left = static_cast<double>(rubble::length(world.linearVelocity(striker)));
        const double gone = static_cast<double>(rubble::length(world.linearVelocity(struck) - Vec3{kSpeed, 0, 0}));
        out.error = std::max({out.error, left, gone});
        // Momentum is kept whatever the solver does with the bounce: what is not is the solver's own fault.
        const Vec3 p = world.linearVelocity(striker) + world.linearVelocity(struck) - Vec3{kSpeed, 0, 0};
        out.secondaryError = std::max(out.secondaryError, static_cast<double>(rubble::length(p)));
    }
    return out;
}

Measured bounces(const WorldSettings& sweep, Length length) {
    // A ball dropped from h0 onto the ground with restitution e rises to e^(2k) h0 after its k-th bounce (while the
    // impact speed stays above the 1 m/s below which contacts do not bounce: the third lands at 2.3 m/s).
    constexpr float kRadius = 0.1f, kRestitution = 0.8f, kDrop = 1.0f;
    const int copies = copiesFor(length, 64);
    World world(
        withSceneEffects(sweep, EffectSet{}.with(Effect::Gravity).with(Effect::Rotation).with(Effect::Restitution)));
    Material bouncy;
    bouncy.friction = 0;
    bouncy.restitution = kRestitution;
    addGround(world, 20.0f, 20.0f, bouncy);
    const ShapeId ball = world.createShape(SphereDef{kRadius});
    std::vector<BodyId> balls;
    for (int i = 0; i < copies; ++i) {
        BodyDef def;
        def.shape = ball;
        def.material = bouncy;
        def.position = gridSpot(i, copies, 0.5f) + Vec3{-15.0f, kDrop + kRadius, -15.0f};
        balls.push_back(world.createBody(def));
    }
    constexpr int kBounces = 3;
    std::vector<std::vector<double>> apexes(balls.size());
    std::vector<double> previous(balls.size(), kDrop), rising(balls.size(), 0);
    Measured out;
    stepTimed(world, stepsFor(2.5, sweep.timeStep), out, [&](long) {
        for (std::size_t i = 0; i < balls.size(); ++i) {
            const double height = static_cast<double>(world.centerOfMass(balls[i]).y - kRadius);
            if (rising[i] > 0 && height < previous[i]) apexes[i].push_back(previous[i]);  // just passed the top
            rising[i] = height > previous[i] ? 1 : 0;
            previous[i] = height;
        }
    });
    for (std::size_t i = 0; i < balls.size(); ++i) {
        double expected = kDrop;
        for (int k = 0; k < kBounces; ++k) {
            expected *= static_cast<double>(kRestitution * kRestitution);
            const double seen = k < static_cast<int>(apexes[i].size()) ? apexes[i][static_cast<std::size_t>(k)] : 0.0;
            out.error = std::max(out.error, std::abs(seen - expected));
        }
    }
    return out;
}

}  // namespace

std::vector<MeasurementScene> analyticScenes() {
    using K = Knob;
    const std::vector<Knob> motion{K::TimeStep, K::Substeps, K::Integrator};
    const std::vector<Knob> joints{K::TimeStep,           K::Substeps,           K::Integrator,  K::VelocityIterations,
                                   K::PositionIterations, K::PositionCorrection, K::WarmStarting};
    const std::vector<Knob> contacts{K::TimeStep,           K::Substeps,           K::Integrator,
                                     K::VelocityIterations, K::PositionIterations, K::PositionCorrection,
                                     K::WarmStarting,       K::ManifoldReuse};
    std::vector<MeasurementScene> scenes;
    scenes.push_back({"free_fall", "Free fall", "Balls dropped from rest fall for 2 s; compared with y0 - g t^2 / 2.",
                      "position error after 2 s", "m", "", "", 1e-3, motion, true,
                      [](const WorldSettings& s, Length l) { return ballistic(s, l, {}, 2.0); }});
    scenes.push_back(
        {"projectile", "Projectile", "Balls thrown at 10 m/s, 45 degrees up, fly for 2 s; compared with the parabola.",
         "position error after 2 s", "m", "", "", 1e-3, motion, false, [](const WorldSettings& s, Length l) {
             return ballistic(s, l, {7.0710678f, 7.0710678f, 0}, 2.0);
         }});
    scenes.push_back({"pendulum", "Pendulum",
                      "A 5 cm ball hung by a ball joint 0.5 m from its centre, released at 30 degrees, swings for 100 "
                      "periods (10 in --quick); compared with the exact large-amplitude period of the compound "
                      "pendulum (elliptic integral) and its constant amplitude.",
                      "amplitude lost over the run", "deg", "period error", "%", 1.0, joints, true, pendulum});
    scenes.push_back(
        {"spring", "Spring",
         "A ball on an undamped spring joint (k = 200 N/m), stretched 10 cm, no gravity, for 20 periods "
         "(5 in --quick); compared with energy k x0^2 / 2 and period 2 pi sqrt(m / k). The spring is a soft "
         "constraint of the solver, integrated implicitly whatever the integrator.",
         "energy lost", "%", "period error", "%", 1.0, motion, true, spring});
    scenes.push_back({"incline", "Ball rolling down an incline",
                      "Balls of 10 cm roll from rest down a 20-degree static ramp for 1 s; compared with s = 5/14 g "
                      "sin(a) t^2.",
                      "distance error after 1 s", "m", "distance off the surface line", "m", 0.01, contacts, true,
                      incline});
    scenes.push_back(
        {"sliding_block", "Sliding block",
         "Cubes of 0.5 m slide on the ground at 5 m/s with friction 0.5; compared with the stopping distance "
         "v0^2 / (2 mu g).",
         "stopping distance error", "m", "speed left after 1.5 s", "m/s", 0.01, contacts, true, slidingBlock});
    scenes.push_back({"tumbling_box", "Box tumbling about its intermediate axis",
                      "A 0.1 x 0.3 x 0.5 m box spun at 5 rad/s about its middle axis with a small disturbance, no "
                      "gravity, for 10 s (4 in --quick): it flips over and back. Torque-free motion keeps energy and "
                      "|L|.",
                      "kinetic energy drift", "%", "angular momentum drift", "%", 1.0, motion, true, tumblingBox});
    scenes.push_back({"elastic_swap", "Head-on elastic collision",
                      "A ball at 2 m/s hits an equal ball at rest, restitution 1, no friction or gravity: it should "
                      "stop and the other leave at 2 m/s.",
                      "velocity error after the swap", "m/s", "momentum error (per unit mass)", "m/s", 0.01, contacts,
                      false, elasticSwap});
    scenes.push_back({"bounce", "Bounce heights",
                      "A ball dropped from 1 m onto the ground, restitution 0.8, no friction: its first three apexes "
                      "compared with 0.8^(2k) m.",
                      "apex height error", "m", "", "", 0.01, contacts, false, bounces});
    return scenes;
}

}  // namespace rubble::accuracy
