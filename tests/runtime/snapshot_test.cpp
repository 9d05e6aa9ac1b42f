// Snapshots: the lock-free buffers never hand the reader a torn or overwritten snapshot, under a writer that never
// waits; interpolation gives the two snapshots at alpha 0 and 1, the midpoint at 0.5 and the shortest arc; the
// snapshots the runtime publishes match the world's own poses.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <atomic>
#include <chrono>
#include <cmath>
#include <random>
#include <string>
#include <thread>

#include "rubble/runtime.h"
#include "runtime/runtime_fixture.h"
#include "runtime/snapshot_buffer.h"

using namespace rubble;

namespace {

/// Every value of the snapshot encodes its step (exact in float below 2^24).
void fillWithStep(Snapshot& s, std::uint64_t step, std::size_t slots) {
    s.step = step;
    s.time = static_cast<double>(step);
    s.generation.assign(slots, static_cast<std::uint32_t>(step));
    const float v = static_cast<float>(step);
    for (auto* a : {&s.px, &s.py, &s.pz, &s.qx, &s.qy, &s.qz, &s.qw}) a->assign(slots, v);
}

/// Empty string when every value of `s` says `s.step`.
std::string mixedValues(const Snapshot& s) {
    const float v = static_cast<float>(s.step);
    for (std::size_t i = 0; i < s.generation.size(); ++i) {
        if (s.generation[i] != s.step) return "generation at " + std::to_string(i);
        for (const auto* a : {&s.px, &s.py, &s.pz, &s.qx, &s.qy, &s.qz, &s.qw})
            if ((*a)[i] != v) return "pose value at " + std::to_string(i);
    }
    return {};
}

}  // namespace

TEST(SnapshotBuffers, ReaderNeverSeesATornOrOverwrittenPair) {
    constexpr std::uint64_t kReads = 2000, kLaps = 50;
    constexpr std::size_t kSlots = 64;
    detail::SnapshotBuffers buffers;
    // The writer publishes as fast as it can until the reader is done, then stops. The reader is done after kReads
    // reads once the writer has lapped it kLaps times (published twice or more while it held a pair), or after 1.5 s
    // on a machine too busy to run both threads much.
    std::atomic<bool> readerDone{false};
    std::atomic<std::uint64_t> lastStep{0};
    std::thread writer([&] {
        std::uint64_t step = 0;
        while (!readerDone.load(std::memory_order_relaxed)) {
            const int b = buffers.beginWrite();
            fillWithStep(buffers.buffer(b), ++step, kSlots);
            buffers.publish(b);
        }
        lastStep.store(step);
    });
    std::mt19937 rng(11);
    std::uint64_t lastNewer = 0, reads = 0, laps = 0;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(1500);
    std::string problem;  // the first one; the loop then stops the writer rather than leave it running
    while (problem.empty()) {
        const Snapshot* older = nullptr;
        const Snapshot* newer = nullptr;
        if (!buffers.acquire(older, newer)) continue;
        ++reads;
        // Read the pair for a while (sometimes long enough for the writer to lap the reader several times): the
        // values must not change under us.
        const int passes = rng() % 16 == 0 ? 100 : 1 + static_cast<int>(rng() % 4);
        for (int p = 0; p < passes && problem.empty(); ++p) {
            if (const std::string m = mixedValues(*newer); !m.empty())
                problem = "newer snapshot of step " + std::to_string(newer->step) + ": " + m;
            if (const std::string m = mixedValues(*older); !m.empty())
                problem = "older snapshot of step " + std::to_string(older->step) + ": " + m;
        }
        if (newer->step < lastNewer) problem = "went back from step " + std::to_string(lastNewer);
        // A pair is two consecutive steps (one snapshot twice only before the second publish).
        if (older->step + 1 != newer->step && !(older == newer && newer->step == 1))
            problem = "pair of steps " + std::to_string(older->step) + " and " + std::to_string(newer->step);
        laps += newer->step > lastNewer + 1;
        lastNewer = newer->step;
        if ((reads >= kReads && laps >= kLaps) || std::chrono::steady_clock::now() > deadline) readerDone.store(true);
        if (readerDone.load() && lastStep.load() != 0 && newer->step == lastStep.load()) break;
    }
    readerDone.store(true);
    writer.join();
    EXPECT_EQ(problem, "");
    // The two threads did overlap: the writer published twice or more while the reader held a pair, many times (so
    // it had to write around the held pair).
    EXPECT_GT(laps, 10u) << "reads " << reads;
}

