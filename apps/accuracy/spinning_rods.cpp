#include "spinning_rods.h"

#include <cmath>

namespace rubble::accuracy {

namespace {
constexpr float kRowSpacing = 2.0f;
constexpr float kWallThickness = 0.02f, kWallHalfHeight = 2.0f, kWallHalfWidth = 0.5f;
}  // namespace

SpinningRods buildSpinningRods(World& world, int copies) {
    SpinningRods out;
    const ShapeId wall = world.createShape(BoxDef{{0.5f * kWallThickness, kWallHalfHeight, kWallHalfWidth}});
    const ShapeId rod = world.createShape(BoxDef{{1.0f, 0.01f, 0.01f}});
    for (int c = 0; c < copies; ++c) {
        const float z = kRowSpacing * static_cast<float>(c);
        const float wallX = 0.3f + 0.6f * static_cast<float>(c % 7) / 6.0f;
        BodyDef wallDef;
        wallDef.type = BodyType::Static;
        wallDef.shape = wall;
        wallDef.position = {wallX + 0.5f * kWallThickness, 0, z};
        world.createBody(wallDef);
        BodyDef def;
        def.shape = rod;
        def.position = {0, 0, z};
        def.orientation = Quat::fromAxisAngle({0, 0, 1}, 1.5707964f);  // along y: both tips in front of the wall
        def.angularVelocity = {0, 0, 60.0f + 60.0f * static_cast<float>(c % 5) / 4.0f};
        out.rods.push_back(world.createBody(def));
        out.walls.push_back(wallX);
    }
    return out;
}

bool SpinningRods::tipPassedWall(const World& world, std::size_t i) const {
    const Transform t = world.transform(rods[i]);
    const float far = walls[i] + kWallThickness, z = kRowSpacing * static_cast<float>(i);
    for (const float end : {-1.0f, 1.0f}) {
        const Vec3 tip = apply(t, {end, 0, 0}), centre = t.position;
        if (!(tip.x > far)) continue;
        // Where the segment from the centre to the tip crosses the far face's plane.
        const float f = centre.x < far ? (far - centre.x) / (tip.x - centre.x) : 0.0f;
        const Vec3 crossing = centre + (tip - centre) * f;
        if (std::fabs(crossing.y) <= kWallHalfHeight && std::fabs(crossing.z - z) <= kWallHalfWidth) return true;
    }
    return false;
}

}  // namespace rubble::accuracy
