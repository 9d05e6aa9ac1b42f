// Scene files from anyone: the loader either refuses the text with a message that names the file, or accepts a scene
// that the World then builds and steps without complaint (the loader and the World hold the same limits,
// include/rubble/limits.h). Anything else (a crash, a sanitizer report, an exception that is not rubble::Error, a
// scene the loader accepted and the World refused) is a finding.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "fuzz_support.h"
#include "rubble/error.h"
#include "rubble/scene.h"
#include "rubble/world.h"
#include "scene/generators.h"

namespace {

// Generators could ask for 16 million bodies in a few bytes, which a file may do; the fuzzer's inputs are held to a
// few hundred bodies and triangles so that each runs in milliseconds, through the same checks at other numbers.
constexpr rubble::scene_detail::SceneCaps kCaps{500, 2000};
constexpr int kSteps = 2;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace rubble;
    // A name inside tests/data/fuzz, so that a scene naming "../obj/quad.obj" reaches the test OBJ files from any
    // working directory.
    const std::string source = RUBBLE_FUZZ_DATA_DIR "/scene.json";
    Scene scene;
    try {
        scene =
            scene_detail::parseSceneWithin(std::string_view(reinterpret_cast<const char*>(data), size), source, kCaps);
    } catch (const Error& e) {
        fuzz::check(std::string_view(e.what()).find(source) != std::string_view::npos,
                    "the loader's message does not name the file: " + std::string(e.what()));
        return 0;
    }
    // Every setting the file gave, but the solver's loops held short: 64 substeps of a thousand iterations is a legal
    // scene and the same code as 4 of 2, at a thousand times the fuzzer's time.
    WorldSettings settings = scene.settings;
    settings.threads = 1;
    settings.substeps = std::min(settings.substeps, 4);
    settings.velocityIterations = std::min(settings.velocityIterations, 4);
    settings.positionIterations = std::min(settings.positionIterations, 2);
    World world(settings);
    try {
        instantiate(scene, world);
        for (int i = 0; i < kSteps; ++i) world.step(settings.timeStep);
    } catch (const Error& e) {
        fuzz::fail("the loader accepted a scene the World refused: " + std::string(e.what()));
    }
    return 0;
}
