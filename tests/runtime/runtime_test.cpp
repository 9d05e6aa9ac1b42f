// The runtime on a real thread: the physics rate holds while the render thread stalls, inputs recorded on a live run
// replay to the same state hash, spawns and ray casts answer through futures, and control (pause, single step,
// stop, destruction while running) behaves.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "rubble/error.h"
#include "rubble/runtime.h"
#include "runtime/runtime_fixture.h"
#include "support/error_of.h"

using namespace rubble;
using namespace std::chrono_literals;

TEST(Runtime, PhysicsKeepsItsRateWhileTheRenderThreadStalls) {
    RuntimeSettings settings;
    settings.rate = 120;
    Runtime runtime(test::boxesOnFloor(4, 2), settings);
    runtime.start();
    // Render normally for a moment, then stall for 200 ms holding the frame we were drawing.
    for (int i = 0; i < 10; ++i) {
        runtime.interpolate();
        std::this_thread::sleep_for(5ms);
    }
    const RenderFrame& before = runtime.latest(1.0f);
    const std::uint64_t stepBefore = before.step;
    const std::uint64_t stepsBefore = runtime.stats().steps;
    const auto stallBegin = std::chrono::steady_clock::now();
    std::this_thread::sleep_for(200ms);
    const double stall = std::chrono::duration<double>(std::chrono::steady_clock::now() - stallBegin).count();
    const std::uint64_t stepsDuring = runtime.stats().steps - stepsBefore;
    // The physics thread counts a step before it publishes the step's frame: the frame read at once may be one step
    // behind the count (ASan's slowdown made that happen in CI). Once stopped, every counted step is published.
    runtime.stop();
    const RenderFrame& after = runtime.latest(1.0f);

    const double expected = stall * settings.rate;  // 24 steps for exactly 200 ms
    // The CI machine has two cores shared with other jobs, so the physics thread may be descheduled for a while:
    // at least half the steps must have run. More than expected can only come from catching up on time that was due
    // before the stall began (at most one wake-up's cap) plus the step in flight.
    EXPECT_GE(static_cast<double>(stepsDuring), 0.5 * expected) << "stall " << stall << " s";
    EXPECT_LE(static_cast<double>(stepsDuring), expected + settings.maxStepsPerWake + 1);
    EXPECT_GE(after.step, stepBefore + stepsDuring);  // the render side sees the steps made during the stall
    EXPECT_EQ(after.bodyCount, 33u);
}

namespace {

/// Plays a little game against a running runtime from a producer thread: impulses, a spawn whose handle comes back
/// through the future and is then pushed and removed, velocity and transform changes, a ray cast.
void playInputs(Runtime& runtime, const std::vector<BodyId>& boxes) {
    for (int round = 0; round < 6; ++round) {
        runtime.submit(ApplyImpulseCommand{boxes[static_cast<std::size_t>(round) % boxes.size()], {0.5f, 2.0f, 0}});
        runtime.submit(AddTorqueCommand{boxes[3], {0, 0.3f, 0}});
        std::this_thread::sleep_for(7ms);
    }
    BodyDef def;
    def.shape = ShapeId{1, 1};  // the fixture's box shape
    def.position = {1, 3, 1};
    const BodyId spawned = runtime.spawn(def).get();
    runtime.submit(SetVelocityCommand{spawned, {0, 0, 2}, {1, 0, 0}});
    std::this_thread::sleep_for(10ms);
    runtime.submit(SetTransformCommand{boxes[0], {-2, 1, -2}, Quat{}});
    const auto hit = runtime.castRay(CastRayCommand{{0.6f, 10, 0.6f}, {0, -1, 0}, 100.0f, {}}).get();
    ASSERT_TRUE(hit.has_value());
    runtime.submit(AddForceCommand{hit->body, {0, 50, 0}});
    std::this_thread::sleep_for(10ms);
    runtime.submit(RemoveBodyCommand{spawned});
    runtime.submit(AddForceAtPointCommand{boxes[1], {5, 0, 0}, {0.6f, 0.5f, 0}});
}

}  // namespace

TEST(Runtime, InputsRecordedOnALiveRunReplayToTheSameState) {
    RuntimeSettings settings;
    settings.rate = 240;
    settings.recordInputs = true;
    Runtime live(test::boxesOnFloor(3, 2), settings);
    const std::vector<BodyId> boxes = [&] {
        std::vector<BodyId> all = live.world().bodies();
        return std::vector<BodyId>(all.begin() + 1, all.end());
    }();
    live.start();
    std::thread producer([&] { playInputs(live, boxes); });
    producer.join();
    std::this_thread::sleep_for(30ms);
    live.stop();
    const std::vector<RecordedInput> inputs = live.takeRecording();
    const std::uint64_t steps = live.world().stepCount();
    const std::uint64_t liveHash = live.world().stateHash();
    EXPECT_TRUE(live.takeInputErrors().empty());
    EXPECT_EQ(inputs.size(), 19u);  // every command playInputs sends

    // The same world, replayed on the caller, with one thread this time: the state hash must not depend on when the
    // inputs arrived in wall time, only on the steps they were applied at, nor on the thread count.
    RuntimeSettings replaySettings = settings;
    replaySettings.recordInputs = false;
    Runtime replayed(test::boxesOnFloor(3, 2, 1), replaySettings);
    replayed.replay(inputs, steps);
    EXPECT_EQ(replayed.world().stepCount(), steps);
    EXPECT_EQ(replayed.world().stateHash(), liveHash);

    // Without the inputs the state differs, so the comparison above can fail.
    Runtime idle(test::boxesOnFloor(3, 2), replaySettings);
    idle.replay({}, steps);
    EXPECT_NE(idle.world().stateHash(), liveHash);
}

