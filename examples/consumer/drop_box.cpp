// Uses Rubble as an installed package: builds a world through the API and another from a scene file's text, steps
// both, and checks that a dropped box comes to rest on the ground. Exit code 0 when it does.
#include <cmath>
#include <cstdio>

#include "rubble/scene.h"
#include "rubble/world.h"

int main() {
    using namespace rubble;
    World world;
    BodyDef ground;
    ground.type = BodyType::Static;
    ground.shape = world.createShape(BoxDef{{10, 0.5f, 10}});
    ground.position = {0, -0.5f, 0};
    world.createBody(ground);
    BodyDef box;
    box.shape = world.createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    box.position = {0, 2, 0};
    const BodyId id = world.createBody(box);
    for (int step = 0; step < 120; ++step) world.step(1.0f / 60.0f);
    const float height = world.position(id).y;

    const Scene scene = parseScene(R"({
        "name": "one ball", "steps": 60,
        "shapes": {"ground": {"type": "box", "half_extents": [5, 0.5, 5]}, "ball": {"type": "sphere", "radius": 0.5}},
        "bodies": [{"shape": "ground", "type": "static", "position": [0, -0.5, 0]},
                   {"shape": "ball", "position": [0, 1, 0]}]})",
                                   "inline scene");
    World fromScene(scene.settings);
    const std::vector<BodyId> bodies = instantiate(scene, fromScene);
    for (int step = 0; step < scene.steps; ++step) fromScene.step(scene.settings.timeStep);
    const float ball = fromScene.position(bodies[1]).y;

    std::printf("box at rest %.3f m up (0.5 expected), ball %.3f m up (0.5 expected)\n", height, ball);
    return std::fabs(height - 0.5f) < 0.02f && std::fabs(ball - 0.5f) < 0.02f ? 0 : 1;
}
