// docs/architecture.md names real files: every backticked path in it exists.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>

TEST(Docs, ArchitecturePageNamesFilesThatExist) {
    const std::filesystem::path root = RUBBLE_SOURCE_DIR;
    std::ifstream in(root / "docs/architecture.md");
    ASSERT_TRUE(in) << "docs/architecture.md is missing";
    std::stringstream text;
    text << in.rdbuf();
    const std::string page = text.str();
    const std::string_view roots[] = {"include/", "src/", "simd/", "apps/", "perf/", "tests/", "docs/", "scenes/"};
    int checked = 0;
    for (std::size_t open = page.find('`'); open != std::string::npos; open = page.find('`', open + 1)) {
        const std::size_t close = page.find('`', open + 1);
        if (close == std::string::npos) break;
        const std::string quoted = page.substr(open + 1, close - open - 1);
        open = close;
        bool isPath = quoted.find(' ') == std::string::npos;
        bool underRoot = false;
        for (std::string_view r : roots) underRoot |= quoted.rfind(r, 0) == 0;
        if (!isPath || !underRoot) continue;
        EXPECT_TRUE(std::filesystem::exists(root / quoted)) << quoted;
        ++checked;
    }
    EXPECT_GT(checked, 15);
}

// docs/limits.md states every limit of include/rubble/limits.h: each constant the header defines has its row.
TEST(Docs, LimitsPageStatesEveryLimit) {
    const std::filesystem::path root = RUBBLE_SOURCE_DIR;
    const auto read = [&](const char* file) {
        std::ifstream in(root / file);
        std::stringstream text;
        text << in.rdbuf();
        return text.str();
    };
    const std::string header = read("include/rubble/limits.h"), page = read("docs/limits.md");
    ASSERT_FALSE(page.empty()) << "docs/limits.md is missing";
    int constants = 0;
    for (std::size_t at = header.find("constexpr"); at != std::string::npos; at = header.find("constexpr", at + 1)) {
        const std::size_t name = header.find(" k", at), end = header.find(' ', name + 1);
        const std::string constant = header.substr(name + 1, end - name - 1);
        EXPECT_NE(page.find("`" + constant + "`"), std::string::npos) << constant << " has no row in docs/limits.md";
        ++constants;
    }
    EXPECT_GE(constants, 15);
}
