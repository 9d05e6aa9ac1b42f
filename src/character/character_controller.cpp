// The character controller (include/rubble/character.h): collide and slide over the world's public queries.
#include "rubble/character.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "rubble/error.h"
#include "rubble/limits.h"
#include "rubble/world.h"
#include "world/validation.h"

namespace rubble {

namespace {

constexpr Vec3 kUp{0, 1, 0};
/// Collide and slide stops after this many surfaces in one update: a corner takes two, a crease three.
constexpr int kMaxSlides = 5;
/// Displacements below this are not swept, m.
constexpr float kMinMove = 1e-5f;

Vec3 horizontal(Vec3 v) { return {v.x, 0, v.z}; }

void validate(const CharacterSettings& s) {
    static constexpr const char* kWhere = "CharacterController";
    const auto positive = [&](const char* name, float value) {
        if (!(value > 0) || !std::isfinite(value))
            detail::fail(kWhere, std::string("settings.") + name + " must be finite and > 0 (got " +
                                     detail::formatNumber(value) + ")");
    };
    positive("radius", s.radius);
    positive("skin", s.skin);
    positive("mass", s.mass);
    if (!(s.height > 2 * s.radius) || !std::isfinite(s.height))
        detail::fail(kWhere, "settings.height must be finite and more than twice the radius (got " +
                                 detail::formatNumber(s.height) + " for radius " + detail::formatNumber(s.radius) +
                                 ")");
    if (!(s.maxSlope > 0 && s.maxSlope < 1.5707f))
        detail::fail(kWhere,
                     "settings.maxSlope must be in (0, pi / 2) rad (got " + detail::formatNumber(s.maxSlope) + ")");
    if (!(s.stepHeight >= 0 && s.stepHeight < s.height - 2 * s.radius))
        detail::fail(kWhere, "settings.stepHeight must be in [0, height - 2 radius) (got " +
                                 detail::formatNumber(s.stepHeight) + ")");
    if (!(s.skin < s.radius)) detail::fail(kWhere, "settings.skin must be less than the radius");
    detail::requireNonNegative(kWhere, "settings.groundSnap", s.groundSnap);
    detail::requireNonNegative(kWhere, "settings.pushForce", s.pushForce);
}

}  // namespace

struct CharacterController::Sweep {
    BodyId body;
    Vec3 point;
    Vec3 normal;
    float distance = 0;
};

CharacterController::CharacterController(World& world, Vec3 feet, const CharacterSettings& settings)
    : world_(world), settings_(settings), feet_(feet) {
    validate(settings);
    detail::requireInWorld("CharacterController", "feet", feet);
    shape_ = world.createShape(CapsuleDef{settings.radius, 0.5f * settings.height - settings.radius});
    BodyDef def;
    def.type = BodyType::Kinematic;
    def.shape = shape_;
    def.position = center();
    def.filter = settings.filter;
    def.contactResponse = false;
    body_ = world.createBody(def);
}

CharacterController::~CharacterController() {
    if (world_.isValid(body_)) world_.destroyBody(body_);
    if (world_.isValid(shape_)) world_.destroyShape(shape_);
}

Vec3 CharacterController::center() const { return feet_ + kUp * (0.5f * settings_.height); }

bool CharacterController::cast(Vec3 from, Vec3 direction, float distance, Sweep& hit, CharacterMove& move) const {
    QueryFilter filter;
    filter.category = settings_.filter.category;
    filter.mask = settings_.filter.mask;
    filter.ignore = body_;
    // What it already overlaps (something moved into it) does not hold it: it walks out of it.
    filter.hitFromInside = false;
    ++move.sweeps;
    const std::optional<ShapeCastHit> found = world_.castShape(shape_, {from, Quat{}}, direction, distance, filter);
    if (!found) return false;
    hit = {found->body, found->point, found->normal, found->distance};
    return true;
}

void CharacterController::push(const Sweep& hit, Vec3 velocity, float dt, CharacterMove& move) {
    if (settings_.pushForce <= 0 || world_.bodyType(hit.body) != BodyType::Dynamic) return;
    Vec3 direction = horizontal(-hit.normal);
    const float size = length(direction);
    if (size < 1e-3f) return;
    direction = direction / size;
    // Up to the speed it walks into the body, within what its force gives over the step.
    const float closing = dot(velocity, direction) - dot(world_.linearVelocity(hit.body), direction);
    if (closing <= 0) return;
    const float impulse = std::min(world_.massProperties(hit.body).mass * closing, settings_.pushForce * dt);
    world_.applyImpulseAtPoint(hit.body, direction * impulse, hit.point);
    ++move.pushedBodies;
}

bool CharacterController::stepUp(Vec3& at, Vec3 walk, CharacterMove& move) {
    const float walkLength = length(walk);
    const Vec3 forward = walk / walkLength;
    Sweep hit;
    float rise = settings_.stepHeight;
    if (cast(at, kUp, rise + settings_.skin, hit, move)) rise = std::max(0.0f, hit.distance - settings_.skin);
    if (rise < settings_.skin) return false;
    const Vec3 raised = at + kUp * rise;
    // Onto the step far enough that the capsule's axis is over its top (so that it stands on the tread, not hangs
    // on the edge), or as far as the walk goes if that is further.
    const float reach = std::max(walkLength, settings_.radius + 2 * settings_.skin);
    float travel = reach;
    if (cast(raised, forward, reach + settings_.skin, hit, move))
        travel = std::max(0.0f, hit.distance - settings_.skin);
    if (travel < settings_.skin) return false;
    const Vec3 over = raised + forward * travel;
    if (!cast(over, -kUp, rise + settings_.skin, hit, move)) return false;  // no tread: a ledge, not a step
    if (hit.normal.y < std::cos(settings_.maxSlope)) return false;
    const Vec3 landed = over - kUp * std::max(0.0f, hit.distance - settings_.skin);
    if (landed.y - at.y < settings_.skin) return false;  // not up at all
    at = landed;
    grounded_ = true;
    ground_ = hit.body;
    groundNormal_ = hit.normal;
    groundPoint_ = hit.point;
    return true;
}

Vec3 CharacterController::slide(Vec3 at, Vec3 displacement, float dt, CharacterMove& move) {
    const float walkable = std::cos(settings_.maxSlope);
    const Vec3 velocity = displacement / dt;
    Vec3 rest = displacement;
    Vec3 firstNormal;
    bool haveFirst = false, stepped = false;
    for (int i = 0; i < kMaxSlides; ++i) {
        const float restLength = length(rest);
        if (restLength < kMinMove) break;
        const Vec3 direction = rest / restLength;
        Sweep hit;
        if (!cast(at, direction, restLength + settings_.skin, hit, move)) {
            at = at + rest;
            break;
        }
        const float travel = std::clamp(hit.distance - settings_.skin, 0.0f, restLength);
        at = at + direction * travel;
        rest = direction * (restLength - travel);
        push(hit, velocity, dt, move);
        Vec3 normal = hit.normal;
        // Dynamic bodies are pushed, not climbed: on the ground they are walls whatever their edges' slope.
        const bool movable = world_.bodyType(hit.body) == BodyType::Dynamic;
        if (normal.y < walkable || (movable && grounded_)) {
            const Vec3 walk = horizontal(rest);
            if (grounded_ && !movable && !stepped && normal.y > -0.1f && length(walk) > kMinMove &&
                dot(walk, normal) < 0 && stepUp(at, walk, move)) {
                stepped = true;
                move.climbedStep = true;
                rest = {0, rest.y > 0 ? rest.y : 0, 0};
                continue;
            }
            // On the ground a steep surface is a wall: walking into it does not lift the character up it.
            const Vec3 across = horizontal(normal);
            if (grounded_ && normal.y > 0 && length(across) > 1e-4f) normal = across / length(across);
        } else if (verticalSpeed_ < 0) {
            verticalSpeed_ = 0;  // landed
        }
        if (normal.y < -0.5f && verticalSpeed_ > 0) verticalSpeed_ = 0;  // hit its head
        Vec3 next = rest - normal * dot(rest, normal);
        // Between two surfaces: along their crease, so that it does not bounce from one into the other.
        if (haveFirst && dot(next, firstNormal) < 0) {
            const Vec3 crease = cross(firstNormal, normal);
            const float creaseLength2 = dot(crease, crease);
            next = creaseLength2 > 1e-8f ? crease * (dot(next, crease) / creaseLength2) : Vec3{};
        }
        firstNormal = normal;
        haveFirst = true;
        rest = next;
    }
    return at;
}

void CharacterController::findGround(Vec3& at, float distance, bool snap, CharacterMove& move) {
    Sweep hit;
    grounded_ = false;
    ground_ = {};
    groundNormal_ = kUp;
    if (!cast(at, -kUp, distance + settings_.skin, hit, move)) return;
    groundNormal_ = hit.normal;
    // Steeper ground holds nothing: the character slides down it.
    if (hit.normal.y < std::cos(settings_.maxSlope)) return;
    grounded_ = true;
    ground_ = hit.body;
    groundPoint_ = hit.point;
    if (snap) at = at - kUp * std::max(0.0f, hit.distance - settings_.skin);
}

CharacterMove CharacterController::update(float dt, Vec3 walkVelocity) {
    static constexpr const char* kWhere = "CharacterController::update";
    detail::requireWithin(kWhere, "dt", dt, limits::kMinTimeStep, limits::kMaxTimeStep, "s");
    detail::requireFinite(kWhere, "walkVelocity", walkVelocity);
    CharacterMove move;
    const float gravity = world_.settings().gravity.y;
    if (grounded_ && !world_.isValid(ground_)) grounded_ = false, ground_ = {};

    // What it stands on moves it through the step; a dynamic body bears its weight.
    Vec3 carry;
    if (grounded_ && world_.bodyType(ground_) != BodyType::Static) {
        const Vec3 arm = groundPoint_ - world_.centerOfMass(ground_);
        carry = (world_.linearVelocity(ground_) + cross(world_.angularVelocity(ground_), arm)) * dt;
        if (world_.bodyType(ground_) == BodyType::Dynamic)
            world_.addForceAtPoint(ground_, {0, settings_.mass * gravity, 0}, groundPoint_);
    }

    if (jumpSpeed_ > 0) {
        verticalSpeed_ = jumpSpeed_;
        jumpSpeed_ = 0;
        grounded_ = false;
    } else if (grounded_) {
        verticalSpeed_ = 0;
    } else {
        verticalSpeed_ += gravity * dt;
    }
    const bool wasGrounded = grounded_;
    const Vec3 start = center();
    Vec3 at = slide(start, {walkVelocity.x * dt, verticalSpeed_ * dt, walkVelocity.z * dt}, dt, move);
    // Sliding down a slope or along a wall falls only as fast as the surfaces let it.
    if (!grounded_ && verticalSpeed_ < 0) verticalSpeed_ = std::max(verticalSpeed_, (at.y - start.y) / dt);
    if (verticalSpeed_ <= 0) {
        findGround(at, wasGrounded ? settings_.groundSnap : 2 * settings_.skin, true, move);
    } else {
        grounded_ = false;
        ground_ = {};
    }
    at = at + carry;
    groundPoint_ = groundPoint_ + carry;
    const Vec3 before = feet_;
    feet_ = at - kUp * (0.5f * settings_.height);
    velocity_ = (feet_ - before) / dt;
    world_.moveKinematic(body_, center(), Quat{}, dt);
    return move;
}

bool CharacterController::jump(float speed) {
    detail::requireNonNegative("CharacterController::jump", "speed", speed);
    if (!grounded_) return false;
    jumpSpeed_ = speed;
    return true;
}

void CharacterController::teleport(Vec3 feet) {
    detail::requireInWorld("CharacterController::teleport", "feet", feet);
    feet_ = feet;
    grounded_ = false;
    ground_ = {};
    verticalSpeed_ = 0;
    velocity_ = {};
    world_.setTransform(body_, center(), Quat{});
    world_.setLinearVelocity(body_, {});
}

}  // namespace rubble
