// Joints at scale, whole steps through the World API at 1 and 2 threads: a hanging chain of 1,000 capsule links on
// ball joints, and a 71 x 71 cloth-like grid of spheres joined to their right and lower neighbours by 9,870 ball
// joints, hung from its top row. Counters: the whole step (step_ms), the joint solver's share of it (joint_ms, from
// Profile::jointMs: rows, warm start, iterations, break checks) and joint-iterations per second (joints x velocity
// iterations x substeps over the joint time). The chain's 1,000 joints run serially in store order (fewer than the
// 1,024 that joint_solver.h colours), so its joint_ms should not change with the thread count; the grid's run in
// colours across the threads, its ball joints in SIMD lanes, and should scale.
#include <benchmark/benchmark.h>

#include <memory>

#include "rubble/world.h"

namespace {

using namespace rubble;

constexpr float kDt = 1.0f / 60.0f;

std::unique_ptr<World> makeChain(int threads) {
    WorldSettings s;
    s.threads = threads;
    auto world = std::make_unique<World>(s);
    BodyDef def;
    def.type = BodyType::Static;
    def.shape = world->createShape(SphereDef{0.1f});
    def.position = {0, 600, 0};
    BodyId previous = world->createBody(def);
    Vec3 previousAnchor{};
    def.type = BodyType::Dynamic;
    def.shape = world->createShape(CapsuleDef{0.1f, 0.15f});
    for (int i = 0; i < 1000; ++i) {
        // Links along -y, each 0.5 m between its joints, released slightly slanted so that the chain swings.
        def.position = {0.02f * float(i), 600.0f - 0.25f - 0.5f * float(i), 0};
        const BodyId link = world->createBody(def);
        BallJointDef ball;
        ball.bodyA = previous;
        ball.bodyB = link;
        ball.localAnchorA = previousAnchor;
        ball.localAnchorB = {0, 0.25f, 0};
        world->createJoint(ball);
        previous = link;
        previousAnchor = {0, -0.25f, 0};
    }
    return world;
}

std::unique_ptr<World> makeCloth(int threads) {
    constexpr int kSide = 71;
    constexpr float kSpacing = 0.2f;
    WorldSettings s;
    s.threads = threads;
    auto world = std::make_unique<World>(s);
    BodyDef def;
    def.shape = world->createShape(SphereDef{0.05f});
    std::vector<BodyId> nodes;
    for (int row = 0; row < kSide; ++row)
        for (int col = 0; col < kSide; ++col) {
            // The top row is static: the cloth hangs from it, in the x-z plane tilted so it swings down.
            def.type = row == 0 ? BodyType::Static : BodyType::Dynamic;
            def.position = {kSpacing * float(col), 20.0f, kSpacing * float(row)};
            nodes.push_back(world->createBody(def));
        }
    for (int row = 0; row < kSide; ++row)
        for (int col = 0; col < kSide; ++col) {
            const BodyId node = nodes[std::size_t(row * kSide + col)];
            if (col + 1 < kSide && row > 0) {
                BallJointDef ball;
                ball.bodyA = node;
                ball.bodyB = nodes[std::size_t(row * kSide + col + 1)];
                ball.localAnchorA = {kSpacing / 2, 0, 0};
                ball.localAnchorB = {-kSpacing / 2, 0, 0};
                world->createJoint(ball);
            }
            if (row + 1 < kSide) {
                BallJointDef ball;
                ball.bodyA = node;
                ball.bodyB = nodes[std::size_t((row + 1) * kSide + col)];
                ball.localAnchorA = {0, 0, kSpacing / 2};
                ball.localAnchorB = {0, 0, -kSpacing / 2};
                world->createJoint(ball);
            }
        }
    return world;
}

/// Box3D's joint_grid (scenes/hard/hanging_sheet.json): 100 x 100 spheres of radius 0.4, 1 m apart in a vertical
/// sheet, ball-jointed to their neighbours at the midpoints (19,701 joints), the top row static, the spheres not
/// colliding with each other: joints only. Awake throughout, as in Box3D's harness: the sheet comes to rest.
std::unique_ptr<World> makeSheet(int threads) {
    constexpr int kSide = 100;
    WorldSettings s;
    s.threads = threads;
    s.effects = s.effects.without(Effect::Sleeping);
    auto world = std::make_unique<World>(s);
    BodyDef def;
    def.shape = world->createShape(SphereDef{0.4f});
    def.filter = {2u, ~2u};
    std::vector<BodyId> nodes;
    for (int row = 0; row < kSide; ++row)
        for (int col = 0; col < kSide; ++col) {
            def.type = row == 0 ? BodyType::Static : BodyType::Dynamic;
            def.position = {float(col), -float(row), 0};
            nodes.push_back(world->createBody(def));
        }
    const auto node = [&](int row, int col) { return nodes[std::size_t(row * kSide + col)]; };
    for (int row = 0; row < kSide; ++row)
        for (int col = 0; col < kSide; ++col) {
            BallJointDef ball;
            if (row > 0) {
                ball.bodyA = node(row - 1, col), ball.bodyB = node(row, col);
                ball.localAnchorA = {0, -0.5f, 0}, ball.localAnchorB = {0, 0.5f, 0};
                world->createJoint(ball);
            }
            if (col > 0 && row > 0) {
                ball.bodyA = node(row, col - 1), ball.bodyB = node(row, col);
                ball.localAnchorA = {0.5f, 0, 0}, ball.localAnchorB = {-0.5f, 0, 0};
                world->createJoint(ball);
            }
        }
    return world;
}

template <auto Make>
void jointStep(benchmark::State& state) {
    const int threads = static_cast<int>(state.range(0));
    auto world = Make(threads);
    for (int i = 0; i < 10; ++i) world->step(kDt);  // past the first steps' warm-up
    double jointMs = 0, stepMs = 0;
    std::uint64_t jointIterations = 0;
    for (auto _ : state) {
        world->step(kDt);
        const Profile& p = world->lastProfile();
        jointMs += p.jointMs;
        stepMs += p.stepMs;
        jointIterations += std::uint64_t{p.joints} * std::uint64_t(world->settings().velocityIterations) *
                           std::uint64_t(world->settings().substeps);
    }
    const double n = static_cast<double>(state.iterations());
    state.counters["joints"] = world->lastProfile().joints;
    state.counters["step_ms"] = stepMs / n;
    state.counters["joint_ms"] = jointMs / n;
    state.counters["joint_iterations_per_s"] = jointMs > 0 ? double(jointIterations) / (jointMs * 1e-3) : 0.0;
}

void chainStep(benchmark::State& state) { jointStep<makeChain>(state); }
void clothStep(benchmark::State& state) { jointStep<makeCloth>(state); }
void sheetStep(benchmark::State& state) { jointStep<makeSheet>(state); }

}  // namespace

// A fixed run of steps (the 11th to the 110th): the structures swing, whip and settle, and a step's cost follows, so
// runs of different lengths (the framework's choice) would average different parts of the motion.
constexpr int kTimedSteps = 100;
BENCHMARK(chainStep)->Arg(1)->Arg(2)->Iterations(kTimedSteps)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(clothStep)->Arg(1)->Arg(2)->Iterations(kTimedSteps)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(sheetStep)->Arg(1)->Arg(2)->Iterations(kTimedSteps)->Unit(benchmark::kMillisecond)->UseRealTime();
