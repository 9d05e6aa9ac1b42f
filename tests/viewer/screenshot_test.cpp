// Headless screenshots under Xvfb with Mesa's software renderer: the viewer renders S1 and the two demos into PNGs,
// which are read back (stb_image, independent of the viewer's writer) and checked for content: most pixels differ
// from the clear colour, and the scene's own colours are there (the boxes' orange, the marble's red, the character's
// yellow).
// Without xvfb-run (and no display) the tests are skipped, saying so.
#include <gtest/gtest.h>
#include <stb_image.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace {

/// Renderer::kClearColor as 8-bit values (0.62, 0.71, 0.80).
constexpr int kClearRgb[3] = {158, 181, 204};

bool haveProgram(const char* name) {
    return std::system((std::string("command -v ") + name + " >/dev/null 2>&1").c_str()) == 0;
}

struct Image {
    int width = 0, height = 0;
    std::vector<unsigned char> rgba;
};

/// Runs the viewer headless with `arguments`; returns false (with a reason) when it cannot run here.
bool renderHeadless(const std::string& arguments, const std::string& png, std::string& skipReason) {
    // Mesa's software rasteriser renders on the calling thread: its own worker threads are not instrumented, and
    // under ThreadSanitizer their teardown reads as races in swrast_dri.so that are not Rubble's. Under
    // AddressSanitizer the GL driver and X libraries leave a few hundred bytes allocated at exit, from modules
    // LeakSanitizer cannot even name, so leak checking is off for the viewer process (and only for it: every
    // library test, and the viewer's own non-GL tests, still check leaks).
    std::string prefix = "LP_NUM_THREADS=0 ASAN_OPTIONS=detect_leaks=0 ";
    if (haveProgram("xvfb-run"))
        prefix += "xvfb-run -a -s '-screen 0 1280x720x24' ";
    else if (!std::getenv("DISPLAY")) {
        skipReason = "xvfb-run is not installed and there is no DISPLAY (scripts/install-deps.sh installs xvfb)";
        return false;
    }
    std::filesystem::remove(png);
    const std::string command = prefix + "'" RUBBLE_VIEWER_BINARY "' " + arguments + " --screenshot '" + png + "'";
    const int status = std::system(command.c_str());
    EXPECT_EQ(status, 0) << command;
    return true;
}

Image load(const std::string& png) {
    Image image;
    int channels = 0;
    unsigned char* data = stbi_load(png.c_str(), &image.width, &image.height, &channels, 4);
    if (!data) return image;
    image.rgba.assign(data, data + static_cast<std::size_t>(image.width) * image.height * 4);
    stbi_image_free(data);
    return image;
}

template <typename Predicate>
double fraction(const Image& image, Predicate predicate) {
    std::size_t count = 0;
    const std::size_t pixels = image.rgba.size() / 4;
    for (std::size_t i = 0; i < pixels; ++i)
        if (predicate(image.rgba[4 * i], image.rgba[4 * i + 1], image.rgba[4 * i + 2])) ++count;
    return pixels ? static_cast<double>(count) / static_cast<double>(pixels) : 0;
}

bool isClear(int r, int g, int b) {
    // The clear colour exactly, give or take rounding in the resolve.
    return std::abs(r - kClearRgb[0]) <= 2 && std::abs(g - kClearRgb[1]) <= 2 && std::abs(b - kClearRgb[2]) <= 2;
}

std::string temporaryPng(const char* name) {
    return (std::filesystem::temp_directory_path() / (std::string(name) + "-" + std::to_string(getpid()) + ".png"))
        .string();
}

}  // namespace

