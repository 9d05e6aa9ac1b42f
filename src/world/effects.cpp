#include "world/effects.h"

namespace rubble::detail {

EffectSet resolveEffects(EffectSet declared, const WorldSettings& settings, const MovingBodies& moving,
                         const StaticMaterialCounts& statics, const std::vector<Shape>& shapes, bool anyJoints,
                         bool& anyDamping) {
    EffectSet active = declared;

    const bool gravityVector = settings.gravity.x != 0 || settings.gravity.y != 0 || settings.gravity.z != 0;
    bool anyGravityScale = false, canTurn = false, anyFriction = false, anyRestitution = false;
    anyDamping = false;
    for (std::uint32_t i = 0, n = moving.size(); i < n; ++i) {
        if (moving.flags[i] & kFlagFrozen) continue;
        anyGravityScale |= moving.gravityScale[i] != 0;
        anyFriction |= moving.friction[i] > 0;
        anyRestitution |= moving.restitution[i] > 0;
        anyDamping |= moving.linearDamping[i] != 0 || moving.angularDamping[i] != 0;
        const bool spinning = moving.wx[i] != 0 || moving.wy[i] != 0 || moving.wz[i] != 0;
        const bool torqued = moving.tx[i] != 0 || moving.ty[i] != 0 || moving.tz[i] != 0;
        const bool dynamic = !(moving.flags[i] & kFlagKinematic);
        const bool round = shapes[moving.shape[i]].kind == ShapeKind::Sphere;
        canTurn |= spinning || torqued || (dynamic && (!round || moving.friction[i] > 0));
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
