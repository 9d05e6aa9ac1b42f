#pragma once
// Effects: which physical effects a step simulates. The scene declares a set; the engine drops the effects that
// the world's content cannot show, so that the step is assembled only from the stages it needs.
#include <cstdint>
#include <vector>

#include "rubble/settings.h"
#include "shapes/shape.h"
#include "storage/body_storage.h"

namespace rubble::detail {

/// How many static bodies have a non-zero friction and restitution coefficient: kept as bodies are created, destroyed
/// and given materials, so that a world of a million static bodies does not scan them whenever a body comes or goes.
struct StaticMaterialCounts {
    std::uint32_t withFriction = 0;
    std::uint32_t withRestitution = 0;

    /// A static body of this material came (+1) or went (-1).
    void count(float friction, float restitution, int sign) {
        withFriction += static_cast<std::uint32_t>(friction > 0 ? sign : 0);
        withRestitution += static_cast<std::uint32_t>(restitution > 0 ? sign : 0);
    }
};

/// What the moving bodies hold of the properties that decide the effects: kept as bodies are created, destroyed,
/// given materials and frozen, so that a world of a million bodies does not scan them all whenever one comes or
/// goes (at a million, that scan cost the next step 3-5 ms). A frozen body holds nothing.
struct MovingMaterialCounts {
    std::uint32_t withGravityScale = 0;
    std::uint32_t withFriction = 0;
    std::uint32_t withRestitution = 0;
    std::uint32_t withDamping = 0;
    /// Dynamic bodies that contacts can turn: any but a sphere, or a sphere with friction.
    std::uint32_t turnable = 0;

    /// Moving body i, as its row holds it now, came (+1) or is about to go or change (-1).
    void count(const MovingBodies& m, std::uint32_t i, const std::vector<Shape>& shapes, int sign);
    friend bool operator==(const MovingMaterialCounts&, const MovingMaterialCounts&) = default;
};

/// The counts of every moving body from scratch, for tests of the kept ones.
MovingMaterialCounts countMovingMaterials(const MovingBodies& m, const std::vector<Shape>& shapes);

/// Declared effects less those the content cannot show:
/// - gravity: needs a non-zero gravity vector and a moving body with a non-zero gravity scale;
/// - rotation: needs a moving body that can turn: one spinning or under torque now, or a dynamic body that
///   contacts can turn (any non-sphere, or a sphere with friction);
/// - friction / restitution: need a body with a non-zero coefficient;
/// - joints: need a joint that has not broken (`anyJoints`); a joint can turn its bodies, so it keeps rotation;
/// - sleeping and continuous collision are choices, kept as declared.
/// `anyDamping` reports whether a moving body has damping (which makes the velocity stage necessary even without
/// gravity, forces or rotation). The bodies are scanned only for rotation declared in a world where nothing but a
/// spin or a torque can turn a body (frictionless spheres, S4).
EffectSet resolveEffects(EffectSet declared, const WorldSettings& settings, const MovingBodies& moving,
                         const MovingMaterialCounts& counts, const StaticMaterialCounts& statics, bool anyJoints,
                         bool& anyDamping);

}  // namespace rubble::detail
