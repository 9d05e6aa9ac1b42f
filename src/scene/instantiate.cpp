// Turning a loaded Scene into shapes, bodies and joints of a World.
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "rubble/error.h"
#include "rubble/scene.h"
#include "rubble/world.h"
#include "scene/generators.h"

namespace rubble {

std::vector<BodyId> instantiate(const Scene& scene, World& world) {
    const std::string& file = scene.source.empty() ? scene.name : scene.source;
    if (scene.shapeNames.size() != scene.shapes.size())
        throw Error(file + ": scene has " + std::to_string(scene.shapes.size()) + " shapes but " +
                    std::to_string(scene.shapeNames.size()) + " shape names");

    // Every shape is built, used or not, so a bad definition is reported whatever the bodies use. The loader
    // checked what is cheap; what the shape builder refuses (say, a degenerate hull) is reported here with the
    // place in the file it came from.
    std::vector<ShapeId> shapes;
    shapes.reserve(scene.shapes.size());
    for (std::size_t i = 0; i < scene.shapes.size(); ++i) {
        try {
            shapes.push_back(world.createShape(scene.shapes[i]));
        } catch (const Error& e) {
            throw Error(file + ": at /shapes/" + scene_detail::jsonPointerToken(scene.shapeNames[i]) + ": " + e.what());
        }
    }

    std::vector<BodyId> bodies;
    bodies.reserve(scene.bodies.size());
    for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
        const SceneBody& b = scene.bodies[i];
        if (b.shape >= shapes.size())
            throw Error(file + ": body " + std::to_string(i) + " names shape " + std::to_string(b.shape) +
                        ", but the scene has " + std::to_string(shapes.size()) + " shapes");
        BodyDef def = b.def;
        def.shape = shapes[b.shape];
        try {
            bodies.push_back(world.createBody(def));
        } catch (const Error& e) {
            // Scene bodies keep no JSON path (generated ones have none); name the body by its creation index.
            throw Error(file + ": body " + std::to_string(i) + " (shape '" + scene.shapeNames[b.shape] +
                        "'): " + e.what());
        }
    }
    // Joints: world anchors and axes into each body's frame (the bodies stand where the file put them).
    for (std::size_t i = 0; i < scene.joints.size(); ++i) {
        const SceneJoint& j = scene.joints[i];
        if (j.bodyA >= bodies.size() || j.bodyB >= bodies.size())
            throw Error(file + ": joint " + std::to_string(i) + " names bodies " + std::to_string(j.bodyA) + " and " +
                        std::to_string(j.bodyB) + ", but the scene has " + std::to_string(bodies.size()));
        const Transform a = world.transform(bodies[j.bodyA]), b = world.transform(bodies[j.bodyB]);
        try {
            std::visit(
                [&](auto def) {
                    def.bodyA = bodies[j.bodyA];
                    def.bodyB = bodies[j.bodyB];
                    def.localAnchorA = applyInverse(a, j.anchorA);
                    def.localAnchorB = applyInverse(b, j.anchorB);
                    if constexpr (std::is_same_v<decltype(def), HingeJointDef>) {
                        def.localAxisA = rotate(conjugate(a.rotation), j.axis);
                        def.localAxisB = rotate(conjugate(b.rotation), j.axis);
                    }
                    world.createJoint(def);
                },
                j.def);
        } catch (const Error& e) {
            throw Error(file + ": joint " + std::to_string(i) + " (bodies " + std::to_string(j.bodyA) + " and " +
                        std::to_string(j.bodyB) + "): " + e.what());
        }
    }
    return bodies;
}

}  // namespace rubble
