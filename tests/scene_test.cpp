// Scene files: malformed input is refused with a message naming file, place and problem; the six standard scenes
// load with exactly the bodies SCENES.md describes (its formulas are evaluated independently here); a scene
// instantiates into a World.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <variant>
#include <vector>

#include "rubble/error.h"
#include "rubble/scene.h"
#include "rubble/world.h"
#include "support/error_of.h"

namespace rubble {
namespace {

const std::string kData = std::string(RUBBLE_TEST_DATA_DIR) + "/scenes/";
const std::string kScenes = std::string(RUBBLE_SOURCE_DIR) + "/scenes/";

using test::errorOf;

void expectAll(const std::string& message, const std::vector<std::string>& parts) {
    for (const std::string& p : parts)
        EXPECT_NE(message.find(p), std::string::npos) << "'" << p << "' not in: " << message;
}

// ---------------------------------------------------------------------------------------------------------------
// Malformed files

struct BadFile {
    const char* file;
    std::vector<std::string> parts;  ///< substrings the message must hold (besides the file name)
};

const BadFile kBadFiles[] = {
    {"bad_syntax.json", {"bad_syntax.json:3:56: syntax error:", "unexpected '}'"}},
    {"bad_truncated.json", {"bad_truncated.json:3:", "syntax error", "truncated"}},
    {"bad_empty.json", {"empty file"}},
    {"bad_toplevel.json", {"top level must be an object, got an array"}},
    {"bad_unknown_key.json", {"at /bodies/0/positon: unknown key 'positon' (did you mean 'position'?)"}},
    {"bad_position_type.json", {"at /bodies/3/position: expected an array of 3 numbers, got a string"}},
    {"bad_negative_extent.json",
     {"at /shapes/cube/half_extents/1: must be in [0.0001, 10000] m (got -1; docs/limits.md)"}},
    {"bad_unknown_shape.json", {"at /bodies/0/shape: unknown shape 'cub'", "cube"}},
    {"bad_integrator.json", {"at /settings/integrator: unknown integrator 'rk5'"}},
    {"bad_overflow.json", {"bad_overflow.json:3:48: number out of range: 1e999"}},
    {"bad_negative_count.json", {"at /generators/0/count: must be >= 0 (got -5)"}},
    {"bad_too_many.json", {"at /generators/0:", "more than the limit of 16777216"}},
    {"bad_missing_shape.json", {"at /bodies/0: missing required key 'shape'"}},
    {"bad_dynamic_mesh.json", {"at /bodies/0/shape:", "static-only shape"}},
    {"bad_duplicate_key.json", {"bad_duplicate_key.json:3:", "duplicate key 'position'"}},
    {"bad_float_range.json", {"at /materials/heavy/density:", "too large for a 32-bit float"}},
    {"bad_quaternion.json", {"at /bodies/0/rotation: quaternion must have unit length (got length 2)"}},
    {"bad_effect.json", {"at /settings/effects/0: unknown effect 'gravty' (did you mean 'gravity'?)"}},
    {"bad_mesh_index.json", {"at /shapes/tri/indices/2: must be <= 2 (got 7)"}},
    {"bad_flat_hull.json", {"at /shapes/plate/points:", "the 5 points are coplanar: a hull needs volume"}},
    {"bad_steps.json", {"at /steps: expected an integer, got 2.5"}},
    {"bad_missing_obj.json", {"at /shapes/terrain/obj:", "no_such_terrain.obj"}},
    {"bad_compound_child.json", {"at /shapes/thing/children/1/shape/type:", "compound child must be"}},
    {"bad_random_range.json", {"at /generators/0/max:", "axis 1"}},
    {"bad_static_velocity.json", {"at /bodies/0/angular_velocity: a static body cannot have a velocity"}},
};

TEST(SceneLoader, MalformedFilesAreRefusedWithFilePlaceAndProblem) {
    for (const BadFile& bad : kBadFiles) {
        SCOPED_TRACE(bad.file);
        const std::string message = errorOf([&] { loadScene(kData + bad.file); });
        expectAll(message, {bad.file});
        expectAll(message, bad.parts);
    }
}

TEST(SceneLoader, MissingFileNamesTheFileAndTheReason) {
    const std::string message = errorOf([] { loadScene(kData + "no_such_scene.json"); });
    expectAll(message, {"cannot open ", "no_such_scene.json", "No such file or directory"});
}

TEST(SceneLoader, DirectoryIsNotAScene) {
    const std::string message = errorOf([] { loadScene(kData); });
    expectAll(message, {"scenes"});
}

TEST(SceneLoader, AbsurdNestingIsRefusedBeforeParsing) {
    const std::string deep(100'000, '[');
    expectAll(errorOf([&] { parseScene(deep, "deep.json"); }),
              {"deep.json:1:65:", "nesting deeper than 64 levels at line 1"});
    // Brackets inside strings do not count.
    const std::string inString = "{\"name\": \"" + std::string(1000, '[') + "\"}";
    EXPECT_EQ(parseScene(inString, "s.json").name, std::string(1000, '['));
    // Deep but within the limit: refused for what it is, not crashed on.
    std::string ok = "{\"name\": " + std::string(60, '[') + std::string(60, ']') + "}";
    expectAll(errorOf([&] { parseScene(ok, "ok.json"); }), {"at /name: expected a string, got an array"});
}

TEST(SceneLoader, BinaryGarbageAndInvalidUtf8AreSyntaxErrors) {
    std::string garbage;
    std::mt19937 rng(1);
    for (int i = 0; i < 4096; ++i) garbage += static_cast<char>(rng() & 0xFF);
    garbage[0] = '\x01';
    const std::string m1 = errorOf([&] { parseScene(garbage, "garbage.json"); });
    expectAll(m1, {"garbage.json:1:1: syntax error"});
    for (const char c : m1) EXPECT_TRUE(c >= 0x20 && c < 0x7F) << "unprintable byte in message: " << m1;

    const std::string badUtf8 = "{\n  \"name\": \"caf\xC3\x28\"\n}";
    const std::string m2 = errorOf([&] { parseScene(badUtf8, "utf8.json"); });
    expectAll(m2, {"utf8.json:2:", "syntax error", "UTF-8"});

    const std::string nul("{\"name\": \"a\"}\0\0", 15);
    expectAll(errorOf([&] { parseScene(nul, "nul.json"); }), {"nul.json:1:14: syntax error: NUL byte"});
    // A document cut short mid-way through a value.
    expectAll(errorOf([] { parseScene("{\"steps\": [1, 2", "cut.json"); }),
              {"cut.json:1:", "end of input", "truncated"});
    expectAll(errorOf([] { parseScene("  \n\t ", "blank.json"); }), {"blank.json: empty file"});
}

TEST(SceneLoader, EveryTruncationAndRandomCorruptionIsAnErrorOrAScene) {
    std::string text;
    {
        std::FILE* f = std::fopen((kData + "good_small.json").c_str(), "rb");
        ASSERT_NE(f, nullptr);
        char buf[4096];
        std::size_t got;
        while ((got = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, got);
        std::fclose(f);
    }
    const std::string name = kData + "fuzz.json";  // in the data folder, so the OBJ reference still resolves
    for (std::size_t cut = 0; cut + 2 < text.size(); ++cut) {
        // Every strict prefix cuts the top-level object short (the last bytes are "}\n").
        const std::string m = errorOf([&] { parseScene(std::string_view(text).substr(0, cut), name); });
        ASSERT_NE(m.find("fuzz.json"), std::string::npos) << "cut at " << cut << ": " << m;
    }
    std::mt19937 rng(7);
    for (int round = 0; round < 2000; ++round) {
        std::string t = text;
        const int edits = 1 + static_cast<int>(rng() % 4);
        for (int e = 0; e < edits; ++e) t[rng() % t.size()] = static_cast<char>(rng() & 0xFF);
        try {
            parseScene(t, name);
        } catch (const Error& e) {
            ASSERT_NE(std::string(e.what()).find("fuzz.json"), std::string::npos) << e.what();
        }
    }
}

TEST(SceneLoader, SemanticErrorsBuiltInTest) {
    const std::string shapes = R"("shapes": {"cube": {"type": "box", "half_extents": [0.5, 0.5, 0.5]}})";
    auto msg = [&](const std::string& body) {
        return errorOf([&] { parseScene("{" + shapes + ", " + body + "}", "t.json"); });
    };
    expectAll(msg(R"("bodies": [{"shape": "cube", "type": "floating"}])"),
              {"t.json: at /bodies/0/type: unknown body type 'floating'"});
    expectAll(msg(R"("bodies": [{"shape": "cube", "user_data": -1}])"), {"at /bodies/0/user_data: must be >= 0"});
    expectAll(msg(R"("bodies": [{"shape": "cube", "filter": {"mask": 4294967296}}])"),
              {"at /bodies/0/filter/mask: must be <= 4294967295"});
    expectAll(msg(R"("bodies": [{"shape": "cube", "material": "steel"}])"),
              {"at /bodies/0/material: unknown material 'steel'"});
    expectAll(msg(R"("bodies": [{"shape": "cube", "material": {"restitution": 2}}])"),
              {"at /bodies/0/material/restitution: must be <= 1"});
    expectAll(msg(R"("bodies": [{"shape": "cube", "rotation": {"axis": [0, 0, 0], "degrees": 3}}])"),
              {"at /bodies/0/rotation/axis: axis must not be zero"});
    expectAll(msg(R"("generators": [{"type": "pyramid", "shape": "cube", "base": 5, "layers": 6}])"),
              {"at /generators/0/layers: must be <= 5"});
    expectAll(
        msg(R"("generators": [{"type": "pyramid", "shape": "cube", "base": 1000000, "repeat": {"count": [100, 100], "spacing": 1}}])"),
        {"at /generators/0:", "more than the limit"});
    expectAll(msg(R"("generators": [{"type": "pyramd", "base": 3}])"),
              {"at /generators/0/type: unknown generator type 'pyramd' (did you mean 'pyramid'?)"});
    expectAll(msg(R"("generators": [{"type": "random", "shape": "cube", "count": 20000000, "min": 0, "max": 1}])"),
              {"at /generators/0/count:", "more than the limit of 16777216"});
    expectAll(msg(R"("figures": ["max_displacement", "tunneled"])"),
              {"at /figures/1: unknown figure 'tunneled' (did you mean 'tunnelled'?)"});
    expectAll(msg(R"("settings": {"dt": 0})"), {"at /settings/dt: must be in [1e-05, 1] s (got 0; docs/limits.md)"});
    expectAll(msg(R"("settings": {"broadphase": "octree"})"),
              {"at /settings/broadphase: unknown broad phase 'octree'", "sap"});
    expectAll(msg(R"("settings": {"effects": ["gravity", "gravity"]})"),
              {"at /settings/effects/1: effect 'gravity' listed twice"});
    expectAll(msg(R"("stepz": 3)"), {"at /stepz: unknown key 'stepz' (did you mean 'steps'?)"});
    expectAll(errorOf([] { parseScene(R"({"shapes": {"a/b": {"type": "sphere", "radius": -2}}})", "p.json"); }),
              {"p.json: at /shapes/a~1b/radius: must be in [0.0001, 10000] m (got -2; docs/limits.md)"});
}

// The hostile files of issue 21, each refused at load with the file, the JSON path and the limit, before any
// allocation the input sizes or any read that could block.
TEST(SceneLoader, InputBeyondTheEnginesLimitsIsRefusedWithTheLimitAndThePlace) {
    const std::string shapes = R"("shapes": {"cube": {"type": "box", "half_extents": [0.5, 0.5, 0.5]}})";
    auto msg = [&](const std::string& body) {
        return errorOf([&] { parseScene("{" + shapes + ", " + body + "}", "t.json"); });
    };
    expectAll(msg(R"("settings": {"substeps": 100})"), {"t.json: at /settings/substeps: must be <= 64 (got 100)"});
    expectAll(msg(R"("settings": {"velocity_iterations": 5000})"), {"at /settings/velocity_iterations:", "1000"});
    expectAll(msg(R"("settings": {"dt": 1e-40})"), {"at /settings/dt: must be in [1e-05, 1] s (got", "docs/limits.md"});
    expectAll(msg(R"("settings": {"dt": 2})"), {"at /settings/dt: must be in [1e-05, 1] s (got 2; docs/limits.md)"});
    expectAll(errorOf([] { parseScene(R"({"shapes": {"dust": {"type": "sphere", "radius": 1e-20}}})", "d.json"); }),
              {"d.json: at /shapes/dust/radius: must be in [0.0001, 10000] m (got 1e-20; docs/limits.md)"});
    expectAll(msg(R"("materials": {"lead": {"density": 1e38}})"),
              {"at /materials/lead/density: must be in [0.001, 1e+06] kg/m^3 (got 1e+38; docs/limits.md)"});
    expectAll(msg(R"("steps": 1000000000)"), {"at /steps:", "100000000"});
    // Body positions within the World's coordinate limit, explicit or generated (the fuzzer's second finding).
    expectAll(msg(R"("bodies": [{"shape": "cube", "position": [-275630, 0, 0]}])"),
              {"at /bodies/0/position: (-275630, 0, 0), farther than 100000 m from the origin", "docs/limits.md"});
    expectAll(msg(R"("generators": [{"type": "grid", "shape": "cube", "count": [3, 1, 1], "spacing": [60000, 1, 1]}])"),
              {"at /generators/0: puts body 2 at (", "farther than 100000 m from the origin"});
    expectAll(errorOf([] { parseScene(R"({"shapes": {"m": {"type": "mesh", "obj": "/dev/zero"}}})", "o.json"); }),
              {"o.json: at /shapes/m/obj: '/dev/zero' is an absolute path: name the OBJ file relative to the scene"});
    expectAll(errorOf([] {
                  parseScene(
                      R"({"shapes": {"h": {"type": "heightfield", "rows": 70000, "columns": 70000, "heights": []}}})",
                      "h.json");
              }),
              {"h.json: at /shapes/h", "9799720002 triangles, more than 16777216"});
}

TEST(SceneLoader, OnlyRegularFilesAreRead) {
    // A FIFO would block a plain read for ever and a device never end: both are refused before a byte is read.
    const std::string fifo = ::testing::TempDir() + "rubble_scene_fifo";
    std::remove(fifo.c_str());
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    expectAll(errorOf([&] { loadScene(fifo); }),
              {fifo, "is not a regular file (a device, FIFO or socket), not a scene file"});
    expectAll(errorOf([] { loadObj("/dev/zero"); }), {"/dev/zero: is not a regular file", "not an OBJ file"});
    std::remove(fifo.c_str());
}

// A rotation's axis may be any non-zero vector the format can write and its angle any finite number: an axis of
// 1e31 (whose squared length overflows a float) or 1e-30 (underflows), and angles of 1e30, once gave a quaternion of
// length 0.92 that the World refused after the loader had accepted it (fuzzing: tests/data/fuzz/scene_loader/
// finding_rotation_axis_of_1e31.json). Each is the rotation its reduced angle names, of unit length.
TEST(SceneLoader, RotationsOfExtremeAxesAndAnglesAreUnitQuaternions) {
    const Scene s =
        loadScene(std::string(RUBBLE_TEST_DATA_DIR) + "/fuzz/scene_loader/finding_rotation_axis_of_1e31.json");
    ASSERT_EQ(s.bodies.size(), 3u);
    for (const SceneBody& b : s.bodies) {
        const Quat q = b.def.orientation;
        EXPECT_NEAR(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w, 1.0f, 1e-6f);
    }
    const Quat eighth = Quat::fromAxisAngle({0, 0, 1}, 3.14159265358979f / 4);
    EXPECT_NEAR(s.bodies[0].def.orientation.z, eighth.z, 1e-6f);
    EXPECT_NEAR(s.bodies[0].def.orientation.w, eighth.w, 1e-6f);
    World world{WorldSettings{}};
    EXPECT_EQ(instantiate(s, world).size(), 3u);
}

TEST(SceneLoader, SolverKnobsReachTheSettings) {
    const Scene s = parseScene(R"({"settings": {"position_correction": "soft_step", "contact_hertz": 45,
        "contact_damping_ratio": 2, "max_push_out_velocity": 1.5, "baumgarte": 0.1, "linear_slop": 0.001,
        "shock_propagation": true, "seed_resting_loads": false, "manifold_reuse_distance": 0.002}})",
                               "knobs.json");
    const SolverSettings& solver = s.settings.solver;
    EXPECT_EQ(solver.positionCorrection, PositionCorrection::SoftStep);
    EXPECT_FLOAT_EQ(solver.contactHertz, 45.0f);
    EXPECT_FLOAT_EQ(solver.contactDampingRatio, 2.0f);
    EXPECT_FLOAT_EQ(solver.maxPushOutVelocity, 1.5f);
    EXPECT_FLOAT_EQ(solver.baumgarte, 0.1f);
    EXPECT_FLOAT_EQ(solver.linearSlop, 0.001f);
    EXPECT_TRUE(solver.shockPropagation);
    EXPECT_FALSE(solver.seedRestingLoads);
    EXPECT_FLOAT_EQ(s.settings.manifoldReuseDistance, 0.002f);
    expectAll(errorOf([] { parseScene(R"({"settings": {"manifold_reuse_distance": -1}})", "r.json"); }),
              {"r.json", "/settings/manifold_reuse_distance"});
    expectAll(errorOf([] { parseScene(R"({"settings": {"contact_hertz": 0}})", "h.json"); }),
              {"h.json", "/settings/contact_hertz"});
    expectAll(errorOf([] { parseScene(R"({"settings": {"linear_slop": -0.01}})", "s.json"); }),
              {"s.json", "/settings/linear_slop"});
}

// The figures of a scene, against motion worked by hand: a ball coasting at 2 m/s along x without gravity for 1 s,
// between two static boxes at x = 0 (their positions span only x = 0, so the ball ends outside their box).
TEST(SceneFigures, MeterMeasuresACoastingBall) {
    const Scene scene = parseScene(R"({"settings": {"gravity": [0, 0, 0], "effects": []},
        "shapes": {"box": {"type": "box", "half_extents": [1, 1, 1]}, "ball": {"type": "sphere", "radius": 0.5}},
        "bodies": [{"shape": "box", "type": "static", "position": [0, -5, 0]},
                   {"shape": "box", "type": "static", "position": [0, 10, 0]},
                   {"shape": "ball", "position": [0, 3, 0], "velocity": [2, 0, 0]}],
        "figures": ["max_displacement", "max_speed", "final_speed", "moved", "escaped", "late_apex"]})",
                                   "coast.json");
    World world(scene.settings);
    const std::vector<BodyId> ids = instantiate(scene, world);
    SceneFigureMeter meter(scene, world, ids);
    for (int i = 0; i < 60; ++i) {
        world.step(1.0f / 60.0f);
        meter.record(world);
    }
    EXPECT_NEAR(meter.value(world, SceneFigure::MaxDisplacement), 2.0, 1e-5);
    EXPECT_NEAR(meter.value(world, SceneFigure::MaxSpeed), 2.0, 1e-6);
    EXPECT_NEAR(meter.value(world, SceneFigure::FinalSpeed), 2.0, 1e-6);
    EXPECT_EQ(meter.value(world, SceneFigure::Moved), 1.0);
    EXPECT_EQ(meter.value(world, SceneFigure::Escaped), 1.0);
    EXPECT_NEAR(meter.value(world, SceneFigure::LateApex), 3.0, 1e-6);
    EXPECT_TRUE(std::isnan(meter.value(world, SceneFigure::Tunnelled)));
    const std::vector<SceneFigureMeter::Result> results = meter.results(world);
    ASSERT_EQ(results.size(), 6u);
    EXPECT_EQ(results[0].text, "largest displacement from start: 2.0000 m");
    expectAll(errorOf([] { parseScene(R"({"figures": ["max_sped"]})", "f.json"); }),
              {"f.json", "/figures/0", "did you mean 'max_speed'"});
}