namespace {

/// A world with a kinematic platform and a listening box on it, and a thread that drives the platform through the
/// input queue as a game would (one move a frame, not in step with the physics).
World platformWorld(int threads) {
    World world = test::boxesOnFloor(2, 1, threads);
    BodyDef platform;
    platform.type = BodyType::Kinematic;
    platform.shape = world.createShape(BoxDef{{1, 0.1f, 1}});
    platform.position = {4, 0.5f, 0};
    world.createBody(platform);
    BodyDef cargo;
    cargo.shape = ShapeId{1, 1};  // the fixture's box shape
    cargo.position = {4, 0.86f, 0};
    world.createBody(cargo);
    return world;
}

}  // namespace

TEST(Runtime, KinematicMovesAndEventsRecordedOnALiveRunReplayToTheSameStateAndEvents) {
    RuntimeSettings settings;
    settings.rate = 240;
    settings.recordInputs = true;
    Runtime live(platformWorld(2), settings);
    const std::vector<BodyId> all = live.world().bodies();
    const BodyId platform = all[all.size() - 2], cargo = all.back();
    live.start();
    live.submit(SetContactEventsCommand{cargo, true});
    for (int frame = 1; frame <= 30; ++frame) {
        const float t = static_cast<float>(frame) / 60.0f;
        live.submit(MoveKinematicCommand{platform, {4 + 0.3f * t, 0.5f + 0.4f * t, 0}, Quat{}, 1.0f / 60.0f});
        std::this_thread::sleep_for(std::chrono::microseconds(16667));
    }
    std::this_thread::sleep_for(20ms);
    live.stop();
    const std::vector<RecordedInput> inputs = live.takeRecording();
    const std::vector<StepEvents> liveEvents = live.takeEvents();
    EXPECT_TRUE(live.takeInputErrors().empty());
    EXPECT_EQ(inputs.size(), 31u);
    // The box landed on the platform and touched it: a begin among the events.
    ASSERT_FALSE(liveEvents.empty());
    EXPECT_FALSE(liveEvents.front().contacts.begins.empty());
    // The last move arrived (20 ms of steps passed after it was sent) and stopped there.
    EXPECT_NEAR(live.world().position(platform).x, 4.15f, 1e-4f);
    EXPECT_NEAR(live.world().position(platform).y, 0.7f, 1e-4f);
    EXPECT_EQ(live.world().linearVelocity(platform), Vec3{});

    RuntimeSettings replaySettings = settings;
    replaySettings.recordInputs = false;
    Runtime replayed(platformWorld(1), replaySettings);
    replayed.replay(inputs, live.world().stepCount());
    EXPECT_EQ(replayed.world().stateHash(), live.world().stateHash());
    const std::vector<StepEvents> replayedEvents = replayed.takeEvents();
    ASSERT_EQ(replayedEvents.size(), liveEvents.size());
    for (std::size_t k = 0; k < liveEvents.size(); ++k) {
        EXPECT_EQ(replayedEvents[k].step, liveEvents[k].step);
        EXPECT_EQ(replayedEvents[k].contacts.begins.size(), liveEvents[k].contacts.begins.size());
        EXPECT_EQ(replayedEvents[k].contacts.ends.size(), liveEvents[k].contacts.ends.size());
        EXPECT_EQ(replayedEvents[k].contacts.hits.size(), liveEvents[k].contacts.hits.size());
    }
}

