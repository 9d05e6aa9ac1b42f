#include "world/effects.h"

namespace rubble::detail {

void MovingMaterialCounts::count(const MovingBodies& m, std::uint32_t i, const std::vector<Shape>& shapes, int sign) {
    if (m.flags[i] & kFlagFrozen) return;
    const auto add = [sign](std::uint32_t& n, bool holds) { n += static_cast<std::uint32_t>(holds ? sign : 0); };
    add(withGravityScale, m.gravityScale[i] != 0);
    add(withFriction, m.friction[i] > 0);
    add(withRestitution, m.restitution[i] > 0);
    add(withDamping, m.linearDamping[i] != 0 || m.angularDamping[i] != 0);
    const bool dynamic = !(m.flags[i] & kFlagKinematic);
    const bool round = shapes[m.shape[i]].kind == ShapeKind::Sphere;
    add(turnable, dynamic && (!round || m.friction[i] > 0));
}

MovingMaterialCounts countMovingMaterials(const MovingBodies& m, const std::vector<Shape>& shapes) {
    MovingMaterialCounts counts;
    for (std::uint32_t i = 0; i < m.size(); ++i) counts.count(m, i, shapes, 1);
    return counts;
}

EffectSet resolveEffects(EffectSet declared, const WorldSettings& settings, const MovingBodies& moving,
                         const MovingMaterialCounts& counts, const StaticMaterialCounts& statics, bool anyJoints,
                         bool& anyDamping) {
    EffectSet active = declared;

    const bool gravityVector = settings.gravity.x != 0 || settings.gravity.y != 0 || settings.gravity.z != 0;
    const bool anyGravityScale = counts.withGravityScale > 0;
    bool anyFriction = counts.withFriction > 0, anyRestitution = counts.withRestitution > 0;
    bool canTurn = counts.turnable > 0;
    anyDamping = counts.withDamping > 0;
    if (!canTurn && !anyJoints && declared.has(Effect::Rotation))
        for (std::uint32_t i = 0, n = moving.size(); i < n && !canTurn; ++i) {
            if (moving.flags[i] & kFlagFrozen) continue;
            canTurn = moving.wx[i] != 0 || moving.wy[i] != 0 || moving.wz[i] != 0 || moving.tx[i] != 0 ||
                      moving.ty[i] != 0 || moving.tz[i] != 0;
        }
    anyFriction |= statics.withFriction > 0;
    anyRestitution |= statics.withRestitution > 0;

    if (!(gravityVector && anyGravityScale)) active = active.without(Effect::Gravity);
    if (!canTurn && !anyJoints) active = active.without(Effect::Rotation);
    if (!anyFriction) active = active.without(Effect::Friction);
    if (!anyRestitution) active = active.without(Effect::Restitution);
    if (!anyJoints) active = active.without(Effect::Joints);
    return active;
}

}  // namespace rubble::detail
