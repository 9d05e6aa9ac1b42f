#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "rubble/body.h"
#include "rubble/events.h"
#include "rubble/id.h"
#include "rubble/joint.h"
#include "rubble/math.h"
#include "rubble/profile.h"
#include "rubble/query.h"
#include "rubble/settings.h"
#include "rubble/shapes.h"

namespace rubble {

class DebugDraw;
struct DebugDrawOptions;
struct ShapeGeometry;
namespace detail {
struct WorldAccess;
}

/// A physics world: shapes, bodies and the step that moves them.
/// Every function that takes a BodyId or ShapeId throws rubble::Error when the handle is null, stale or from
/// another world, and every setter refuses non-finite or out-of-range input the same way.
class World {
public:
    explicit World(const WorldSettings& settings = {});
    ~World();
    World(const World&) = delete;
    World& operator=(const World&) = delete;
    World(World&&) noexcept;
    World& operator=(World&&) noexcept;

    /// Validates and builds a shape (convex hulls are computed here).
    ShapeId createShape(const ShapeDef& def);
    /// Removes a shape no body uses any more.
    void destroyShape(ShapeId id);
    bool isValid(ShapeId id) const;
    /// Mass properties of the shape at unit density.
    MassProperties shapeMassProperties(ShapeId id) const;
    /// The shape as built, for renderers: sizes, and triangles of hulls, meshes and heightfields
    /// (include/rubble/shape_geometry.h, src/shapes/shape_geometry.cpp).
    ShapeGeometry shapeGeometry(ShapeId id) const;

    BodyId createBody(const BodyDef& def);
    /// O(1); other bodies' handles stay valid.
    void destroyBody(BodyId id);
    bool isValid(BodyId id) const;
    std::uint32_t bodyCount() const;
    /// Handles of all bodies, in slot order (stable across steps).
    std::vector<BodyId> bodies() const;

    BodyType bodyType(BodyId id) const;
    ShapeId bodyShape(BodyId id) const;
    /// Pose of the shape's local origin.
    Transform transform(BodyId id) const;
    Vec3 position(BodyId id) const;
    Quat orientation(BodyId id) const;
    /// World position of the centre of mass.
    Vec3 centerOfMass(BodyId id) const;
    Vec3 linearVelocity(BodyId id) const;
    Vec3 angularVelocity(BodyId id) const;
    /// Mass properties of the body (zero mass for static and kinematic bodies); inertia in the body frame.
    MassProperties massProperties(BodyId id) const;
    Material material(BodyId id) const;
    CollisionFilter filter(BodyId id) const;
    std::uint64_t userData(BodyId id) const;
    /// True when the body's state went non-finite, or its motion would have carried it past the coordinate limit
    /// (include/rubble/limits.h), and the world stopped simulating it (where it last was, at rest).
    bool isFrozen(BodyId id) const;
    /// False while the body sleeps with its island (Effect::Sleeping) and for static bodies; true otherwise.
    bool isAwake(BodyId id) const;
    /// Wakes the body's sleeping island (nothing for an awake or static body). Forces, impulses, velocities and
    /// transforms set through this API wake the island too, as does removing or moving a body it rests on.
    void wakeUp(BodyId id);

    void setTransform(BodyId id, Vec3 position, Quat orientation);
    void setLinearVelocity(BodyId id, Vec3 v);
    void setAngularVelocity(BodyId id, Vec3 w);
    void setMaterial(BodyId id, const Material& m);  ///< density changes the mass of a dynamic body
    void setFilter(BodyId id, CollisionFilter f);
    void setUserData(BodyId id, std::uint64_t data);

    /// Forces and torques accumulate until the next step, which applies and clears them. Dynamic bodies only
    /// respond; on other bodies they are ignored.
    void addForce(BodyId id, Vec3 force);
    void addTorque(BodyId id, Vec3 torque);
    void addForceAtPoint(BodyId id, Vec3 force, Vec3 worldPoint);
    /// Impulses change velocity at once.
    void applyLinearImpulse(BodyId id, Vec3 impulse);
    void applyAngularImpulse(BodyId id, Vec3 impulse);
    void applyImpulseAtPoint(BodyId id, Vec3 impulse, Vec3 worldPoint);

