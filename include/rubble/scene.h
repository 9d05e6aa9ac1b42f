#pragma once
// Scene files: JSON documents describing settings, materials, shapes, bodies and generators.
// The format is documented in docs/scene_format.md.
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "rubble/body.h"
#include "rubble/id.h"
#include "rubble/joint.h"
#include "rubble/settings.h"
#include "rubble/shapes.h"

namespace rubble {

class World;

/// A body of a scene; `shape` indexes Scene::shapes (BodyDef::shape is filled in by instantiate).
struct SceneBody {
    std::uint32_t shape = 0;
    BodyDef def;
};

/// A joint of a scene (docs/scene_format.md, "Joints"), in world terms: instantiate() turns the world anchors and the
/// axis into each body's local frame and fills in the bodies. The def's other fields (limits, motor, spring, breaking)
/// are taken as they are.
struct SceneJoint {
    std::variant<DistanceJointDef, SpringJointDef, BallJointDef, HingeJointDef> def;
    std::uint32_t bodyA = 0, bodyB = 0;  ///< indices into Scene::bodies
    Vec3 anchorA, anchorB;               ///< world points fixed to A and to B (the same point but for rods and springs)
    Vec3 axis{0, 1, 0};                  ///< hinges: the axis, world
};

/// Figures a scene reports at the end of a run (SCENES.md, and the hard cases' own).
enum class SceneFigure : std::uint8_t {
    MaxDisplacement,  ///< largest distance any dynamic body's centre of mass moved from its start, m
    Tunnelled,        ///< dynamic bodies whose centre is more than 0.5 m below the terrain surface
    MaxSpeed,         ///< largest speed any dynamic body reached after any step of the run, m/s
    FinalSpeed,       ///< largest speed of any dynamic body after the last step, m/s (at rest: near 0)
    Moved,            ///< dynamic bodies whose centre of mass ended more than 0.1 m from its start
    /// Dynamic bodies whose centre of mass ended outside the box spanned by the static bodies' positions (for a
    /// scene enclosed by static walls: those that got out)
    Escaped,
    LateApex,  ///< highest centre of mass of any dynamic body over the last 2 s of the run, m
    /// Largest distance between a joint's two anchors (ball and hinge joints), or of a rod's anchors from its length
    /// (distance joints), after the last step, m. Springs stretch by design and are left out.
    JointStretch,
    /// Highest a dynamic sphere's lowest point rose above the terrain surface under its centre after the run's first
    /// second, m: a marble that hops over a mesh's edges shows it (other shapes are left out)
    MaxHop,
};
inline constexpr int kSceneFigureCount = 9;
/// The figure's name in scene files ("max_displacement", ...).
std::string_view sceneFigureName(SceneFigure f);

struct Scene {
    std::string name;
    std::string source;  ///< file the scene came from
    WorldSettings settings;
    int steps = 60;  ///< default step count of a run
    std::vector<std::string> shapeNames;
    std::vector<ShapeDef> shapes;
    std::vector<SceneBody> bodies;  ///< explicit bodies first, then generated ones in file order
    std::vector<SceneJoint> joints;
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

/// Measures the scene's figures over a run: the runner prints them, the stability tests bound them. Construct it
/// once the scene is instantiated (it takes the starts), call record() after every step, read results() at the end.
/// record() costs a pass over the dynamic bodies only when a figure needs one (MaxSpeed, LateApex, MaxHop).
class SceneFigureMeter {
public:
    SceneFigureMeter(const Scene& scene, const World& world, const std::vector<BodyId>& bodies);
    void record(const World& world);
    struct Result {
        SceneFigure figure;
        double value;
        std::string text;  ///< "largest displacement from start: 0.0123 m"
    };
    std::vector<Result> results(const World& world) const;
    /// The value of one figure the scene declares (NaN when it declares none such).
    double value(const World& world, SceneFigure figure) const;

private:
    std::vector<SceneFigure> figures_;
    std::vector<BodyId> dynamic_;
    std::vector<Vec3> starts_;
    Vec3 staticMin_{0, 0, 0}, staticMax_{0, 0, 0};
    bool anyStatic_ = false;
    double maxSpeed_ = 0;
    double maxHop_ = 0;
    std::vector<std::pair<BodyId, float>> spheres_;  ///< MaxHop: dynamic spheres and their radii
    double time_ = 0;
    std::vector<std::pair<double, double>> apexes_;  ///< (time, highest centre) per step of the last 2 s
    /// JointStretch: per joint, its bodies, local anchors and rod length (0 for ball and hinge joints).
    struct JointAnchors {
        BodyId a, b;
        Vec3 localA, localB;
        float length = 0;
    };
    std::vector<JointAnchors> joints_;
};

/// Creates the scene's shapes, bodies and joints in `world`; returns the body handles in Scene::bodies order.
std::vector<BodyId> instantiate(const Scene& scene, World& world);

}  // namespace rubble