TEST(SnapshotBuffers, AHeldPairSurvivesAnyNumberOfPublishes) {
    // Deterministic interleavings: the reader takes a pair, the writer publishes k more times, the pair must be intact
    // and the next acquire must give the two newest, for every k (k >= 3 is where a four-buffer scheme runs out).
    for (int k = 0; k < 8; ++k) {
        detail::SnapshotBuffers buffers;
        std::uint64_t step = 0;
        auto publish = [&] {
            const int b = buffers.beginWrite();
            fillWithStep(buffers.buffer(b), ++step, 8);
            buffers.publish(b);
        };
        publish();
        publish();
        const Snapshot *older = nullptr, *newer = nullptr;
        ASSERT_TRUE(buffers.acquire(older, newer));
        ASSERT_EQ(newer->step, 2u);
        for (int i = 0; i < k; ++i) publish();
        EXPECT_EQ(older->step, 1u);
        EXPECT_EQ(newer->step, 2u);
        EXPECT_EQ(mixedValues(*older), "");
        EXPECT_EQ(mixedValues(*newer), "");
        ASSERT_TRUE(buffers.acquire(older, newer));
        EXPECT_EQ(newer->step, step) << "k = " << k;
        EXPECT_EQ(older->step, k == 0 ? 1u : step - 1) << "k = " << k;
    }
}

namespace {

Snapshot twoBodies(std::uint64_t step, Vec3 p0, Quat q0, Vec3 p1, Quat q1, std::uint32_t gen1) {
    Snapshot s;
    s.step = step;
    s.time = static_cast<double>(step) / 60.0;
    s.generation = {1, gen1};
    s.px = {p0.x, p1.x}, s.py = {p0.y, p1.y}, s.pz = {p0.z, p1.z};
    s.qx = {q0.x, q1.x}, s.qy = {q0.y, q1.y}, s.qz = {q0.z, q1.z}, s.qw = {q0.w, q1.w};
    s.shape = {0, 0};
    s.flags = {0, 0};
    return s;
}

Quat axisAngle(Vec3 axis, float angle) {
    const float s = std::sin(angle / 2) / length(axis);
    return {axis.x * s, axis.y * s, axis.z * s, std::cos(angle / 2)};
}

}  // namespace

TEST(Interpolation, EndsMidpointAndShortestArc) {
    const Quat qa = axisAngle({0, 1, 0}, 0.2f), qb = axisAngle({0, 1, 0}, 0.6f);
    // The newer orientation is stored as -qb (the same rotation, other hemisphere): blending must take the short
    // way from 0.2 to 0.6 rad, not the long way round through -qb.
    const Quat minusQb{-qb.x, -qb.y, -qb.z, -qb.w};
    const Snapshot older = twoBodies(10, {1, 2, 3}, qa, {0, 0, 0}, Quat{}, 1);
    const Snapshot newer = twoBodies(11, {3, 6, -1}, minusQb, {5, 5, 5}, qb, 2);  // body 1 was replaced
    RenderFrame frame;

    interpolateSnapshots(older, newer, 0.0f, frame);
    EXPECT_EQ(frame.px[0], 1.0f);
    EXPECT_EQ(frame.py[0], 2.0f);
    EXPECT_EQ(frame.pz[0], 3.0f);
    // Rotations compare up to sign; the 1e-6 is the rounding of the renormalisation.
    EXPECT_NEAR(std::fabs(frame.qy[0]), qa.y, 1e-6f);
    EXPECT_NEAR(std::fabs(frame.qw[0]), qa.w, 1e-6f);
    EXPECT_EQ(frame.px[1], 5.0f) << "a body new in the newer snapshot takes its newer pose at any alpha";
    EXPECT_EQ(frame.step, 11u);
    EXPECT_EQ(frame.olderStep, 10u);

    interpolateSnapshots(older, newer, 1.0f, frame);
    EXPECT_EQ(frame.px[0], 3.0f);
    EXPECT_EQ(frame.py[0], 6.0f);
    EXPECT_EQ(frame.pz[0], -1.0f);
    EXPECT_EQ(frame.qy[0], minusQb.y);
    EXPECT_EQ(frame.qw[0], minusQb.w);

    interpolateSnapshots(older, newer, 0.5f, frame);
    EXPECT_FLOAT_EQ(frame.px[0], 2.0f);
    EXPECT_FLOAT_EQ(frame.py[0], 4.0f);
    EXPECT_FLOAT_EQ(frame.pz[0], 1.0f);
    // At 0.5 the normalised lerp is exactly the slerp midpoint: a rotation of 0.4 rad about y (Eigen's slerp as the
    // reference). The long way round would give 0.4 + pi.
    const Eigen::Quaternionf ea(qa.w, qa.x, qa.y, qa.z), eb(qb.w, qb.x, qb.y, qb.z);
    const Eigen::Quaternionf mid = ea.slerp(0.5f, eb);
    const float sign = frame.qw[0] * mid.w() < 0 ? -1.0f : 1.0f;
    EXPECT_NEAR(sign * frame.qx[0], mid.x(), 1e-6f);
    EXPECT_NEAR(sign * frame.qy[0], mid.y(), 1e-6f);
    EXPECT_NEAR(sign * frame.qz[0], mid.z(), 1e-6f);
    EXPECT_NEAR(sign * frame.qw[0], mid.w(), 1e-6f);
    EXPECT_NEAR(2 * std::acos(std::fabs(frame.qw[0])), 0.4f, 1e-5f);
    EXPECT_NEAR(frame.time, (older.time + newer.time) / 2, 1e-12);
}

