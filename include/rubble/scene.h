#pragma once
// Scene files: JSON documents describing settings, materials, shapes, bodies and generators.
// The format is documented in docs/scene_format.md.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "rubble/body.h"
#include "rubble/id.h"
#include "rubble/settings.h"
#include "rubble/shapes.h"

namespace rubble {

class World;

/// A body of a scene; `shape` indexes Scene::shapes (BodyDef::shape is filled in by instantiate).
struct SceneBody {
    std::uint32_t shape = 0;
    BodyDef def;
};

/// Figures a scene reports at the end of a run (SCENES.md).
enum class SceneFigure : std::uint8_t {
    MaxDisplacement,  ///< largest distance any dynamic body moved from its start, m
    Tunnelled,        ///< dynamic bodies whose centre is more than 0.5 m below the terrain surface
};

struct Scene {
    std::string name;
    std::string source;  ///< file the scene came from
    WorldSettings settings;
    int steps = 60;  ///< default step count of a run
    std::vector<std::string> shapeNames;
    std::vector<ShapeDef> shapes;
    std::vector<SceneBody> bodies;  ///< explicit bodies first, then generated ones in file order
    std::vector<SceneFigure> figures;
};

/// Reads and validates a scene file. Throws rubble::Error whose message names the file, the JSON path
/// (or line and column for syntax errors) and the problem.
Scene loadScene(const std::string& path);
/// Same, from text in memory; `sourceName` stands for the file in messages and for resolving relative paths.
Scene parseScene(std::string_view text, const std::string& sourceName);

/// Reads a settings object of the scene format (docs/scene_format.md, `settings`) over the scene's settings: keys it
/// names replace the scene's, the others stay. Validated as in a scene file; messages name `sourceName` and the key.
void overrideSettings(Scene& scene, std::string_view settingsJson, const std::string& sourceName);

/// Creates the scene's shapes and bodies in `world`; returns the body handles in Scene::bodies order.
std::vector<BodyId> instantiate(const Scene& scene, World& world);

}  // namespace rubble
