// The core's instruction sets: what the check names when a CPU lacks them, and which level of a dispatch build the
// loader chose (scripts/test.sh runs the suite once per level this machine has and says which it expects).
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "core/cpu_check.h"
#include "rubble/build_info.h"
#include "rubble/error.h"
#include "rubble/world.h"

namespace rubble {
namespace {

using detail::missingCpuFeatures;

TEST(CpuCheck, NamesExactlyTheMissingFeaturesInOrder) {
    const std::uint32_t v3 =
        detail::kCpuSse41 | detail::kCpuSse42 | detail::kCpuAvx | detail::kCpuAvx2 | detail::kCpuFma | detail::kCpuBmi2;
    EXPECT_EQ(missingCpuFeatures(v3, v3), "");
    EXPECT_EQ(missingCpuFeatures(v3, v3 | detail::kCpuAvx512f), "");
    EXPECT_EQ(missingCpuFeatures(v3, detail::kCpuSse41 | detail::kCpuSse42 | detail::kCpuAvx), "AVX2, FMA, BMI2");
    EXPECT_EQ(missingCpuFeatures(detail::kCpuAvx512vl | detail::kCpuSse41, 0), "SSE4_1, AVX512VL");
    EXPECT_EQ(missingCpuFeatures(0, 0), "");
}

TEST(CpuCheck, CoreFeaturesMatchItsBuild) {
    // Each level includes the one below; what the core was compiled for implies its lane width.
    const std::string build = buildInfo().coreBuild;
    const std::uint32_t f = detail::kCoreCpuFeatures;
    if (build == "x86-64-v2" || build == "x86-64-v3" || build == "x86-64-v4") {
        EXPECT_NE(f & detail::kCpuSse42, 0u);
        EXPECT_EQ((f & detail::kCpuAvx2) != 0, build != "x86-64-v2");
        EXPECT_EQ((f & detail::kCpuAvx512f) != 0, build == "x86-64-v4");
    } else {
        EXPECT_EQ(build, "native");
    }
    EXPECT_EQ(missingCpuFeatures(f, detail::cpuFeatures()), "") << "the running core needs more than this CPU has";
    EXPECT_NO_THROW(World{WorldSettings{}});
}

TEST(CpuCheck, LoaderChoseTheExpectedLevel) {
    const char* expected = std::getenv("RUBBLE_EXPECT_CORE_BUILD");
    if (expected == nullptr) GTEST_SKIP() << "RUBBLE_EXPECT_CORE_BUILD not set (scripts/test.sh sets it)";
    const BuildInfo info = buildInfo();
    ASSERT_STREQ(info.coreBuild, expected);
    const std::string level = expected;
    const int lanes = level == "x86-64-v4" ? 16 : level == "x86-64-v3" ? 8 : 4;
    EXPECT_EQ(info.floatLanes, lanes) << info.instructionSet;
}

}  // namespace
}  // namespace rubble
