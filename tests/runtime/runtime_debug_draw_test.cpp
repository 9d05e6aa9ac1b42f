// Runtime debug drawing: the stepping side draws into a line batch after each step and the render side takes the
// newest one. Checked against World::debugDraw of the same world at the same step (drawn directly, independently of
// the runtime's hand-over), and for being off until asked.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "rubble/debug_draw.h"
#include "rubble/runtime.h"
#include "rubble/world.h"
#include "runtime/runtime_fixture.h"

using namespace rubble;

TEST(RuntimeDebugDraw, NothingIsDrawnUntilAsked) {
    Runtime runtime(test::boxesOnFloor(2, 1, 1));
    runtime.advance(0.05);
    DebugLines lines;
    EXPECT_FALSE(runtime.takeDebugLines(lines));
}

TEST(RuntimeDebugDraw, BatchMatchesTheWorldDrawnDirectlyAtThatStep) {
    Runtime runtime(test::boxesOnFloor(3, 2, 1));
    DebugDrawOptions options;
    options.flags = kDrawAabbs | kDrawContacts;
    runtime.setDebugDraw(options);
    runtime.advance(0.25);  // 30 steps at 120 Hz: the boxes have landed and touch
    DebugLines lines;
    ASSERT_TRUE(runtime.takeDebugLines(lines));
    World& world = runtime.world();
    EXPECT_EQ(lines.step, world.stepCount());
    DebugLineBatch direct;
    world.debugDraw(direct, options);
    ASSERT_EQ(lines.lineCount(), direct.lines.lineCount());
    ASSERT_EQ(lines.points.size(), 2 * lines.lineCount());
    for (std::size_t i = 0; i < lines.points.size(); ++i) EXPECT_EQ(lines.points[i], direct.lines.points[i]);
    // 19 bodies (floor + 18 boxes), 12 lines per box; contacts add 4 lines per point.
    EXPECT_GT(lines.lineCount(), 19u * 12);
    // Taken once: the next take has nothing new until another step.
    EXPECT_FALSE(runtime.takeDebugLines(lines));
    runtime.advance(1.0 / 120);
    EXPECT_TRUE(runtime.takeDebugLines(lines));
    runtime.setDebugDraw(std::nullopt);
    runtime.advance(1.0 / 120);
    EXPECT_FALSE(runtime.takeDebugLines(lines));
}

TEST(RuntimeDebugDraw, LiveThreadHandsOverBatches) {
    Runtime runtime(test::boxesOnFloor(2, 1, 1));
    DebugDrawOptions options;
    options.flags = kDrawShapes;
    runtime.setDebugDraw(options);
    runtime.start();
    DebugLines lines;
    bool got = false;
    for (int i = 0; i < 400 && !got; ++i) {
        got = runtime.takeDebugLines(lines);
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    runtime.stop();
    ASSERT_TRUE(got);
    EXPECT_EQ(lines.lineCount(), 5u * 12);  // floor and four boxes, 12 edges each
    EXPECT_GT(lines.step, 0u);
}