// Joints in a scene file: world anchors and axes become each body's local ones, a lattice joins grid neighbours at
// their midpoints (leaving static pairs out), and what cannot act is refused with its place in the file.
TEST(SceneJoints, JointsLoadInstantiateAndRefuseWhatCannotAct) {
    const Scene scene = parseScene(R"({"settings": {"effects": ["gravity", "rotation", "joints"]},
        "shapes": {"ball": {"type": "sphere", "radius": 0.25}},
        "bodies": [{"shape": "ball", "type": "static", "position": [0, 5, 0]},
                   {"shape": "ball", "position": [1, 5, 0], "rotation": {"axis": [0, 0, 1], "degrees": 90}},
                   {"shape": "ball", "position": [2, 5, 0]}],
        "joints": [{"type": "hinge", "bodies": [0, 1], "anchor": [0.5, 5, 0], "axis": [0, 0, 1],
                    "limit": {"lower": -1, "upper": 1}, "motor": {"speed": 2, "max_torque": 10}},
                   {"type": "distance", "bodies": [1, 2], "anchors": [[1, 5, 0], [2, 5, 0]]},
                   {"type": "spring", "bodies": [1, 2], "stiffness": 50, "rest_length": 1.5}],
        "figures": ["joint_stretch"]})",
                                   "joints.json");
    ASSERT_EQ(scene.joints.size(), 3u);
    World world(scene.settings);
    const std::vector<BodyId> ids = instantiate(scene, world);
    ASSERT_EQ(world.jointCount(), 3u);
    const auto& hinge = std::get<HingeJointDef>(scene.joints[0].def);
    EXPECT_TRUE(hinge.enableLimit && hinge.enableMotor);
    EXPECT_FLOAT_EQ(hinge.upperAngle, 1.0f);
    EXPECT_FLOAT_EQ(hinge.maxMotorTorque, 10.0f);
    EXPECT_FLOAT_EQ(*std::get<SpringJointDef>(scene.joints[2].def).restLength, 1.5f);
    // Nothing has moved: every joint holds its anchors together (the rod at its length).
    SceneFigureMeter meter(scene, world, ids);
    EXPECT_NEAR(meter.value(world, SceneFigure::JointStretch), 0.0, 1e-6);

    const Scene lattice = parseScene(R"({"shapes": {"ball": {"type": "sphere", "radius": 0.25}},
        "generators": [{"type": "grid", "shape": "ball", "count": [3, 2, 1], "spacing": 1, "origin": [0, -2, 0]},
                       {"type": "grid", "shape": "ball", "body_type": "static", "count": [3, 1, 1], "spacing": 1}],
        "joints": [{"type": "ball", "lattice": {"first": 0, "count": [3, 3, 1], "along": ["x", "y"]}}]})",
                                     "lattice.json");
    // Along x: 2 pairs in each of 3 rows but the static top row's; along y: 2 pairs in each of 3 columns.
    ASSERT_EQ(lattice.joints.size(), 2u * 2 + 2u * 3);
    EXPECT_EQ(lattice.joints[0].bodyA, 0u);
    EXPECT_EQ(lattice.joints[0].bodyB, 1u);
    EXPECT_NEAR(lattice.joints[0].anchorA.x, 0.5f, 1e-6f);

    const auto refused = [](const char* joints, std::vector<std::string> parts) {
        const std::string text = std::string(R"({"shapes": {"ball": {"type": "sphere", "radius": 0.25}},
            "bodies": [{"shape": "ball", "type": "static"}, {"shape": "ball", "type": "static", "position": [1, 0, 0]},
                       {"shape": "ball", "position": [2, 0, 0]}], "joints": )") +
                                 joints + "}";
        parts.insert(parts.begin(), "j.json");
        expectAll(errorOf([&] { parseScene(text, "j.json"); }), parts);
    };
    refused(R"([{"type": "bal", "bodies": [0, 2]}])", {"/joints/0/type", "did you mean 'ball'"});
    refused(R"([{"type": "ball", "bodies": [0, 3]}])", {"/joints/0/bodies/1"});
    refused(R"([{"type": "ball", "bodies": [2, 2]}])", {"/joints/0", "two different bodies"});
    refused(R"([{"type": "ball", "bodies": [0, 1]}])", {"/joints/0", "both static"});
    refused(R"([{"type": "ball", "bodies": [0, 2], "length": 1}])", {"/joints/0/length", "only distance joints"});
    refused(R"([{"type": "ball", "bodies": [0, 2], "anchors": [[0, 0, 0], [1, 0, 0]]}])", {"/joints/0/anchors"});
    refused(R"([{"type": "hinge", "bodies": [0, 2], "limit": {"lower": 1, "upper": -1}}])", {"/joints/0/limit"});
    refused(R"([{"type": "distance", "bodies": [0, 2], "anchor": [1, 0, 0]}])", {"/joints/0", "1 mm apart"});
    refused(R"([{"type": "ball", "lattice": {"first": 1, "count": [3, 1, 1], "along": ["x"]}}])",
            {"/joints/0/lattice", "do not exist"});
    expectAll(errorOf([] {
                  parseScene(R"({"settings": {"effects": ["gravity"]}, "shapes": {"b": {"type": "sphere", "radius": 1}},
                      "bodies": [{"shape": "b", "type": "static"}, {"shape": "b", "position": [3, 0, 0]}],
                      "joints": [{"type": "ball", "bodies": [0, 1]}]})",
                             "e.json");
              }),
              {"e.json", "/joints", "'joints'"});
}