TEST(ViewerScreenshot, PyramidSceneIsDrawn) {
    const std::string png = temporaryPng("rubble-viewer-s1");
    std::string skip;
    if (!renderHeadless("'" RUBBLE_SOURCE_DIR "/scenes/s1_pyramid.json' --frames 3 --size 320x180", png, skip))
        GTEST_SKIP() << skip;
    const Image image = load(png);
    ASSERT_EQ(image.width, 320);
    ASSERT_EQ(image.height, 180);
    // Ground and pyramid fill most of the view (about 80 %: sky only above the horizon); a blank or black image
    // has none, or all, of its pixels at the clear colour.
    const double drawn = fraction(image, [](int r, int g, int b) { return !isClear(r, g, b); });
    EXPECT_GT(drawn, 0.5);
    // The boxes' orange (0.93, 0.58, 0.20 before lighting): red well above blue, in a lit or shaded face.
    const double orange = fraction(image, [](int r, int g, int b) { return r > 120 && r > g + 30 && g > b + 30; });
    EXPECT_GT(orange, 0.05) << "the pyramid's boxes are missing";
    std::filesystem::remove(png);
}

TEST(ViewerScreenshot, MarbleDemoShowsTheBallInTheMaze) {
    const std::string png = temporaryPng("rubble-viewer-marble");
    std::string skip;
    if (!renderHeadless("--demo marble --autopilot --frames 30 --size 320x180", png, skip)) GTEST_SKIP() << skip;
    const Image image = load(png);
    ASSERT_EQ(image.width, 320);
    // The follow camera keeps the ball in view: its red (0.85, 0.12, 0.15) with little green or blue. The ball is
    // about 11 pixels across here (0.9 m at 16 m in a 0.9 rad view 180 pixels high); its red pixels, the darkest
    // shading and the selection box's edge aside, measured 52 (0.09 %). Half of that is asked for; with the ball
    // out of view there are none.
    const double red = fraction(image, [](int r, int g, int b) { return r > 100 && r > 2 * g && r > 2 * b; });
    EXPECT_GT(red, 0.00045) << "the marble is not in the picture";
    // The maze's blues fill most of the rest.
    const double blue = fraction(image, [](int r, int g, int b) { return b > r + 40 && !isClear(r, g, b); });
    EXPECT_GT(blue, 0.3);
    std::filesystem::remove(png);
}

TEST(ViewerScreenshot, CharacterDemoShowsTheCharacterOnTheCourse) {
    const std::string png = temporaryPng("rubble-viewer-character");
    std::string skip;
    if (!renderHeadless("--demo character --autopilot --frames 240 --size 320x180", png, skip)) GTEST_SKIP() << skip;
    const Image image = load(png);
    ASSERT_EQ(image.width, 320);
    // The follow camera keeps the character in view, from above and behind: its yellow (0.98, 0.82, 0.12), red and
    // green high, blue low. Its yellow pixels measured 174 (0.3 %) after 240 frames, in the corridor; half of that is
    // asked for; with the character out of view, or hidden by the corridor's walls, there are none.
    const double yellow = fraction(image, [](int r, int g, int b) { return r > 120 && g > 90 && b < r / 3; });
    EXPECT_GT(yellow, 0.0015) << "the character is not in the picture";
    const double drawn = fraction(image, [](int r, int g, int b) { return !isClear(r, g, b); });
    EXPECT_GT(drawn, 0.4);
    std::filesystem::remove(png);
}

TEST(ViewerScreenshot, DebugLayersComeThroughTheRuntime) {
    // The AABB layer is drawn by the stepping side (Runtime::setDebugDraw) and handed to the renderer; its green
    // (60, 220, 90) appears nowhere else in S1.
    auto green = [](int r, int g, int b) { return g > r + 80 && g > b + 60; };
    const std::string png = temporaryPng("rubble-viewer-layers");
    std::string skip;
    if (!renderHeadless("'" RUBBLE_SOURCE_DIR "/scenes/s1_pyramid.json' --frames 3 --size 320x180 --layers aabbs", png,
                        skip))
        GTEST_SKIP() << skip;
    const double withLayer = fraction(load(png), green);
    ASSERT_TRUE(renderHeadless("'" RUBBLE_SOURCE_DIR "/scenes/s1_pyramid.json' --frames 3 --size 320x180", png, skip));
    const double without = fraction(load(png), green);
    EXPECT_EQ(without, 0.0);
    EXPECT_GT(withLayer, 0.02) << "the AABB lines are missing";
    std::filesystem::remove(png);
}