TEST(Runtime, CharacterWalkedThroughTheQueueReplaysToTheSameStateAndPlace) {
    RuntimeSettings settings;
    settings.rate = 240;
    settings.recordInputs = true;
    Runtime live(test::boxesOnFloor(2, 1), settings);
    const CharacterId hero = live.addCharacter({-3, 0.02f, -3});
    live.start();
    // A game's input: walk, turn, jump, stop, at frame times the physics thread does not share.
    live.submit(WalkCharacterCommand{hero, {2, 0, 0}});
    std::this_thread::sleep_for(100ms);
    live.submit(WalkCharacterCommand{hero, {0, 0, 2}, 4.0f});
    std::this_thread::sleep_for(100ms);
    live.submit(WalkCharacterCommand{hero, {}});
    std::this_thread::sleep_for(1200ms);  // a jump at 4 m/s lasts 0.8 s
    live.stop();
    const std::vector<RecordedInput> inputs = live.takeRecording();
    ASSERT_EQ(inputs.size(), 3u);
    const CharacterState end = *live.character(hero);
    EXPECT_TRUE(end.grounded);
    EXPECT_GT(end.feet.x, -3 + 2 * 0.05f);
    EXPECT_GT(end.feet.z, -3 + 2 * 0.05f);
    EXPECT_NEAR(live.world().position(end.body).x, end.feet.x, 1e-4f);

    RuntimeSettings replaySettings = settings;
    replaySettings.recordInputs = false;
    Runtime replayed(test::boxesOnFloor(2, 1, 1), replaySettings);
    const CharacterId again = replayed.addCharacter({-3, 0.02f, -3});
    replayed.replay(inputs, live.world().stepCount());
    EXPECT_EQ(replayed.world().stateHash(), live.world().stateHash());
    EXPECT_EQ(replayed.character(again)->feet, end.feet);
    EXPECT_NE(test::errorOf([&] {
                  live.submit(WalkCharacterCommand{hero, {NAN, 0, 0}});
              }).find("velocity"),
              std::string::npos);
}

TEST(Runtime, ReplayRefusesInputsOutOfStepOrder) {
    Runtime runtime(test::boxesOnFloor(1, 1));
    const BodyId box = runtime.world().bodies()[1];
    const std::vector<RecordedInput> inputs = {{2, ApplyImpulseCommand{box, {1, 0, 0}}},
                                               {1, ApplyImpulseCommand{box, {1, 0, 0}}}};
    EXPECT_NE(test::errorOf([&] { runtime.replay(inputs, 5); }).find("inputs must be in step order"),
              std::string::npos);
}

TEST(Runtime, CommandsAreValidatedAtSubmissionAndStaleHandlesReportedAtTheStep) {
    Runtime runtime(test::boxesOnFloor(1, 1));
    const float nan = std::numeric_limits<float>::quiet_NaN();
    EXPECT_NE(test::errorOf([&] {
                  runtime.submit(AddForceCommand{BodyId{1, 1}, {nan, 0, 0}});
              }).find("AddForceCommand.force is not finite"),
              std::string::npos);
    EXPECT_NE(test::errorOf([&] {
                  runtime.castRay(CastRayCommand{{0, 0, 0}, {0, 0, 0}, 1.0f, {}});
              }).find("direction is zero"),
              std::string::npos);
    runtime.submit(ApplyImpulseCommand{BodyId{57, 3}, {1, 0, 0}});
    BodyDef bad;  // null shape: the spawn's future carries the world's error
    auto spawned = runtime.spawn(bad);
    runtime.singleStep();
    const std::vector<std::string> errors = runtime.takeInputErrors();
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_NE(errors[0].find("World::applyLinearImpulse"), std::string::npos);
    EXPECT_THROW(spawned.get(), Error);
    EXPECT_EQ(runtime.stats().steps, 1u);
}

TEST(Runtime, PauseSingleStepResumeAndStop) {
    Runtime runtime(test::boxesOnFloor(2, 1));
    EXPECT_NE(test::errorOf([&] { runtime.advance(-1); }).find("seconds must be in [0, 1e6]"), std::string::npos);
    runtime.start();
    EXPECT_NE(test::errorOf([&] { runtime.start(); }).find("already running"), std::string::npos);
    EXPECT_NE(test::errorOf([&] { runtime.advance(1); }).find("stop it first"), std::string::npos);
    std::this_thread::sleep_for(30ms);
    EXPECT_NE(test::errorOf([&] { runtime.singleStep(); }).find("pause it first"), std::string::npos);
    runtime.pause();
    const std::uint64_t paused = runtime.world().stepCount();  // the world may be read while paused
    std::this_thread::sleep_for(30ms);
    EXPECT_EQ(runtime.stats().steps, paused);
    runtime.singleStep();
    runtime.singleStep();
    EXPECT_EQ(runtime.world().stepCount(), paused + 2);
    EXPECT_EQ(runtime.latest(1.0f).step, paused + 2);
    runtime.resume();
    EXPECT_NE(test::errorOf([&] { runtime.world(); }).find("pause or stop it first"), std::string::npos);
    std::this_thread::sleep_for(30ms);
    runtime.stop();
    EXPECT_GT(runtime.world().stepCount(), paused + 2);
    EXPECT_FALSE(runtime.running());
}

TEST(Runtime, CanBeDestroyedWhileRunning) {
    // Destruction joins the thread; pending futures are released with broken promises, not left hanging.
    std::future<BodyId> pending;
    {
        Runtime runtime(test::boxesOnFloor(2, 1));
        runtime.start();
        runtime.pause();
        BodyDef def;
        def.shape = runtime.world().bodyShape(runtime.world().bodies()[1]);
        runtime.resume();
        pending = runtime.spawn(def);
        std::this_thread::sleep_for(20ms);
    }
    ASSERT_TRUE(pending.valid());
    EXPECT_EQ(pending.wait_for(0s), std::future_status::ready);
}