// The runner's --set: keys named replace the scene's, the others stay, and a bad value is refused as in a file.
TEST(SceneLoader, SettingsOverridesReplaceOnlyTheKeysTheyName) {
    Scene s = parseScene(R"({"settings": {"substeps": 2, "velocity_iterations": 12}})", "base.json");
    overrideSettings(s, R"({"substeps": 4, "position_correction": "soft_step"})", "--set");
    EXPECT_EQ(s.settings.substeps, 4);
    EXPECT_EQ(s.settings.velocityIterations, 12);
    EXPECT_EQ(s.settings.solver.positionCorrection, PositionCorrection::SoftStep);
    expectAll(errorOf([&] { overrideSettings(s, R"({"substep": 4})", "--set substep=4"); }),
              {"--set substep=4", "/substep", "did you mean 'substeps'"});
    expectAll(errorOf([&] { overrideSettings(s, R"([4])", "--set x"); }), {"--set x", "must be an object"});
    EXPECT_EQ(s.settings.substeps, 4);
}

TEST(SceneLoader, SmallValidFileFillsEveryField) {
    const Scene s = loadScene(kData + "good_small.json");
    EXPECT_EQ(s.name, "small");
    EXPECT_EQ(s.steps, 5);
    EXPECT_EQ(s.settings.gravity, (Vec3{0, -10, 0}));
    EXPECT_EQ(s.settings.integrator, Integrator::Verlet);
    EXPECT_EQ(s.settings.broadPhase, BroadPhaseKind::Grid);
    EXPECT_EQ(s.settings.threads, 1);
    EXPECT_EQ(s.settings.effects, EffectSet::defaults());
    ASSERT_EQ(s.shapeNames, (std::vector<std::string>{"ground", "tri", "ball"}));
    const auto* tri = std::get_if<TriangleMeshDef>(&s.shapes[1]);
    ASSERT_NE(tri, nullptr);  // OBJ path resolved relative to the scene file
    EXPECT_EQ(tri->indices.size(), 3u);
    ASSERT_EQ(s.bodies.size(), 3u + 4u);
    const BodyDef& ball = s.bodies[2].def;
    EXPECT_EQ(s.bodies[2].shape, 2u);
    EXPECT_EQ(ball.type, BodyType::Dynamic);
    EXPECT_EQ(ball.position, (Vec3{1, 2, 3}));
    EXPECT_NEAR(ball.orientation.z, std::sqrt(0.5f), 1e-6f);
    EXPECT_NEAR(ball.orientation.w, std::sqrt(0.5f), 1e-6f);
    EXPECT_FLOAT_EQ(ball.material.friction, 0.05f);
    EXPECT_FLOAT_EQ(ball.material.density, 1000.0f);
    EXPECT_EQ(ball.linearVelocity, (Vec3{1, 0, 0}));
    EXPECT_EQ(ball.angularVelocity, (Vec3{0, 1, 0}));
    EXPECT_EQ(ball.filter.category, 2u);
    EXPECT_EQ(ball.filter.mask, 0xFFFFFFFFu);
    EXPECT_FLOAT_EQ(ball.linearDamping, 0.1f);
    EXPECT_FLOAT_EQ(ball.angularDamping, 0.2f);
    EXPECT_FLOAT_EQ(ball.gravityScale, 0.5f);
    EXPECT_EQ(ball.userData, 0xFFFFFFFFFFFFFFFFull);
    // Grid: y outermost, then x, then z; shapes cycled by creation index.
    const Vec3 expected[4] = {{10, 0, 0}, {11, 0, 0}, {10, 2, 0}, {11, 2, 0}};
    for (int n = 0; n < 4; ++n) {
        EXPECT_EQ(s.bodies[3 + n].def.position, expected[n]);
        EXPECT_EQ(s.bodies[3 + n].shape, n % 2 == 0 ? 2u : 0u);
        EXPECT_EQ(s.bodies[3 + n].def.type, BodyType::Kinematic);
    }
}

