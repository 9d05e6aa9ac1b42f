// rubble-viewer: opens a scene (or a demo: marble, character) in a window, or renders it headless into a PNG.

#include <cstdio>
#include <exception>
#include <optional>
#include <string>
#include <string_view>

#include "command_line.h"
#include "rubble/error.h"
#include "viewer_app.h"

namespace {

constexpr const char* kUsage =
    "usage: rubble-viewer [SCENE.json | --demo marble | --demo character] [options]\n"
    "\n"
    "  SCENE.json         scene file (default: the standard scene S1, scenes/s1_pyramid.json)\n"
    "  --demo marble      the marble demo: steer a ball through a maze with the arrow keys\n"
    "  --demo character   the character demo: walk a course of corridor, stairs, ramp and lift with\n"
    "                     the arrows or WASD (space jumps), collecting coins\n"
    "  --rate HZ          physics steps per second (default 120)\n"
    "  --threads T        physics worker threads (default: the scene's setting; 0 = all cores)\n"
    "  --size WxH         window or screenshot size in pixels (default 1280x720)\n"
    "  --frames N         headless: render N frames, physics stepped 1/60 s per frame on this thread\n"
    "  --screenshot FILE  headless: write the last frame as a PNG (needs --frames)\n"
    "  --overlay          headless: draw the overlay into the screenshot too (its numbers vary from run to run)\n"
    "  --autopilot        demos: the marble finds its way through the maze, the character walks the course\n"
    "  --layers LIST      debug layers shown at the start, comma-separated: contacts, aabbs, islands, sleeping,\n"
    "                     cells (broad-phase grid cells and static tree), joints\n"
    "                     (default: sleeping)\n";

[[noreturn]] void usageError(const std::string& message) {
    std::fprintf(stderr, "rubble-viewer: %s\n\n%s", message.c_str(), kUsage);
    std::exit(2);
}

long parseNumber(std::string_view flag, std::string_view text, long min, long max) {
    const std::optional<long> value = rubble::apps::parseWhole(text, min, max);
    if (!value) usageError(rubble::apps::wholeNumberError(flag, text, min, max));
    return *value;
}

std::string defaultScene() { return rubble::apps::defaultScene(RUBBLE_SCENES_DIR); }

rubble::viewer::ViewerOptions parseOptions(int argc, char** argv) {
    rubble::viewer::ViewerOptions o;
    bool overlayFlag = false;
    for (int i = 1; i < argc; ++i) {
        const std::string_view a = argv[i];
        auto value = [&]() -> std::string_view {
            if (i + 1 >= argc) usageError(std::string(a) + " needs a value");
            return argv[++i];
        };
        if (a == "--help" || a == "-h") {
            std::fputs(kUsage, stdout);
            std::exit(0);
        } else if (a == "--demo") {
            const std::string_view name = value();
            if (name != "marble" && name != "character")
                usageError("--demo knows 'marble' and 'character', not '" + std::string(name) + "'");
            (name == "marble" ? o.marble : o.character) = true;
        } else if (a == "--rate")
            o.rate = static_cast<double>(parseNumber(a, value(), 1, 10000));
        else if (a == "--threads")
            o.threads = static_cast<int>(parseNumber(a, value(), 0, 1024));
        else if (a == "--size") {
            const std::string_view size = value();
            const std::size_t x = size.find('x');
            if (x == std::string_view::npos) usageError("--size takes WIDTHxHEIGHT, not '" + std::string(size) + "'");
            o.width = static_cast<int>(parseNumber(a, size.substr(0, x), 16, 8192));
            o.height = static_cast<int>(parseNumber(a, size.substr(x + 1), 16, 8192));
        } else if (a == "--frames")
            o.frames = static_cast<int>(parseNumber(a, value(), 1, 1'000'000));
        else if (a == "--screenshot")
            o.screenshot = std::string(value());
        else if (a == "--overlay")
            overlayFlag = true;
        else if (a == "--autopilot")
            o.autopilot = true;
        else if (a == "--layers") {
            o.layers = std::string(value());
            std::string_view rest = o.layers;
            while (!rest.empty()) {
                const std::size_t comma = rest.find(',');
                const std::string_view name = rest.substr(0, comma);
                if (name != "contacts" && name != "aabbs" && name != "islands" && name != "sleeping" &&
                    name != "cells" && name != "joints")
                    usageError("--layers knows contacts, aabbs, islands, sleeping, cells and joints, not '" +
                               std::string(name) + "'");
                rest = comma == std::string_view::npos ? std::string_view{} : rest.substr(comma + 1);
            }
        } else if (const auto error = rubble::apps::takeSceneArgument(a, o.scene)) {
            usageError(*error);
        }
    }
    if ((o.marble || o.character) && !o.scene.empty()) usageError("give a scene or a demo, not both");
    if (o.marble && o.character) usageError("give one demo");
    if (!o.screenshot.empty() && o.frames == 0) usageError("--screenshot needs --frames N (the headless mode)");
    if (o.autopilot && !o.marble && !o.character) usageError("--autopilot is for the demos");
    if (!o.marble && !o.character && o.scene.empty()) o.scene = defaultScene();
    // Headless screenshots leave the overlay out unless asked: its timings would make them differ run to run.
    if (o.frames > 0) o.overlay = overlayFlag;
    return o;
}

}  // namespace

int main(int argc, char** argv) {
    const rubble::viewer::ViewerOptions options = parseOptions(argc, argv);
    try {
        return rubble::viewer::runViewer(options);
    } catch (const rubble::Error& e) {
        std::fprintf(stderr, "rubble-viewer: %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rubble-viewer: %s\n", e.what());
        return 1;
    }
}
