// The joints block of World's API (include/rubble/world.h): validation at the boundary and the joint store's
// handles. The joints are solved in the solver stage (src/solver/joint_solver.cpp).
#include <cmath>
#include <string>

#include "world/world_impl.h"

namespace rubble {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kMinRodLength = 1e-3f;

std::string describe(BodyId id) {
    return "(index " + std::to_string(id.index) + ", generation " + std::to_string(id.generation) + ")";
}

std::string describe(JointId id) {
    return "(index " + std::to_string(id.index) + ", generation " + std::to_string(id.generation) + ")";
}

const detail::Joint& jointOf(const World::Impl& w, JointId id, const char* where) {
    const detail::Joint* j = w.joints.find(id);
    if (!j) {
        if (id.isNull()) fail(where, "the joint handle is null");
        fail(where, "joint handle " + describe(id) + " is stale or not from this world");
    }
    return *j;
}

void requireBreakLimit(const char* where, const char* name, float f) {
    if (std::isnan(f) || f <= 0)
        fail(where, std::string(name) + " must be > 0 or infinity (got " + std::to_string(f) + ")");
}

/// Validates what every joint shares and fills the stored joint's common part.
detail::Joint baseJoint(const World::Impl& w, const JointBase& def, JointType type, const char* where) {
    for (const auto& [id, name] : {std::pair{def.bodyA, "bodyA"}, std::pair{def.bodyB, "bodyB"}}) {
        if (id.isNull()) fail(where, std::string("def.") + name + " is null");
        if (!w.bodies.find(id))
            fail(where, std::string("def.") + name + " " + describe(id) + " is stale or not from this world");
    }
    if (def.bodyA == def.bodyB)
        fail(where, "def.bodyA and def.bodyB are the same body " + describe(def.bodyA) +
                        ": a joint connects two bodies (use a static body to anchor to the world)");
    if (w.bodies.find(def.bodyA)->set == BodySet::Static && w.bodies.find(def.bodyB)->set == BodySet::Static)
        fail(where, "def.bodyA and def.bodyB are both static: a joint needs a body that can move");
    requireFinite(where, "def.localAnchorA", def.localAnchorA);
    requireFinite(where, "def.localAnchorB", def.localAnchorB);
    requireBreakLimit(where, "def.breakForce", def.breakForce);
    requireBreakLimit(where, "def.breakTorque", def.breakTorque);
    detail::Joint j;
    j.type = type;
    j.bodyA = def.bodyA, j.bodyB = def.bodyB;
    j.localAnchorA = def.localAnchorA, j.localAnchorB = def.localAnchorB;
    j.collideConnected = def.collideConnected;
    j.breakForce = def.breakForce, j.breakTorque = def.breakTorque;
    return j;
}

Transform poseOf(const World& world, BodyId id) { return world.transform(id); }

float anchorDistance(const World& world, const JointBase& def) {
    return length(apply(poseOf(world, def.bodyB), def.localAnchorB) -
                  apply(poseOf(world, def.bodyA), def.localAnchorA));
}

Vec3 unitAxis(const char* where, const char* name, Vec3 axis) {
    requireFinite(where, name, axis);
    const float len = length(axis);
    if (!(len > 1e-6f)) fail(where, std::string(name) + " must not be zero " + describe(axis));
    return axis * (1.0f / len);
}

}  // namespace

JointId World::createJoint(const DistanceJointDef& def) {
    static constexpr const char* kWhere = "World::createJoint(DistanceJointDef)";
    Impl& w = *impl_;
    detail::Joint j = baseJoint(w, def, JointType::Distance, kWhere);
    if (def.length) {
        requireFinite(kWhere, "def.length", *def.length);
        if (*def.length < kMinRodLength)
            fail(kWhere, "def.length must be >= 0.001 m (got " + std::to_string(*def.length) +
                             "); use a ball joint for coincident anchors");
        j.length = *def.length;
    } else {
        j.length = anchorDistance(*this, def);
        if (j.length < kMinRodLength)
            fail(kWhere, "the anchors are " + std::to_string(j.length) +
                             " m apart, the rod length must be >= 0.001 m; use a ball joint for coincident anchors");
    }
    w.effectsDirty = true;
    return w.joints.add(j);
}

JointId World::createJoint(const SpringJointDef& def) {
    static constexpr const char* kWhere = "World::createJoint(SpringJointDef)";
    Impl& w = *impl_;
    detail::Joint j = baseJoint(w, def, JointType::Spring, kWhere);
    requireNonNegative(kWhere, "def.stiffness", def.stiffness);
    requireNonNegative(kWhere, "def.damping", def.damping);
    if (def.restLength) requireNonNegative(kWhere, "def.restLength", *def.restLength);
    j.stiffness = def.stiffness, j.damping = def.damping;
    j.length = def.restLength ? *def.restLength : anchorDistance(*this, def);
    w.effectsDirty = true;
    return w.joints.add(j);
}

