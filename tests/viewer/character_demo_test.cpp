// The character demo without OpenGL: driven through the Runtime as the viewer drives it (one walk command and one lift
// move a frame, physics advanced 1/60 s per frame on this thread), its autopilot walks the course to the ledge's end,
// riding the lift, and collects every coin on the way exactly once.
#include <gtest/gtest.h>

#include "character_demo.h"
#include "rubble/runtime.h"
#include "rubble/world.h"

namespace rubble::viewer {
namespace {

TEST(CharacterDemo, AutopilotWalksTheCourseAndCollectsEveryCoinOnce) {
    CharacterDemo demo;
    World world = CharacterDemo::makeWorld();
    demo.build(world);
    Runtime runtime(std::move(world));
    const CharacterId hero = runtime.addCharacter(demo.start);
    const BodyId body = runtime.character(hero)->body;
    constexpr float kFrame = 1.0f / 60.0f;
    bool arrived = false;
    int frames = 0;
    for (; frames < 60 * 40 && !arrived; ++frames) {
        const CharacterState state = *runtime.character(hero);
        arrived = demo.atEnd(state.feet);
        for (const BodyId coin : demo.collect(runtime.takeEvents(), body)) runtime.submit(RemoveBodyCommand{coin});
        runtime.submit(WalkCharacterCommand{hero, demo.autopilotWalk(state)});
        runtime.submit(demo.moveLift(state, kFrame));
        runtime.advance(kFrame);
    }
    EXPECT_TRUE(arrived) << "stopped at " << runtime.character(hero)->feet.x << ", " << runtime.character(hero)->feet.y
                         << " after " << frames << " frames";
    EXPECT_EQ(demo.coinsCollected, static_cast<int>(demo.coins.size()));
    EXPECT_TRUE(runtime.takeInputErrors().empty());
    for (const BodyId coin : demo.coins) EXPECT_FALSE(runtime.world().isValid(coin));
}

TEST(CharacterDemo, KeysWalkRelativeToTheCamera) {
    const CharacterDemo demo;
    const Vec3 ahead = demo.walkVelocity(0, 1, {0, -0.5f, -1});
    EXPECT_NEAR(ahead.z, -CharacterDemo::kWalkSpeed, 1e-5f);
    EXPECT_NEAR(ahead.y, 0, 1e-6f);
    const Vec3 diagonal = demo.walkVelocity(1, 1, {0, 0, -1});
    EXPECT_NEAR(length(diagonal), CharacterDemo::kWalkSpeed, 1e-4f);
    EXPECT_EQ(demo.walkVelocity(0, 0, {0, 0, -1}), Vec3{});
}

}  // namespace
}  // namespace rubble::viewer