TEST(Interpolation, AllocatesNothingOnceTheSlotCountSettles) {
    const Snapshot older = twoBodies(1, {0, 0, 0}, Quat{}, {1, 1, 1}, Quat{}, 1);
    const Snapshot newer = twoBodies(2, {1, 0, 0}, Quat{}, {1, 2, 1}, Quat{}, 1);
    RenderFrame frame;
    interpolateSnapshots(older, newer, 0.3f, frame);
    const float* px = frame.px.data();
    const float* qw = frame.qw.data();
    const std::uint32_t* gen = frame.generation.data();
    for (int i = 0; i < 100; ++i) interpolateSnapshots(older, newer, static_cast<float>(i) / 100.0f, frame);
    EXPECT_EQ(frame.px.data(), px);
    EXPECT_EQ(frame.qw.data(), qw);
    EXPECT_EQ(frame.generation.data(), gen);
}

TEST(RuntimeSnapshots, MatchTheWorldsPosesAndFollowBodiesComingAndGoing) {
    RuntimeSettings settings;
    settings.rate = 60;
    Runtime runtime(test::boxesOnFloor(2, 1), settings);
    EXPECT_EQ(runtime.latest(1.0f).slotCount(), 0u);  // nothing published yet
    runtime.advance(2.0 / 60.0);
    const RenderFrame& frame = runtime.latest(1.0f);
    World& world = runtime.world();
    ASSERT_EQ(frame.step, world.stepCount());
    ASSERT_EQ(frame.bodyCount, world.bodyCount());
    for (BodyId id : world.bodies()) {
        const Transform t = world.transform(id);
        EXPECT_EQ(frame.generation[id.index], id.generation);
        EXPECT_EQ(frame.px[id.index], t.position.x);
        EXPECT_EQ(frame.py[id.index], t.position.y);
        EXPECT_EQ(frame.pz[id.index], t.position.z);
        EXPECT_EQ(frame.qw[id.index], t.rotation.w);
        EXPECT_EQ(frame.shape[id.index], world.bodyShape(id).index);
        EXPECT_EQ((frame.flags[id.index] & kSnapshotStatic) != 0, world.bodyType(id) == BodyType::Static);
    }
    // Remove one body and spawn another into its slot: the new body has another generation, so at alpha 0 it shows
    // its own (newer) pose, not a blend with the body that had the slot before.
    const BodyId removed = world.bodies()[2];
    runtime.submit(RemoveBodyCommand{removed});
    runtime.singleStep();
    BodyDef def;
    def.shape = world.bodyShape(world.bodies()[1]);
    def.position = {7, 8, 9};
    auto spawned = runtime.spawn(def);
    runtime.singleStep();
    const BodyId id = spawned.get();
    ASSERT_EQ(id.index, removed.index);
    const RenderFrame& next = runtime.latest(0.0f);
    EXPECT_EQ(next.generation[id.index], id.generation);
    EXPECT_NEAR(next.py[id.index], 8.0f, 0.01f);  // one step of free fall from rest moves it by g dt^2 = 3 mm
    EXPECT_EQ(next.bodyCount, world.bodyCount());
}

TEST(RuntimeSnapshots, AlphaFromTheClockIsTheTimePastTheNewerStep) {
    RuntimeSettings settings;
    settings.rate = 60;
    Runtime runtime(test::boxesOnFloor(1, 1), settings);
    const double dt = 1.0 / 60.0;
    runtime.advance(2.5 * dt);  // steps due at dt and 2 dt ran; the clock is half a step past the newer one
    EXPECT_DOUBLE_EQ(runtime.clockTime(), 2.5 * dt);
    const RenderFrame& frame = runtime.interpolate();
    EXPECT_EQ(frame.step, 2u);
    EXPECT_EQ(frame.olderStep, 1u);
    EXPECT_NEAR(frame.alpha, 0.5f, 1e-6f);  // the clock counts whole nanoseconds
    EXPECT_NEAR(frame.time, 1.5 * dt, 1e-9);
    EXPECT_EQ(runtime.interpolate(10 * dt).alpha, 1.0f);  // never extrapolates
    EXPECT_EQ(runtime.interpolate(0).alpha, 0.0f);
}
