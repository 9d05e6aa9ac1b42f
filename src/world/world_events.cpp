// World's events, contacts and kinematic moves (include/rubble/world.h, "Events and contacts"); the stages that
// gather the events are in src/events/.
#include <cmath>
#include <string>

#include "rubble/limits.h"
#include "world/world_impl.h"

namespace rubble {

namespace {

std::uint32_t partOrNone(std::uint64_t part, std::uint64_t none) {
    return part == none ? kNoIndex : static_cast<std::uint32_t>(part);
}

/// The manifold of `key` seen from body `id`, appended to `out`; nothing when `id` is not one of its bodies.
void appendContact(BodyId id, const detail::ContactKey& key, const detail::Manifold& manifold,
                   const detail::PointImpulse* impulses, std::vector<BodyContact>& out) {
    const BodyId a = key.bodyA(), b = key.bodyB();
    if (a != id && b != id) return;
    const bool asA = a == id;
    BodyContact& c = out.emplace_back();
    c.other = asA ? b : a;
    c.normal = asA ? manifold.normal : -manifold.normal;
    c.pointCount = manifold.pointCount;
    for (int i = 0; i < manifold.pointCount; ++i) {
        const detail::PointImpulse& impulse = impulses[i];
        c.points[i] = {manifold.points[i].position, manifold.points[i].depth, impulse.normal,
                       std::sqrt(impulse.tangent1 * impulse.tangent1 + impulse.tangent2 * impulse.tangent2)};
    }
    const std::uint32_t childA = partOrNone((key.parts >> 16) & 0xFFFF, detail::kNoChild);
    const std::uint32_t childB = partOrNone(key.parts & 0xFFFF, detail::kNoChild);
    c.child = asA ? childA : childB;
    c.otherChild = asA ? childB : childA;
    c.triangle = partOrNone(key.parts >> 32, 0xFFFFFFFFu);
}

}  // namespace

const ContactEvents& World::contactEvents() const { return impl_->contactEvents; }

const SensorEvents& World::sensorEvents() const { return impl_->sensorEvents; }

void World::setContactEvents(BodyId id, bool enabled) {
    Impl& w = *impl_;
    const BodySlot& s = w.slotOf(id, "World::setContactEvents");
    std::uint8_t& flags = s.set == BodySet::Static ? w.bodies.statics.flags[s.dense] : w.bodies.moving.flags[s.dense];
    w.countEventFlags(flags, -1);
    flags =
        static_cast<std::uint8_t>(enabled ? flags | detail::kFlagContactEvents : flags & ~detail::kFlagContactEvents);
    w.countEventFlags(flags, 1);
}

bool World::contactEventsEnabled(BodyId id) const {
    const Impl& w = *impl_;
    const BodySlot& s = w.slotOf(id, "World::contactEventsEnabled");
    return ((s.set == BodySet::Static ? w.bodies.statics.flags : w.bodies.moving.flags)[s.dense] &
            detail::kFlagContactEvents) != 0;
}

bool World::isSensor(BodyId id) const {
    const Impl& w = *impl_;
    const BodySlot& s = w.slotOf(id, "World::isSensor");
    return ((s.set == BodySet::Static ? w.bodies.statics.flags : w.bodies.moving.flags)[s.dense] &
            detail::kFlagSensor) != 0;
}

std::size_t World::contactsOf(BodyId id, std::vector<BodyContact>& out) const {
    const Impl& w = *impl_;
    const BodySlot& slot = w.slotOf(id, "World::contactsOf");
    const std::size_t before = out.size();
    const detail::MovingBodies& m = w.bodies.moving;
    const bool moving = slot.set == BodySet::Moving;
    const bool asleep = moving && (m.flags[slot.dense] & detail::kFlagAsleep) != 0;
    // A manifold of a body asleep now is listed from its island's kept manifolds (those of an island that fell
    // asleep in the last step are in both places).
    // Bodies are named by the contact cache's keys (slots and generations), which removals between steps leave
    // valid, unlike the pairs' dense indices.
    const auto asleepNow = [&](std::uint32_t slotIndex) {
        if (!w.bodies.alive(slotIndex)) return false;
        const BodySlot& s = w.bodies.slots()[slotIndex];
        return s.set == BodySet::Moving && (m.flags[s.dense] & detail::kFlagAsleep) != 0;
    };
    if (w.contactsOfLastStep && !asleep) {
        for (std::size_t k = 0; k < w.contacts.manifolds.size(); ++k) {
            const detail::ContactKey& key = w.contactCache.currentKey(k);
            const std::uint32_t slotA = key.bodyA().index, slotB = key.bodyB().index;
            if ((slotA != id.index && slotB != id.index) || asleepNow(slotA == id.index ? slotB : slotA)) continue;
            appendContact(id, key, w.contacts.manifolds[k], &w.impulses[k * detail::kMaxManifoldPoints], out);
        }
    }
    const auto appendKept = [&](const detail::KeptManifold& kept) {
        appendContact(id, kept.key, kept.manifold, kept.impulses, out);
    };
    if (asleep)
        for (const detail::KeptManifold& kept : w.sleeping.keptManifolds(slot.dense, w.bodies)) appendKept(kept);
    else if (!moving)
        w.sleeping.forEachKeptManifold(appendKept);
    return out.size() - before;
}

void World::moveKinematic(BodyId id, Vec3 position, Quat orientation, float dt) {
    static constexpr const char* kWhere = "World::moveKinematic";
    Impl& w = *impl_;
    const long i = w.movingIndex(id, kWhere);
    if (i < 0) fail(kWhere, "body " + std::to_string(id.index) + " is static and cannot move (make it kinematic)");
    MovingBodies& m = w.bodies.moving;
    if (!(m.flags[i] & detail::kFlagKinematic))
        fail(kWhere, "body " + std::to_string(id.index) +
                         " is dynamic: forces move it (setTransform places it, setLinearVelocity sets its speed)");
    requireInWorld(kWhere, "position", position);
    const Quat q = requireUnit(kWhere, "orientation", orientation);
    requireWithin(kWhere, "dt", dt, limits::kMinTimeStep, limits::kMaxTimeStep, "s");
    if (m.flags[i] & detail::kFlagFrozen) return;
    const Vec3 com = position + rotate(q, {m.lcx[i], m.lcy[i], m.lcz[i]});
    const Vec3 v = (com - w.comOf(static_cast<std::uint32_t>(i))) / dt;
    // The turn from the current orientation to the target, the shorter way round, as an angle about an axis.
    Quat turn = q * conjugate(w.orientationOf(static_cast<std::uint32_t>(i)));
    if (turn.w < 0) turn = {-turn.x, -turn.y, -turn.z, -turn.w};
    const Vec3 axis{turn.x, turn.y, turn.z};
    const float sine = length(axis);
    const Vec3 omega = sine > 0 ? axis * (2.0f * std::atan2(sine, turn.w) / (sine * dt)) : Vec3{};
    w.wake(static_cast<std::uint32_t>(i));
    m.vx[i] = v.x, m.vy[i] = v.y, m.vz[i] = v.z;
    m.wx[i] = omega.x, m.wy[i] = omega.y, m.wz[i] = omega.z;
}

}  // namespace rubble
