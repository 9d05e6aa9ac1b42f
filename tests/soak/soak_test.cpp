// The soak's short version: the world `rubble soak` runs, at 3,000 bodies with 30 replaced every step for 240
// steps (each body lives 100 steps, long enough to land): the body count holds, nothing freezes, and the storage's slot
// map and dense rows agree after the churn. (Memory and step time over 20,000 steps are the runner's to show: a test
// must not time anything.)
#include <gtest/gtest.h>

#include "soak.h"
#include "world/world_access.h"

namespace rubble::soak {
namespace {

TEST(Soak, ChurningWorldKeepsItsCountAndItsStorageWhole) {
    SoakSettings settings;
    settings.bodies = 3000;
    settings.churn = 30;
    settings.threads = 2;
    Soak soak(settings);
    for (int s = 0; s < 240; ++s) {
        soak.step();
        ASSERT_EQ(soak.world().bodyCount(), 3001u) << "step " << s << " (the terrain is one body)";
    }
    EXPECT_EQ(soak.frozen(), 0u);
    EXPECT_EQ(detail::WorldAccess::of(soak.world()).bodies.checkInvariants(), "");
    EXPECT_GT(soak.world().lastProfile().meshPairs, 0u) << "the rain reached the terrain";
}

}  // namespace
}  // namespace rubble::soak