TEST(SceneLoader, DemoSceneLoads) {
    const Scene s = loadScene(kScenes + "hull_rain.json");
    EXPECT_EQ(s.bodies.size(), 6u + 6u * 4u * 6u + 50u);
    EXPECT_TRUE(std::holds_alternative<CompoundDef>(s.shapes[3]));
    EXPECT_EQ(std::get<CompoundDef>(s.shapes[3]).children.size(), 5u);
}

// ---------------------------------------------------------------------------------------------------------------
// The standard scenes against SCENES.md

/// SCENES.md's common settings. S1-S4 name their solver (8 + 2 iterations, one substep: Baumgarte, whose iteration
/// counts mean what Jolt's do); S5 and S6 ask for each engine's defaults.
enum class StandardSolver { EightPlusTwo, Defaults };
void expectStandardSettings(const Scene& s, int steps, StandardSolver solver = StandardSolver::EightPlusTwo) {
    EXPECT_EQ(s.steps, steps);
    EXPECT_FLOAT_EQ(s.settings.timeStep, 1.0f / 60.0f);
    const WorldSettings defaults;
    const bool standard = solver == StandardSolver::EightPlusTwo;
    EXPECT_EQ(s.settings.velocityIterations, standard ? 8 : defaults.velocityIterations);
    EXPECT_EQ(s.settings.positionIterations, standard ? 2 : defaults.positionIterations);
    EXPECT_EQ(s.settings.substeps, standard ? 1 : defaults.substeps);
    EXPECT_EQ(s.settings.solver.positionCorrection,
              standard ? PositionCorrection::Baumgarte : defaults.solver.positionCorrection);
    EXPECT_EQ(s.settings.threads, 0);  // not pinned: the runner's --threads decides
    EXPECT_FALSE(s.settings.effects.has(Effect::Sleeping));
}

