// docs/architecture.md names real files: every backticked path in it exists.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

TEST(Docs, ArchitecturePageNamesFilesThatExist) {
    const std::filesystem::path root = RUBBLE_SOURCE_DIR;
    std::ifstream in(root / "docs/architecture.md");
    ASSERT_TRUE(in) << "docs/architecture.md is missing";
    std::stringstream text;
    text << in.rdbuf();
    const std::string page = text.str();
    const std::regex path(R"(`((?:include|src|simd|apps|perf|tests|docs|scenes)/[A-Za-z0-9_./-]+)`)");
    int checked = 0;
    for (auto it = std::sregex_iterator(page.begin(), page.end(), path); it != std::sregex_iterator(); ++it) {
        EXPECT_TRUE(std::filesystem::exists(root / (*it)[1].str())) << (*it)[1].str();
        ++checked;
    }
    EXPECT_GT(checked, 15);
}