    /// Advances the world by dt seconds (dt > 0 and finite).
    void step(float dt);

    const WorldSettings& settings() const;
    /// Changes settings between steps (thread count included).
    void setSettings(const WorldSettings& settings);
    /// Effects simulated by the next step: the declared ones less those the world's content cannot show.
    EffectSet activeEffects() const;
    const Profile& lastProfile() const;
    std::uint64_t stepCount() const;

    // -----------------------------------------------------------------------------------------------------------
    // Joints (include/rubble/joint.h, src/storage/joint_storage.h, src/solver/joint_solver.h)
    //
    // Joints are solved in the same velocity iterations as the contacts (joints first, then the contacts). A body may
    // have any number of joints; destroyBody destroys the joints attached to the body (their JointIds become
    // invalid). Bad input (null, stale or static-static bodies, the same body twice, non-finite or out-of-range
    // numbers, zero axes) throws rubble::Error naming the call, the field and the value.

    JointId createJoint(const DistanceJointDef& def);
    JointId createJoint(const SpringJointDef& def);
    JointId createJoint(const BallJointDef& def);
    JointId createJoint(const HingeJointDef& def);
    void destroyJoint(JointId id);
    bool isValid(JointId id) const;
    std::uint32_t jointCount() const;
    JointType jointType(JointId id) const;
    /// The joint's bodies, A then B.
    std::pair<BodyId, BodyId> jointBodies(JointId id) const;
    /// True once the joint broke; it no longer acts but keeps its handle until destroyed.
    bool isJointBroken(JointId id) const;
    /// Joints that broke since the last call, each reported once, in the order they broke.
    std::vector<JointId> takeBrokenJoints();
    /// Force the joint applied to body B in the last substep it acted, N (A received the opposite).
    Vec3 jointReactionForce(JointId id) const;
    /// Torque the joint applied to body B about the anchor in the last substep it acted, N m (hinges only).
    Vec3 jointReactionTorque(JointId id) const;
    /// Current hinge angle (B relative to A about the axis, zero at creation), rad in (-pi, pi].
    float hingeAngle(JointId id) const;
    /// Motor of a hinge: enables or disables it and sets its speed (rad/s) and torque limit (N m, >= 0).
    void setHingeMotor(JointId id, bool enable, float speed, float maxTorque);

    /// Bodies frozen (non-finite, or leaving the coordinate limit: isFrozen) since the last call.
    std::vector<BodyId> takeFrozenBodies();

    // -----------------------------------------------------------------------------------------------------------
    // Events and contacts (include/rubble/events.h, src/events/, src/world/world_events.cpp)

    /// Contact events of the last step, for the bodies that ask (BodyDef::contactEvents). Valid until the next step.
    const ContactEvents& contactEvents() const;
    /// Sensor events of the last step (BodyDef::sensor). Valid until the next step.
    const SensorEvents& sensorEvents() const;
    /// Starts or stops reporting a body's contacts. A pair it touches that no body listens to any more ends with an
    /// end event at the next step, so that every begin has its end.
    void setContactEvents(BodyId id, bool enabled);
    bool contactEventsEnabled(BodyId id) const;
    bool isSensor(BodyId id) const;
    /// Appends the body's contacts as the last step left them (one per touching or nearly touching part: a compound's
    /// child, a mesh's triangle), those of its sleeping island included, in the step's order; returns how many. A
    /// static body's contacts with sleeping bodies are listed too. Bodies created since the last step have none;
    /// a sensor has none (see sensorEvents).
    std::size_t contactsOf(BodyId id, std::vector<BodyContact>& contacts) const;

    /// Moves a kinematic body to `position` and `orientation` over the next `dt` seconds (normally the next step's):
    /// sets the velocities that get it there, so that it pushes and carries dynamic bodies on its way, as a platform
    /// or a door does. Called every step for a path; the velocities stay until changed, so a body not moved again
    /// keeps going. Refused for static and dynamic bodies (a dynamic body is moved by forces; setTransform teleports).
    void moveKinematic(BodyId id, Vec3 position, Quat orientation, float dt);