void expectNear(Vec3 got, double x, double y, double z, const char* what, std::size_t index) {
    constexpr double tol = 1e-4;
    EXPECT_NEAR(got.x, x, tol) << what << " " << index;
    EXPECT_NEAR(got.y, y, tol) << what << " " << index;
    EXPECT_NEAR(got.z, z, tol) << what << " " << index;
}

void expectGround(const Scene& s, Vec3 halfExtents, Vec3 position) {
    ASSERT_FALSE(s.bodies.empty());
    const SceneBody& g = s.bodies[0];
    EXPECT_EQ(g.def.type, BodyType::Static);
    EXPECT_EQ(g.def.position, position);
    const auto* box = std::get_if<BoxDef>(&s.shapes.at(g.shape));
    ASSERT_NE(box, nullptr);
    EXPECT_EQ(box->halfExtents, halfExtents);
    EXPECT_FLOAT_EQ(g.def.material.friction, 0.6f);
}

/// A dynamic cube of half extent 0.5 with SCENES.md's material.
void expectCube(const Scene& s, const SceneBody& b, float density) {
    EXPECT_EQ(b.def.type, BodyType::Dynamic);
    const auto* box = std::get_if<BoxDef>(&s.shapes.at(b.shape));
    ASSERT_NE(box, nullptr);
    EXPECT_EQ(box->halfExtents, (Vec3{0.5f, 0.5f, 0.5f}));
    EXPECT_FLOAT_EQ(b.def.material.friction, 0.6f);
    EXPECT_FLOAT_EQ(b.def.material.restitution, 0.0f);
    EXPECT_FLOAT_EQ(b.def.material.density, density);
    EXPECT_EQ(b.def.orientation, Quat{});
    EXPECT_EQ(b.def.linearVelocity, Vec3{});
}

