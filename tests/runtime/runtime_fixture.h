#pragma once
// Small worlds for the runtime tests: a floor and a grid of boxes above it.
#include "rubble/world.h"

namespace rubble::test {

inline World boxesOnFloor(int perSide, int layers, int threads = 2) {
    WorldSettings settings;
    settings.threads = threads;
    World world(settings);
    const ShapeId floor = world.createShape(BoxDef{{50, 0.5f, 50}});
    const ShapeId box = world.createShape(BoxDef{{0.25f, 0.25f, 0.25f}});
    BodyDef ground;
    ground.type = BodyType::Static;
    ground.shape = floor;
    ground.position = {0, -0.5f, 0};
    world.createBody(ground);
    for (int l = 0; l < layers; ++l)
        for (int i = 0; i < perSide; ++i)
            for (int k = 0; k < perSide; ++k) {
                BodyDef def;
                def.shape = box;
                def.position = {0.6f * static_cast<float>(i), 0.26f + 0.52f * static_cast<float>(l),
                                0.6f * static_cast<float>(k)};
                world.createBody(def);
            }
    return world;
}

}  // namespace rubble::test