    /// 64-bit hash of the state of every body (pose and velocities, bit for bit), in slot order.
    std::uint64_t stateHash() const;

    /// Height of the highest static mesh or heightfield surface straight below or above (x, z), if any.
    /// Used for the scenes' tunnelling figure.
    bool terrainHeightAt(float x, float z, float& height) const;

    // -----------------------------------------------------------------------------------------------------------
    // Queries (include/rubble/query.h, src/query/)
    //
    // Queries see every body at its current pose, bodies created, moved or removed since the last step included.
    // The first query after such a change (or a step) brings the query trees up to date; every later one only
    // reads them, so const queries may run on several threads at once, but never during a non-const call.
    // Directions need not be unit length (they are normalised; zero is refused); maxDistance may be infinity.
    // Results do not depend on the thread count; equal distances are ordered by body slot, then child, then
    // triangle. Bad input (non-finite numbers, a zero direction, a negative distance or radius, a null or stale
    // shape) throws rubble::Error naming the call, the field and the value.

    /// Closest surface the ray enters within maxDistance, if any.
    std::optional<RayHit> castRay(Vec3 origin, Vec3 direction, float maxDistance, const QueryFilter& filter = {}) const;
    /// Appends every hit within maxDistance to `hits`, nearest first: one per solid body (per child of a compound)
    /// the ray enters, and one per mesh or heightfield triangle it crosses. Returns how many it appended.
    std::size_t castRayAll(Vec3 origin, Vec3 direction, float maxDistance, std::vector<RayHit>& hits,
                           const QueryFilter& filter = {}) const;
    /// First body a sphere touches when swept from `center` along `direction` (radius >= 0; 0 sweeps a point).
    std::optional<ShapeCastHit> castSphere(Vec3 center, float radius, Vec3 direction, float maxDistance,
                                           const QueryFilter& filter = {}) const;
    /// First body a shape of this world (sphere, box, capsule, hull or compound) touches when swept without rotation
    /// from `start` along `direction`. Sweeps that are not closed forms (those involving boxes, hulls, or a cast shape
    /// other than a sphere) stop within 1e-4 m short of the contact, never past it beyond rounding.
    std::optional<ShapeCastHit> castShape(ShapeId shape, const Transform& start, Vec3 direction, float maxDistance,
                                          const QueryFilter& filter = {}) const;
    /// Appends the bodies whose shape touches or overlaps the box [min, max], by slot; returns how many. Shapes are
    /// tested exactly, not by their bounding boxes. Meshes and heightfields are surfaces, seen from both sides: a box
    /// wholly inside a closed mesh does not overlap it. (QueryFilter's hitBackFaces and hitFromInside do not apply.)
    std::size_t overlapAabb(Vec3 min, Vec3 max, std::vector<BodyId>& bodies, const QueryFilter& filter = {}) const;
    /// Same for a sphere (radius >= 0).
    std::size_t overlapSphere(Vec3 center, float radius, std::vector<BodyId>& bodies,
                              const QueryFilter& filter = {}) const;
    /// Same for a shape of this world (sphere, box, capsule, hull or compound) at `pose`.
    std::size_t overlapShape(ShapeId shape, const Transform& pose, std::vector<BodyId>& bodies,
                             const QueryFilter& filter = {}) const;

    // -----------------------------------------------------------------------------------------------------------
    // Debug draw (include/rubble/debug_draw.h, src/world/debug_draw.cpp)

    /// Draws what `options` selects (shapes at their bodies' poses, AABBs, last step's contact points and normals,
    /// sleeping state, last step's broad-phase cells, joints) into `draw`. Const: may run between steps on any one
    /// thread.
    void debugDraw(DebugDraw& draw, const DebugDrawOptions& options) const;

    struct Impl;

private:
    friend struct detail::WorldAccess;  // the runtime (src/runtime/) reads the body arrays to publish snapshots
    std::unique_ptr<Impl> impl_;
};

}  // namespace rubble