JointId World::createJoint(const BallJointDef& def) {
    Impl& w = *impl_;
    const detail::Joint j = baseJoint(w, def, JointType::Ball, "World::createJoint(BallJointDef)");
    w.effectsDirty = true;
    return w.joints.add(j);
}

JointId World::createJoint(const HingeJointDef& def) {
    static constexpr const char* kWhere = "World::createJoint(HingeJointDef)";
    Impl& w = *impl_;
    detail::Joint j = baseJoint(w, def, JointType::Hinge, kWhere);
    j.localAxisA = unitAxis(kWhere, "def.localAxisA", def.localAxisA);
    j.localAxisB = unitAxis(kWhere, "def.localAxisB", def.localAxisB);
    if (def.enableLimit) {
        requireFinite(kWhere, "def.lowerAngle", def.lowerAngle);
        requireFinite(kWhere, "def.upperAngle", def.upperAngle);
        if (def.lowerAngle > def.upperAngle)
            fail(kWhere, "def.lowerAngle (" + std::to_string(def.lowerAngle) + ") is above def.upperAngle (" +
                             std::to_string(def.upperAngle) + ")");
        if (def.lowerAngle < -kPi || def.upperAngle > kPi)
            fail(kWhere, "hinge limits must lie in [-pi, pi] (got [" + std::to_string(def.lowerAngle) + ", " +
                             std::to_string(def.upperAngle) + "])");
    }
    requireFinite(kWhere, "def.motorSpeed", def.motorSpeed);
    requireNonNegative(kWhere, "def.maxMotorTorque", def.maxMotorTorque);
    j.enableLimit = def.enableLimit;
    j.lowerAngle = def.lowerAngle, j.upperAngle = def.upperAngle;
    j.enableMotor = def.enableMotor;
    j.motorSpeed = def.motorSpeed, j.maxMotorTorque = def.maxMotorTorque;
    j.referenceRotation = conjugate(orientation(def.bodyA)) * orientation(def.bodyB);
    w.effectsDirty = true;
    return w.joints.add(j);
}

void World::destroyJoint(JointId id) {
    Impl& w = *impl_;
    jointOf(w, id, "World::destroyJoint");
    w.joints.remove(id);
    w.effectsDirty = true;
}

bool World::isValid(JointId id) const { return impl_->joints.find(id) != nullptr; }

std::uint32_t World::jointCount() const { return impl_->joints.size(); }

JointType World::jointType(JointId id) const { return jointOf(*impl_, id, "World::jointType").type; }

std::pair<BodyId, BodyId> World::jointBodies(JointId id) const {
    const detail::Joint& j = jointOf(*impl_, id, "World::jointBodies");
    return {j.bodyA, j.bodyB};
}

bool World::isJointBroken(JointId id) const { return jointOf(*impl_, id, "World::isJointBroken").broken; }

std::vector<JointId> World::takeBrokenJoints() {
    std::vector<JointId> out;
    out.swap(impl_->joints.brokenReports());
    return out;
}

Vec3 World::jointReactionForce(JointId id) const {
    return jointOf(*impl_, id, "World::jointReactionForce").reactionForce;
}

Vec3 World::jointReactionTorque(JointId id) const {
    return jointOf(*impl_, id, "World::jointReactionTorque").reactionTorque;
}

float World::hingeAngle(JointId id) const {
    static constexpr const char* kWhere = "World::hingeAngle";
    const detail::Joint& j = jointOf(*impl_, id, kWhere);
    if (j.type != JointType::Hinge) fail(kWhere, "joint " + describe(id) + " is not a hinge");
    return detail::hingeAngle(j, impl_->bodies);
}

void World::setHingeMotor(JointId id, bool enable, float speed, float maxTorque) {
    static constexpr const char* kWhere = "World::setHingeMotor";
    detail::Joint* j = impl_->joints.find(id);
    jointOf(*impl_, id, kWhere);
    if (j->type != JointType::Hinge) fail(kWhere, "joint " + describe(id) + " is not a hinge");
    requireFinite(kWhere, "speed", speed);
    requireNonNegative(kWhere, "maxTorque", maxTorque);
    j->enableMotor = enable;
    j->motorSpeed = speed;
    j->maxMotorTorque = maxTorque;
    if (!enable) j->motorImpulse = 0;
}

}  // namespace rubble