TEST(SceneStandard, S1Pyramid) {
    const Scene s = loadScene(kScenes + "s1_pyramid.json");
    expectStandardSettings(s, 600);
    ASSERT_EQ(s.bodies.size(), 2870u + 1u);
    expectGround(s, {100, 0.5f, 100}, {0, -0.5f, 0});
    std::size_t b = 1;
    for (int k = 0; k < 20; ++k) {
        const int n = 20 - k;
        for (int i = 0; i < n; ++i) {
            for (int j = 0; j < n; ++j, ++b) {
                expectNear(s.bodies[b].def.position, (i - (n - 1) / 2.0) * 1.0, 0.5 + k * 1.0,
                           (j - (n - 1) / 2.0) * 1.0, "cube", b);
                expectCube(s, s.bodies[b], 1000);
            }
        }
    }
    EXPECT_EQ(s.figures, std::vector<SceneFigure>{SceneFigure::MaxDisplacement});
}

TEST(SceneStandard, S2ManyPyramids) {
    const Scene s = loadScene(kScenes + "s2_pyramids.json");
    expectStandardSettings(s, 600);
    ASSERT_EQ(s.bodies.size(), 9100u + 1u);
    expectGround(s, {100, 0.5f, 100}, {0, -0.5f, 0});
    std::size_t b = 1;
    for (int a = 0; a < 10; ++a) {
        for (int c = 0; c < 10; ++c) {
            const double px = (a - 4.5) * 10, pz = (c - 4.5) * 10;
            for (int k = 0; k < 6; ++k) {
                const int n = 6 - k;
                for (int i = 0; i < n; ++i)
                    for (int j = 0; j < n; ++j, ++b) {
                        expectNear(s.bodies[b].def.position, px + (i - (n - 1) / 2.0), 0.5 + k,
                                   pz + (j - (n - 1) / 2.0), "cube", b);
                        expectCube(s, s.bodies[b], 1000);
                    }
            }
        }
    }
    EXPECT_EQ(b, s.bodies.size());
}

