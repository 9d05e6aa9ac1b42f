// The world: input validation at the API boundary, body and shape storage, settings. The step is in step.cpp.
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>

#include "core/cpu_check.h"
#include "rubble/error.h"
#include "rubble/limits.h"
#include "world/world_impl.h"

namespace rubble {
namespace detail {

void rotateDiagonal(Quat r, Vec3 d, float out[6]) {
    const Vec3 c0 = rotate(r, {1, 0, 0}), c1 = rotate(r, {0, 1, 0}), c2 = rotate(r, {0, 0, 1});
    auto entry = [&](int i, int j) {
        const float ri[3] = {c0[i], c1[i], c2[i]};
        const float rj[3] = {c0[j], c1[j], c2[j]};
        return ri[0] * d.x * rj[0] + ri[1] * d.y * rj[1] + ri[2] * d.z * rj[2];
    };
    out[0] = entry(0, 0);
    out[1] = entry(1, 1);
    out[2] = entry(2, 2);
    out[3] = entry(0, 1);
    out[4] = entry(0, 2);
    out[5] = entry(1, 2);
}

}  // namespace detail

namespace {

void validateMaterial(const char* where, const Material& m) {
    requireNonNegative(where, "material.friction", m.friction);
    requireFinite(where, "material.restitution", m.restitution);
    if (m.restitution < 0 || m.restitution > 1)
        fail(where, "material.restitution must be in [0, 1] (got " + std::to_string(m.restitution) + ")");
    requireWithin(where, "material.density", m.density, limits::kMinDensity, limits::kMaxDensity, "kg/m^3");
}

const char* bodyTypeName(BodyType t) {
    switch (t) {
        case BodyType::Static:
            return "static";
        case BodyType::Kinematic:
            return "kinematic";
        case BodyType::Dynamic:
            return "dynamic";
    }
    return "?";
}

std::uint64_t mix(std::uint64_t h, std::uint64_t v) {
    // FNV-1a over 64-bit words with a final avalanche per word: cheap, and any flipped bit changes the hash.
    h ^= v;
    h *= 0x100000001b3ull;
    h ^= h >> 29;
    return h;
}

std::uint64_t bitsOf(float f) {
    std::uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return u;
}

}  // namespace

World::World(const WorldSettings& settings) {
    // Also what links the check into a static core (its load-time twin lives in the same file).
    detail::requireCpuFeatures();
    if (settings.threads < 0)
        fail("World", "settings.threads must be >= 0 (got " + std::to_string(settings.threads) + ")");
    impl_ = std::make_unique<Impl>(settings);
    setSettings(settings);
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

// ---------------------------------------------------------------------------------------------------------------
// Shapes

ShapeId World::createShape(const ShapeDef& def) {
    Shape shape = detail::buildShape(def);
    Impl& w = *impl_;
    const ShapeId id = w.shapeIds.acquire();
    const std::uint32_t index = id.index;
    if (index == w.shapes.size()) {
        w.shapes.push_back(std::move(shape));
        w.shapeUsers.push_back(0);
    } else {
        w.shapes[index] = std::move(shape);
    }
    if (!w.shapes[index].staticOnly()) w.shapeBounds.set(index, detail::shapeBoundsInfo(w.shapes[index]));
    w.shapeUsers[index] = 0;
    return id;
}

void World::destroyShape(ShapeId id) {
    Impl& w = *impl_;
    w.shapeOf(id, "World::destroyShape");
    if (w.shapeUsers[id.index] != 0)
        fail("World::destroyShape", "shape " + std::to_string(id.index) + " is still used by " +
                                        std::to_string(w.shapeUsers[id.index]) + " bodies");
    w.shapes[id.index] = Shape{};
    w.shapeIds.release(id.index);
}

bool World::isValid(ShapeId id) const { return impl_->shapeIds.contains(id); }

MassProperties World::shapeMassProperties(ShapeId id) const {
    return impl_->shapeOf(id, "World::shapeMassProperties").unitMass;
}

// ---------------------------------------------------------------------------------------------------------------
// Bodies

BodyId World::createBody(const BodyDef& def) {
    static constexpr const char* kWhere = "World::createBody";
    Impl& w = *impl_;
    const Shape& shape = w.shapeOf(def.shape, kWhere);
    if (def.type != BodyType::Static && def.type != BodyType::Kinematic && def.type != BodyType::Dynamic)
        fail(kWhere, "BodyDef.type is not a valid BodyType (" + std::to_string(static_cast<int>(def.type)) + ")");
    if (shape.staticOnly() && def.type != BodyType::Static)
        fail(kWhere, std::string("a ") + bodyTypeName(def.type) + " body cannot use shape " +
                         std::to_string(def.shape.index) +
                         ": triangle meshes and heightfields are static-only (use a hull or compound)");
    requireInWorld(kWhere, "BodyDef.position", def.position);
    const Quat q = requireUnit(kWhere, "BodyDef.orientation", def.orientation);
    requireFinite(kWhere, "BodyDef.linearVelocity", def.linearVelocity);
    requireFinite(kWhere, "BodyDef.angularVelocity", def.angularVelocity);
    validateMaterial(kWhere, def.material);
    requireNonNegative(kWhere, "BodyDef.linearDamping", def.linearDamping);
    requireNonNegative(kWhere, "BodyDef.angularDamping", def.angularDamping);
    requireFinite(kWhere, "BodyDef.gravityScale", def.gravityScale);
    if (def.type == BodyType::Static && (def.linearVelocity != Vec3{} || def.angularVelocity != Vec3{}))
        fail(kWhere, "a static body cannot have a velocity (use a kinematic body to move it)");
    if (w.bodies.count() >= limits::kMaxBodies)
        fail(kWhere,
             "the world holds " + std::to_string(w.bodies.count()) + " bodies, the most it may (docs/limits.md)");

    w.queries.bodiesChanged();
    std::uint32_t i;
    if (def.type == BodyType::Static) {
        const BodyId id = w.bodies.allocate(BodySet::Static, i);
        detail::StaticBodies& s = w.bodies.statics;
        s.px[i] = def.position.x, s.py[i] = def.position.y, s.pz[i] = def.position.z;
        s.qx[i] = q.x, s.qy[i] = q.y, s.qz[i] = q.z, s.qw[i] = q.w;
        s.friction[i] = def.material.friction;
        s.restitution[i] = def.material.restitution;
        w.staticMaterials.count(def.material.friction, def.material.restitution, 1);
        s.density[i] = def.material.density;
        s.shape[i] = def.shape.index;
        s.filterCategory[i] = def.filter.category;
        s.filterMask[i] = def.filter.mask;
        s.userData[i] = def.userData;
        s.flags[i] = static_cast<std::uint8_t>((def.contactEvents ? detail::kFlagContactEvents : 0) |
                                               (def.sensor ? detail::kFlagSensor : 0) |
                                               (def.contactResponse ? 0 : detail::kFlagNoResponse));
        w.countEventFlags(s.flags[i], 1);
        w.shapeUsers[def.shape.index] += 1;
        w.effectsDirty = true;
        w.broadPhase.staticAdded(id.index, w.bodies, w.shapes, *w.pool);
        return id;
    }

    const BodyId id = w.bodies.allocate(BodySet::Moving, i);
    MovingBodies& m = w.bodies.moving;
    const bool kinematic = def.type == BodyType::Kinematic;
    m.qx[i] = q.x, m.qy[i] = q.y, m.qz[i] = q.z, m.qw[i] = q.w;
    m.vx[i] = def.linearVelocity.x, m.vy[i] = def.linearVelocity.y, m.vz[i] = def.linearVelocity.z;
    m.wx[i] = def.angularVelocity.x, m.wy[i] = def.angularVelocity.y, m.wz[i] = def.angularVelocity.z;
    m.linearDamping[i] = kinematic ? 0.0f : def.linearDamping;
    m.angularDamping[i] = kinematic ? 0.0f : def.angularDamping;
    m.gravityScale[i] = kinematic ? 0.0f : def.gravityScale;
    m.friction[i] = def.material.friction;
    m.restitution[i] = def.material.restitution;
    m.density[i] = def.material.density;
    m.shape[i] = def.shape.index;
    m.filterCategory[i] = def.filter.category;
    m.filterMask[i] = def.filter.mask;
    m.userData[i] = def.userData;
    m.flags[i] = static_cast<std::uint8_t>(
        (kinematic ? detail::kFlagKinematic : 0) | (def.allowSleep ? 0 : detail::kFlagNoSleep) |
        (def.bullet ? detail::kFlagBullet : 0) | (def.contactEvents ? detail::kFlagContactEvents : 0) |
        (def.sensor ? detail::kFlagSensor : 0) | (def.contactResponse ? 0 : detail::kFlagNoResponse));
    w.countEventFlags(m.flags[i], 1);
    w.setMassFromShape(i);
    const Vec3 com = def.position + rotate(q, {m.lcx[i], m.lcy[i], m.lcz[i]});
    m.px[i] = com.x, m.py[i] = com.y, m.pz[i] = com.z;
    w.shapeUsers[def.shape.index] += 1;
    w.movingMaterials.count(m, i, w.shapes, 1);
    w.effectsDirty = true;
    return id;
}

void World::destroyBody(BodyId id) {
    Impl& w = *impl_;
    const BodySlot& slot = w.slotOf(id, "World::destroyBody");
    const bool moving = slot.set == BodySet::Moving;
    const std::uint32_t shape = moving ? w.bodies.moving.shape[slot.dense] : w.bodies.statics.shape[slot.dense];
    w.shapeUsers[shape] -= 1;
    w.countEventFlags(moving ? w.bodies.moving.flags[slot.dense] : w.bodies.statics.flags[slot.dense], -1);
    // What rested on the body falls: its own sleeping island and the islands it touched wake.
    if (slot.set == BodySet::Moving) {
        w.wake(slot.dense);
        w.movingMaterials.count(w.bodies.moving, slot.dense, w.shapes, -1);
    }
    w.sleeping.wakeTouching(id.index, w.bodies, w.contactCache);
    if (slot.set == BodySet::Static) {
        w.broadPhase.staticRemoved(id.index);
        const detail::StaticBodies& s = w.bodies.statics;
        w.staticMaterials.count(s.friction[slot.dense], s.restitution[slot.dense], -1);
    }
    w.joints.removeAttachedTo(id);
    w.bodies.release(id);
    w.queries.bodiesChanged();
    w.effectsDirty = true;
}

bool World::isValid(BodyId id) const { return impl_->bodies.find(id) != nullptr; }

std::uint32_t World::bodyCount() const { return impl_->bodies.count(); }

std::vector<BodyId> World::bodies() const {
    std::vector<BodyId> out;
    out.reserve(impl_->bodies.count());
    const detail::BodyStorage& bodies = impl_->bodies;
    for (std::uint32_t s = 0; s < bodies.slots().size(); ++s)
        if (bodies.alive(s)) out.push_back(bodies.idAt(s));
    return out;
}

BodyType World::bodyType(BodyId id) const {
    const long i = impl_->movingIndex(id, "World::bodyType");
    if (i < 0) return BodyType::Static;
    return (impl_->bodies.moving.flags[i] & detail::kFlagKinematic) ? BodyType::Kinematic : BodyType::Dynamic;
}

ShapeId World::bodyShape(BodyId id) const {
    const Impl& w = *impl_;
    const BodySlot& s = w.slotOf(id, "World::bodyShape");
    const std::uint32_t index =
        s.set == BodySet::Moving ? w.bodies.moving.shape[s.dense] : w.bodies.statics.shape[s.dense];
    return w.shapeIds.idAt(index);
}

Transform World::transform(BodyId id) const {
    const Impl& w = *impl_;
    const BodySlot& s = w.slotOf(id, "World::transform");
    if (s.set == BodySet::Static) {
        const detail::StaticBodies& b = w.bodies.statics;
        const std::uint32_t i = s.dense;
        return {{b.px[i], b.py[i], b.pz[i]}, {b.qx[i], b.qy[i], b.qz[i], b.qw[i]}};
    }
    const MovingBodies& m = w.bodies.moving;
    const std::uint32_t i = s.dense;
    const Quat q = w.orientationOf(i);
    return {w.comOf(i) - rotate(q, {m.lcx[i], m.lcy[i], m.lcz[i]}), q};
}

Vec3 World::position(BodyId id) const { return transform(id).position; }
Quat World::orientation(BodyId id) const { return transform(id).rotation; }

Vec3 World::centerOfMass(BodyId id) const {
    const long i = impl_->movingIndex(id, "World::centerOfMass");
    if (i >= 0) return impl_->comOf(static_cast<std::uint32_t>(i));
    const Transform t = transform(id);
    return apply(t, impl_->shapes[impl_->bodies.statics.shape[impl_->bodies.find(id)->dense]].unitMass.centerOfMass);
}

Vec3 World::linearVelocity(BodyId id) const {
    const long i = impl_->movingIndex(id, "World::linearVelocity");
    if (i < 0) return {};
    const MovingBodies& m = impl_->bodies.moving;
    return {m.vx[i], m.vy[i], m.vz[i]};
}

Vec3 World::angularVelocity(BodyId id) const {
    const long i = impl_->movingIndex(id, "World::angularVelocity");
    if (i < 0) return {};
    const MovingBodies& m = impl_->bodies.moving;
    return {m.wx[i], m.wy[i], m.wz[i]};
}

MassProperties World::massProperties(BodyId id) const {
    const Impl& w = *impl_;
    const long i = w.movingIndex(id, "World::massProperties");
    if (i < 0 || !w.isDynamic(static_cast<std::uint32_t>(i))) {
        MassProperties none;
        if (i >= 0) none.centerOfMass = w.shapes[w.bodies.moving.shape[i]].unitMass.centerOfMass;
        return none;
    }
    return detail::scaleMass(w.shapes[w.bodies.moving.shape[i]].unitMass, w.bodies.moving.density[i]);
}

Material World::material(BodyId id) const {
    const Impl& w = *impl_;
    const BodySlot& s = w.slotOf(id, "World::material");
    if (s.set == BodySet::Static) {
        const auto& b = w.bodies.statics;
        return {b.friction[s.dense], b.restitution[s.dense], b.density[s.dense]};
    }
    const auto& b = w.bodies.moving;
    return {b.friction[s.dense], b.restitution[s.dense], b.density[s.dense]};
}

CollisionFilter World::filter(BodyId id) const {
    const Impl& w = *impl_;
    const BodySlot& s = w.slotOf(id, "World::filter");
    if (s.set == BodySet::Static)
        return {w.bodies.statics.filterCategory[s.dense], w.bodies.statics.filterMask[s.dense]};
    return {w.bodies.moving.filterCategory[s.dense], w.bodies.moving.filterMask[s.dense]};
}

std::uint64_t World::userData(BodyId id) const {
    const Impl& w = *impl_;
    const BodySlot& s = w.slotOf(id, "World::userData");
    return s.set == BodySet::Static ? w.bodies.statics.userData[s.dense] : w.bodies.moving.userData[s.dense];
}

bool World::isFrozen(BodyId id) const {
    const long i = impl_->movingIndex(id, "World::isFrozen");
    return i >= 0 && (impl_->bodies.moving.flags[i] & detail::kFlagFrozen);
}

bool World::isAwake(BodyId id) const {
    const long i = impl_->movingIndex(id, "World::isAwake");
    return i >= 0 && !(impl_->bodies.moving.flags[i] & detail::kFlagAsleep);
}

void World::wakeUp(BodyId id) {
    const long i = impl_->movingIndex(id, "World::wakeUp");
    if (i >= 0) impl_->wake(static_cast<std::uint32_t>(i));
}

void World::setTransform(BodyId id, Vec3 position, Quat orientation) {
    static constexpr const char* kWhere = "World::setTransform";
    Impl& w = *impl_;
    const BodySlot& s = w.slotOf(id, kWhere);
    requireInWorld(kWhere, "position", position);
    const Quat q = requireUnit(kWhere, "orientation", orientation);
    w.queries.bodiesChanged();
    const std::uint32_t i = s.dense;
    w.sleeping.wakeTouching(id.index, w.bodies, w.contactCache);
    if (s.set == BodySet::Static) {
        auto& b = w.bodies.statics;
        b.px[i] = position.x, b.py[i] = position.y, b.pz[i] = position.z;
        b.qx[i] = q.x, b.qy[i] = q.y, b.qz[i] = q.z, b.qw[i] = q.w;
        w.broadPhase.staticRemoved(id.index);
        w.broadPhase.staticAdded(id.index, w.bodies, w.shapes, *w.pool);
        return;
    }
    w.wake(i);
    MovingBodies& m = w.bodies.moving;
    m.qx[i] = q.x, m.qy[i] = q.y, m.qz[i] = q.z, m.qw[i] = q.w;
    const Vec3 com = position + rotate(q, {m.lcx[i], m.lcy[i], m.lcz[i]});
    m.px[i] = com.x, m.py[i] = com.y, m.pz[i] = com.z;
    w.refreshWorldInertia(i);
}

void World::setLinearVelocity(BodyId id, Vec3 v) {
    static constexpr const char* kWhere = "World::setLinearVelocity";
    const long i = impl_->movingIndex(id, kWhere);
    requireFinite(kWhere, "velocity", v);
    if (i < 0) {
        if (v != Vec3{}) fail(kWhere, "a static body cannot have a velocity");
        return;
    }
    MovingBodies& m = impl_->bodies.moving;
    if (m.flags[i] & detail::kFlagFrozen) return;
    impl_->wake(static_cast<std::uint32_t>(i));
    m.vx[i] = v.x, m.vy[i] = v.y, m.vz[i] = v.z;
}

void World::setAngularVelocity(BodyId id, Vec3 v) {
    static constexpr const char* kWhere = "World::setAngularVelocity";
    const long i = impl_->movingIndex(id, kWhere);
    requireFinite(kWhere, "angular velocity", v);
    if (i < 0) {
        if (v != Vec3{}) fail(kWhere, "a static body cannot have a velocity");
        return;
    }
    MovingBodies& m = impl_->bodies.moving;
    if (m.flags[i] & detail::kFlagFrozen) return;
    impl_->wake(static_cast<std::uint32_t>(i));
    m.wx[i] = v.x, m.wy[i] = v.y, m.wz[i] = v.z;
    if (v != Vec3{} && !impl_->effects.has(Effect::Rotation)) impl_->effectsDirty = true;
}

void World::setMaterial(BodyId id, const Material& material) {
    static constexpr const char* kWhere = "World::setMaterial";
    Impl& w = *impl_;
    const BodySlot& s = w.slotOf(id, kWhere);
    validateMaterial(kWhere, material);
    const std::uint32_t i = s.dense;
    if (s.set == BodySet::Static) {
        auto& b = w.bodies.statics;
        w.staticMaterials.count(b.friction[i], b.restitution[i], -1);
        w.staticMaterials.count(material.friction, material.restitution, 1);
        b.friction[i] = material.friction, b.restitution[i] = material.restitution, b.density[i] = material.density;
    } else {
        auto& b = w.bodies.moving;
        w.wake(i);
        w.movingMaterials.count(b, i, w.shapes, -1);
        b.friction[i] = material.friction, b.restitution[i] = material.restitution, b.density[i] = material.density;
        w.movingMaterials.count(b, i, w.shapes, 1);
        if (w.isDynamic(i)) w.setMassFromShape(i);
    }
    w.effectsDirty = true;
}

void World::setFilter(BodyId id, CollisionFilter f) {
    Impl& w = *impl_;
    const BodySlot& s = w.slotOf(id, "World::setFilter");
    if (s.set == BodySet::Static) {
        w.bodies.statics.filterCategory[s.dense] = f.category;
        w.bodies.statics.filterMask[s.dense] = f.mask;
        w.broadPhase.staticFilterChanged(id.index, f.category, f.mask);
        w.sleeping.wakeTouching(id.index, w.bodies, w.contactCache);
    } else {
        w.wake(s.dense);
        w.bodies.moving.filterCategory[s.dense] = f.category;
        w.bodies.moving.filterMask[s.dense] = f.mask;
    }
}

void World::setUserData(BodyId id, std::uint64_t data) {
    Impl& w = *impl_;
    const BodySlot& s = w.slotOf(id, "World::setUserData");
    (s.set == BodySet::Static ? w.bodies.statics.userData : w.bodies.moving.userData)[s.dense] = data;
}

// ---------------------------------------------------------------------------------------------------------------
// Forces and impulses: dynamic bodies respond; static, kinematic and frozen bodies ignore them.

void World::addForce(BodyId id, Vec3 force) {
    static constexpr const char* kWhere = "World::addForce";
    const long i = impl_->movingIndex(id, kWhere);
    requireFinite(kWhere, "force", force);
    if (i < 0 || !impl_->isDynamic(static_cast<std::uint32_t>(i))) return;
    impl_->wake(static_cast<std::uint32_t>(i));
    MovingBodies& m = impl_->bodies.moving;
    m.fx[i] += force.x, m.fy[i] += force.y, m.fz[i] += force.z;
    impl_->forcesPending = true;
}

void World::addTorque(BodyId id, Vec3 torque) {
    static constexpr const char* kWhere = "World::addTorque";
    const long i = impl_->movingIndex(id, kWhere);
    requireFinite(kWhere, "torque", torque);
    if (i < 0 || !impl_->isDynamic(static_cast<std::uint32_t>(i))) return;
    impl_->wake(static_cast<std::uint32_t>(i));
    MovingBodies& m = impl_->bodies.moving;
    m.tx[i] += torque.x, m.ty[i] += torque.y, m.tz[i] += torque.z;
    impl_->forcesPending = true;
    if (torque != Vec3{} && !impl_->effects.has(Effect::Rotation)) impl_->effectsDirty = true;
}

void World::addForceAtPoint(BodyId id, Vec3 force, Vec3 worldPoint) {
    static constexpr const char* kWhere = "World::addForceAtPoint";
    const long i = impl_->movingIndex(id, kWhere);
    requireFinite(kWhere, "force", force);
    requireFinite(kWhere, "point", worldPoint);
    if (i < 0 || !impl_->isDynamic(static_cast<std::uint32_t>(i))) return;
    addForce(id, force);
    addTorque(id, cross(worldPoint - impl_->comOf(static_cast<std::uint32_t>(i)), force));
}

void World::applyLinearImpulse(BodyId id, Vec3 impulse) {
    static constexpr const char* kWhere = "World::applyLinearImpulse";
    const long i = impl_->movingIndex(id, kWhere);
    requireFinite(kWhere, "impulse", impulse);
    if (i < 0 || !impl_->isDynamic(static_cast<std::uint32_t>(i))) return;
    impl_->wake(static_cast<std::uint32_t>(i));
    MovingBodies& m = impl_->bodies.moving;
    m.vx[i] += impulse.x * m.invMass[i], m.vy[i] += impulse.y * m.invMass[i], m.vz[i] += impulse.z * m.invMass[i];
}

void World::applyAngularImpulse(BodyId id, Vec3 impulse) {
    static constexpr const char* kWhere = "World::applyAngularImpulse";
    const long i = impl_->movingIndex(id, kWhere);
    requireFinite(kWhere, "impulse", impulse);
    if (i < 0 || !impl_->isDynamic(static_cast<std::uint32_t>(i))) return;
    impl_->wake(static_cast<std::uint32_t>(i));
    const Vec3 dw = impl_->applyWorldInverseInertia(static_cast<std::uint32_t>(i), impulse);
    MovingBodies& m = impl_->bodies.moving;
    m.wx[i] += dw.x, m.wy[i] += dw.y, m.wz[i] += dw.z;
    if (dw != Vec3{} && !impl_->effects.has(Effect::Rotation)) impl_->effectsDirty = true;
}

void World::applyImpulseAtPoint(BodyId id, Vec3 impulse, Vec3 worldPoint) {
    static constexpr const char* kWhere = "World::applyImpulseAtPoint";
    const long i = impl_->movingIndex(id, kWhere);
    requireFinite(kWhere, "impulse", impulse);
    requireFinite(kWhere, "point", worldPoint);
    if (i < 0 || !impl_->isDynamic(static_cast<std::uint32_t>(i))) return;
    applyLinearImpulse(id, impulse);
    applyAngularImpulse(id, cross(worldPoint - impl_->comOf(static_cast<std::uint32_t>(i)), impulse));
}

const WorldSettings& World::settings() const { return impl_->settings; }

void World::setSettings(const WorldSettings& s) {
    static constexpr const char* kWhere = "World::setSettings";
    requireFinite(kWhere, "settings.gravity", s.gravity);
    requireWithin(kWhere, "settings.timeStep", s.timeStep, limits::kMinTimeStep, limits::kMaxTimeStep, "s");
    requireNonNegative(kWhere, "settings.contactMargin", s.contactMargin);
    requireNonNegative(kWhere, "settings.manifoldReuseDistance", s.manifoldReuseDistance);
    requireNonNegative(kWhere, "settings.contactFeatureDrift", s.contactFeatureDrift);
    const auto requireCount = [&](const char* name, int value, int lo, int hi) {
        if (value < lo || value > hi)
            fail(kWhere, std::string(name) + " must be in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                             "] (got " + std::to_string(value) + "; docs/limits.md)");
    };
    requireCount("settings.substeps", s.substeps, 1, limits::kMaxSubsteps);
    requireCount("settings.velocityIterations", s.velocityIterations, 0, limits::kMaxIterations);
    requireCount("settings.positionIterations", s.positionIterations, 0, limits::kMaxIterations);
    requireCount("settings.threads", s.threads, 0, limits::kMaxThreads);
    requireNonNegative(kWhere, "settings.sleep.linearThreshold", s.sleep.linearThreshold);
    requireNonNegative(kWhere, "settings.sleep.angularThreshold", s.sleep.angularThreshold);
    requireNonNegative(kWhere, "settings.sleep.timeToSleep", s.sleep.timeToSleep);
    requireNonNegative(kWhere, "settings.hitEventSpeed", s.hitEventSpeed);
    if ((s.effects.bits & ~EffectSet::all().bits) != 0)
        fail(kWhere, "settings.effects has unknown bits (" + std::to_string(s.effects.bits) + ")");
    Impl& w = *impl_;
    if (s.threads != w.settings.threads) w.pool = std::make_unique<detail::TaskPool>(s.threads);
    w.settings = s;
    w.effectsDirty = true;
}

EffectSet World::activeEffects() const {
    impl_->resolveEffectsIfDirty();
    return impl_->effects;
}

const Profile& World::lastProfile() const { return impl_->profile; }
std::uint64_t World::stepCount() const { return impl_->steps; }

std::vector<BodyId> World::takeFrozenBodies() {
    std::vector<BodyId> out;
    out.swap(impl_->frozenReports);
    return out;
}

std::uint64_t World::stateHash() const {
    const Impl& w = *impl_;
    std::uint64_t h = 0xcbf29ce484222325ull;
    const auto& slots = w.bodies.slots();
    for (std::uint32_t s = 0; s < slots.size(); ++s) {
        if (!w.bodies.alive(s)) continue;
        h = mix(h, (std::uint64_t{s} << 32) | w.bodies.idAt(s).generation);
        const std::uint32_t i = slots[s].dense;
        if (slots[s].set == BodySet::Static) {
            const auto& b = w.bodies.statics;
            for (float f : {b.px[i], b.py[i], b.pz[i], b.qx[i], b.qy[i], b.qz[i], b.qw[i]}) h = mix(h, bitsOf(f));
        } else {
            const auto& b = w.bodies.moving;
            for (float f : {b.px[i], b.py[i], b.pz[i], b.qx[i], b.qy[i], b.qz[i], b.qw[i], b.vx[i], b.vy[i], b.vz[i],
                            b.wx[i], b.wy[i], b.wz[i]})
                h = mix(h, bitsOf(f));
        }
    }
    return h;
}

bool World::terrainHeightAt(float x, float z, float& height) const {
    const Impl& w = *impl_;
    const auto& b = w.bodies.statics;
    bool found = false;
    for (std::uint32_t i = 0; i < b.size(); ++i) {
        const Shape& shape = w.shapes[b.shape[i]];
        if (!shape.staticOnly()) continue;
        const Quat q{b.qx[i], b.qy[i], b.qz[i], b.qw[i]};
        // Only terrains whose local up is the world's up have a height "at (x, z)"; tilted meshes are skipped.
        const Vec3 up = rotate(q, {0, 1, 0});
        if (up.y < 1.0f - 1e-5f) continue;
        const Vec3 local = rotate(conjugate(q), Vec3{x - b.px[i], 0, z - b.pz[i]});
        if (const auto h = detail::surfaceHeightAt(shape, local.x, local.z)) {
            const float worldHeight = *h + b.py[i];
            if (!found || worldHeight > height) height = worldHeight;
            found = true;
        }
    }
    return found;
}

}  // namespace rubble