TEST(SceneStandard, S3PileOnMesh) {
    const Scene s = loadScene(kScenes + "s3_mesh_pile.json");
    expectStandardSettings(s, 600);
    ASSERT_EQ(s.bodies.size(), 4000u + 1u);
    EXPECT_EQ(s.figures, (std::vector<SceneFigure>{SceneFigure::MaxDisplacement, SceneFigure::Tunnelled}));

    const SceneBody& terrainBody = s.bodies[0];
    EXPECT_EQ(terrainBody.def.type, BodyType::Static);
    EXPECT_EQ(terrainBody.def.position, Vec3{});
    const auto* mesh = std::get_if<TriangleMeshDef>(&s.shapes.at(terrainBody.shape));
    ASSERT_NE(mesh, nullptr);
    ASSERT_EQ(mesh->vertices.size(), 101u * 101u);
    ASSERT_EQ(mesh->indices.size(), 3u * 20000u);
    // Every vertex on the 101 x 101 grid with SCENES.md's height; find each one by its x, z.
    std::vector<int> seen(101 * 101, 0);
    for (const Vec3& v : mesh->vertices) {
        const double x = std::round(v.x), z = std::round(v.z);
        ASSERT_EQ(v.x, x);
        ASSERT_EQ(v.z, z);
        ASSERT_TRUE(x >= -50 && x <= 50 && z >= -50 && z <= 50);
        EXPECT_NEAR(v.y, 2 * std::sin(x / 8) * std::cos(z / 8), 1e-5);
        ++seen[static_cast<int>(x + 50) * 101 + static_cast<int>(z + 50)];
    }
    for (const int c : seen) ASSERT_EQ(c, 1);
    // Each triangle: within one 1 m cell, counter-clockwise seen from +y, with the (x0,z0)-(x1,z1) diagonal as an edge.
    std::vector<int> perCell(100 * 100, 0);
    for (std::size_t t = 0; t < 20000; ++t) {
        const Vec3 p[3] = {mesh->vertices.at(mesh->indices[3 * t]), mesh->vertices.at(mesh->indices[3 * t + 1]),
                           mesh->vertices.at(mesh->indices[3 * t + 2])};
        const float x0 = std::min({p[0].x, p[1].x, p[2].x}), z0 = std::min({p[0].z, p[1].z, p[2].z});
        const Vec3 e1 = p[1] - p[0], e2 = p[2] - p[0];
        EXPECT_GT(e1.z * e2.x - e1.x * e2.z, 0.0f) << "triangle " << t << " is not counter-clockwise from +y";
        int diagonalCorners = 0;
        for (const Vec3& q : p) {
            EXPECT_TRUE(q.x - x0 == 0 || q.x - x0 == 1);
            EXPECT_TRUE(q.z - z0 == 0 || q.z - z0 == 1);
            if (q.x - x0 == q.z - z0) ++diagonalCorners;
        }
        EXPECT_EQ(diagonalCorners, 2) << "triangle " << t;
        ++perCell[static_cast<int>(x0 + 50) * 100 + static_cast<int>(z0 + 50)];
    }
    for (const int c : perCell) ASSERT_EQ(c, 2);

    for (int l = 0; l < 10; ++l)
        for (int i = 0; i < 20; ++i)
            for (int j = 0; j < 20; ++j) {
                const std::size_t b = static_cast<std::size_t>(l * 400 + i * 20 + j);
                const SceneBody& body = s.bodies[1 + b];
                expectNear(body.def.position, (i - 9.5) * 2.5, 6 + l * 2.5, (j - 9.5) * 2.5, "body", b);
                EXPECT_EQ(body.def.type, BodyType::Dynamic);
                EXPECT_EQ(body.def.orientation, Quat{});
                EXPECT_FLOAT_EQ(body.def.material.density, 1000.0f);
                EXPECT_FLOAT_EQ(body.def.material.friction, 0.6f);
                const ShapeDef& shape = s.shapes.at(body.shape);
                switch (b % 3) {
                    case 0:
                        ASSERT_TRUE(std::holds_alternative<SphereDef>(shape)) << b;
                        EXPECT_EQ(std::get<SphereDef>(shape).radius, 0.5f);
                        break;
                    case 1:
                        ASSERT_TRUE(std::holds_alternative<BoxDef>(shape)) << b;
                        EXPECT_EQ(std::get<BoxDef>(shape).halfExtents, (Vec3{0.5f, 0.5f, 0.5f}));
                        break;
                    default:
                        ASSERT_TRUE(std::holds_alternative<CapsuleDef>(shape)) << b;
                        EXPECT_EQ(std::get<CapsuleDef>(shape).radius, 0.3f);
                        EXPECT_EQ(std::get<CapsuleDef>(shape).halfHeight, 0.5f);
                }
            }
}

TEST(SceneStandard, S4Sparse) {
    const Scene s = loadScene(kScenes + "s4_sparse.json");
    expectStandardSettings(s, 100);
    EXPECT_EQ(s.settings.gravity, Vec3{});
    EXPECT_FALSE(s.settings.effects.has(Effect::Gravity));
    ASSERT_EQ(s.bodies.size(), 100000u);  // no ground
    std::mt19937 rng(42);
    std::uniform_real_distribution<float> pos(-100.0f, 100.0f), vel(-5.0f, 5.0f);
    for (std::size_t b = 0; b < s.bodies.size(); ++b) {
        const SceneBody& body = s.bodies[b];
        const float x = pos(rng), y = pos(rng), z = pos(rng);
        const float vx = vel(rng), vy = vel(rng), vz = vel(rng);
        ASSERT_EQ(body.def.position, (Vec3{x, y, z})) << b;
        ASSERT_EQ(body.def.linearVelocity, (Vec3{vx, vy, vz})) << b;
        if (b < 10) {
            const auto* sphere = std::get_if<SphereDef>(&s.shapes.at(body.shape));
            ASSERT_NE(sphere, nullptr);
            EXPECT_EQ(sphere->radius, 0.5f);
            EXPECT_EQ(body.def.type, BodyType::Dynamic);
            EXPECT_EQ(body.def.material.restitution, 1.0f);
            EXPECT_EQ(body.def.material.friction, 0.0f);
        }
    }
}

// The random generator's random_rotation: every orientation a unit quaternion, and uniform over the rotations,
// checked against what Haar measure predicts rather than against the formula: a rotated axis is uniform on the sphere
// (each component's mean 0, its square's mean 1/3), and the rotation matrix's trace 1 + 2 cos(angle) has mean 0 (the
// angle's density is (1 - cos) / pi). 20,000 draws: the means' standard errors are under 0.01, the bounds 0.03.
TEST(SceneLoader, RandomRotationsAreUnitAndUniform) {
    const std::string text = R"({"shapes": {"cube": {"type": "box", "half_extents": [0.5, 0.5, 0.5]}},
        "generators": [{"type": "random", "shape": "cube", "count": 20000, "seed": 7, "min": -10, "max": 10,
                        "random_rotation": true}]})";
    const Scene s = parseScene(text, "r.json");
    ASSERT_EQ(s.bodies.size(), 20000u);
    double axisMean[3] = {}, axisSquare[3] = {}, trace = 0;
    for (const SceneBody& b : s.bodies) {
        const Quat q = b.def.orientation;
        ASSERT_NEAR(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w, 1.0f, 1e-6f);
        const Vec3 x = rotate(q, {1, 0, 0}), y = rotate(q, {0, 1, 0}), z = rotate(q, {0, 0, 1});
        for (int a = 0; a < 3; ++a) axisMean[a] += x[a], axisSquare[a] += x[a] * x[a];
        trace += x.x + y.y + z.z;
    }
    const double n = static_cast<double>(s.bodies.size());
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(axisMean[a] / n, 0.0, 0.03) << a;
        EXPECT_NEAR(axisSquare[a] / n, 1.0 / 3.0, 0.03) << a;
    }
    EXPECT_NEAR(trace / n, 0.0, 0.03);
    // The same seed draws the same bodies; positions come first, as without rotations.
    EXPECT_EQ(parseScene(text, "r.json").bodies[123].def.orientation, s.bodies[123].def.orientation);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> pos(-10.0f, 10.0f);
    const float x = pos(rng), y = pos(rng), z = pos(rng);
    EXPECT_EQ(s.bodies[0].def.position, (Vec3{x, y, z}));
    expectAll(errorOf([&] {
                  parseScene(R"({"shapes": {"cube": {"type": "box", "half_extents": [0.5, 0.5, 0.5]}},
                      "generators": [{"type": "random", "shape": "cube", "count": 2, "min": 0, "max": 1,
                                      "rotation": {"axis": [0, 1, 0], "degrees": 30}, "random_rotation": true}]})",
                             "r.json");
              }),
              {"at /generators/0/random_rotation: give either 'rotation' or 'random_rotation'"});
    // The grid draws them too, one per body in creation order, from its own seed.
    const std::string grid = R"({"shapes": {"cube": {"type": "box", "half_extents": [0.5, 0.5, 0.5]}},
        "generators": [{"type": "grid", "shape": "cube", "count": [2, 2, 2], "spacing": 2, "random_rotation": true,
                        "seed": 5}]})";
    const Scene g = parseScene(grid, "g.json");
    ASSERT_EQ(g.bodies.size(), 8u);
    for (const SceneBody& b : g.bodies) {
        const Quat q = b.def.orientation;
        EXPECT_NEAR(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w, 1.0f, 1e-6f);
        EXPECT_NE(q, Quat{});
    }
    EXPECT_NE(g.bodies[0].def.orientation, g.bodies[1].def.orientation);
    expectAll(errorOf([&] {
                  parseScene(R"({"shapes": {"cube": {"type": "box", "half_extents": [0.5, 0.5, 0.5]}},
                      "generators": [{"type": "grid", "shape": "cube", "count": [1, 1, 1], "spacing": 1, "seed": 3}]})",
                             "g.json");
              }),
              {"at /generators/0/seed: a grid draws nothing without 'random_rotation'"});
}

TEST(SceneStandard, S5LargePyramid) {
    const Scene s = loadScene(kScenes + "s5_large_pyramid.json");
    expectStandardSettings(s, 200, StandardSolver::Defaults);
    ASSERT_EQ(s.bodies.size(), 5050u + 1u);
    expectGround(s, {400, 1, 400}, {0, -1, 0});
    const double h = 0.5;
    const int B = 100;
    std::size_t b = 1;
    for (int i = 0; i < B; ++i)
        for (int j = i; j < B; ++j, ++b) {
            expectNear(s.bodies[b].def.position, (i + 1) * h + 2 * (j - i) * h - h * B, (2 * i + 1) * h, 0, "cube", b);
            expectCube(s, s.bodies[b], 100);
        }
    EXPECT_EQ(b, s.bodies.size());
}

TEST(SceneStandard, S6ManyPyramids) {
    const Scene s = loadScene(kScenes + "s6_many_pyramids.json");
    expectStandardSettings(s, 100, StandardSolver::Defaults);
    ASSERT_EQ(s.bodies.size(), 10780u + 1u);
    const double h = 0.5, G = h * 14 * (10 + 1);
    EXPECT_EQ(G, 77.0);
    expectGround(s, {77, 1, 77}, {0, -1, 0});
    // Our order: columns (x) outer, rows (z) inner, each pyramid complete; SCENES.md leaves the order free.
    std::size_t b = 1;
    for (int c = 0; c < 14; ++c) {
        const double cx = -G + c * (2 * h * 10 + 2 * h) + 2 * h;
        for (int r = 0; r < 14; ++r) {
            const double z = -G + 2 * h + r * 2 * (G - 2 * h) / 13;
            for (int i = 0; i < 10; ++i)
                for (int j = i; j < 10; ++j, ++b) {
                    expectNear(s.bodies[b].def.position, (i + 1) * h + 2 * (j - i) * h + cx - 0.5, (2 * i + 1) * h, z,
                               "cube", b);
                    expectCube(s, s.bodies[b], 100);
                }
        }
    }
    EXPECT_EQ(b, s.bodies.size());
}

// ---------------------------------------------------------------------------------------------------------------
// Into a World

TEST(SceneRoundTrip, InstantiateCreatesEveryBodyWhereTheFileSays) {
    const Scene s = loadScene(kScenes + "s1_pyramid.json");
    World world(s.settings);
    const std::vector<BodyId> ids = instantiate(s, world);
    ASSERT_EQ(ids.size(), s.bodies.size());
    EXPECT_EQ(world.bodyCount(), 2871u);
    EXPECT_EQ(world.bodyType(ids[0]), BodyType::Static);
    // Body 1 + 2 * 20 + 3: bottom layer (n = 20), i = 2, j = 3.
    const Vec3 p = world.position(ids[1 + 2 * 20 + 3]);
    EXPECT_EQ(p, (Vec3{2 - 9.5f, 0.5f, 3 - 9.5f}));
    EXPECT_FLOAT_EQ(world.material(ids[44]).density, 1000.0f);
}

TEST(SceneRoundTrip, MixedShapesInstantiate) {
    const Scene s = loadScene(kScenes + "hull_rain.json");
    World world(s.settings);
    const std::vector<BodyId> ids = instantiate(s, world);
    EXPECT_EQ(world.bodyCount(), s.bodies.size());
    EXPECT_EQ(world.position(ids[5]), (Vec3{1, 8, 0}));
    EXPECT_EQ(world.userData(ids[3]), 2u);
}

TEST(SceneRoundTrip, ShapeBuilderErrorsNameTheFileAndShape) {
    Scene s;
    s.source = "made.json";
    s.shapeNames = {"ok", "bad"};
    s.shapes = {SphereDef{0.5f}, SphereDef{-1.0f}};
    World world;
    expectAll(errorOf([&] { instantiate(s, world); }), {"made.json: at /shapes/bad: "});

    Scene t;
    t.source = "t.json";
    t.shapeNames = {"ok"};
    t.shapes = {SphereDef{0.5f}};
    t.bodies.resize(1);
    t.bodies[0].shape = 3;
    World world2;
    expectAll(errorOf([&] { instantiate(t, world2); }), {"t.json: body 0"});
}

}  // namespace
}  // namespace rubble
