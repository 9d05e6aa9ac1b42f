#include "runtime/input_queue.h"

#include <type_traits>

#include "rubble/error.h"
#include "world/validation.h"

namespace rubble::detail {

namespace {

template <class... F>
struct Overloaded : F... {
    using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

}  // namespace

void validateCommand(const Command& command) {
    static constexpr const char* kWhere = "Runtime::submit";
    std::visit(
        Overloaded{
            [](const AddForceCommand& c) { requireFinite(kWhere, "AddForceCommand.force", c.force); },
            [](const AddForceAtPointCommand& c) {
                requireFinite(kWhere, "AddForceAtPointCommand.force", c.force);
                requireFinite(kWhere, "AddForceAtPointCommand.point", c.point);
            },
            [](const AddTorqueCommand& c) { requireFinite(kWhere, "AddTorqueCommand.torque", c.torque); },
            [](const ApplyImpulseCommand& c) { requireFinite(kWhere, "ApplyImpulseCommand.impulse", c.impulse); },
            [](const ApplyImpulseAtPointCommand& c) {
                requireFinite(kWhere, "ApplyImpulseAtPointCommand.impulse", c.impulse);
                requireFinite(kWhere, "ApplyImpulseAtPointCommand.point", c.point);
            },
            [](const ApplyAngularImpulseCommand& c) {
                requireFinite(kWhere, "ApplyAngularImpulseCommand.impulse", c.impulse);
            },
            [](const SetVelocityCommand& c) {
                requireFinite(kWhere, "SetVelocityCommand.linear", c.linear);
                requireFinite(kWhere, "SetVelocityCommand.angular", c.angular);
            },
            [](const SetTransformCommand& c) {
                requireFinite(kWhere, "SetTransformCommand.position", c.position);
                requireUnit(kWhere, "SetTransformCommand.orientation", c.orientation);
            },
            [](const MoveKinematicCommand& c) {
                requireFinite(kWhere, "MoveKinematicCommand.position", c.position);
                requireUnit(kWhere, "MoveKinematicCommand.orientation", c.orientation);
                if (!(c.duration >= 0) || !std::isfinite(c.duration))
                    fail(kWhere, "MoveKinematicCommand.duration must be finite and >= 0 (got " +
                                     std::to_string(c.duration) + ")");
            },
            [](const SetContactEventsCommand&) {},
            [](const WalkCharacterCommand& c) {
                requireFinite(kWhere, "WalkCharacterCommand.velocity", c.velocity);
                requireNonNegative(kWhere, "WalkCharacterCommand.jumpSpeed", c.jumpSpeed);
            },
            [](const SpawnBodyCommand&) {},  // the world validates the BodyDef; errors go to the future
            [](const RemoveBodyCommand&) {},
            [](const CastRayCommand& c) {
                requireFinite(kWhere, "CastRayCommand.origin", c.origin);
                requireFinite(kWhere, "CastRayCommand.direction", c.direction);
                if (c.direction == Vec3{}) fail(kWhere, "CastRayCommand.direction is zero");
                if (std::isnan(c.maxDistance) || c.maxDistance < 0)
                    fail(kWhere, "CastRayCommand.maxDistance must be >= 0 (got " + std::to_string(c.maxDistance) + ")");
            },
        },
        command);
}

bool changesLayout(const Command& command) {
    return std::holds_alternative<SpawnBodyCommand>(command) || std::holds_alternative<RemoveBodyCommand>(command) ||
           std::holds_alternative<SetTransformCommand>(command);
}

void applyCommand(World& world, const Command& command, CommandTargets targets, Reply* reply,
                  std::vector<std::string>& errors) {
    try {
        std::visit(
            Overloaded{
                [&](const AddForceCommand& c) { world.addForce(c.body, c.force); },
                [&](const AddForceAtPointCommand& c) { world.addForceAtPoint(c.body, c.force, c.point); },
                [&](const AddTorqueCommand& c) { world.addTorque(c.body, c.torque); },
                [&](const ApplyImpulseCommand& c) { world.applyLinearImpulse(c.body, c.impulse); },
                [&](const ApplyImpulseAtPointCommand& c) { world.applyImpulseAtPoint(c.body, c.impulse, c.point); },
                [&](const ApplyAngularImpulseCommand& c) { world.applyAngularImpulse(c.body, c.impulse); },
                [&](const SetVelocityCommand& c) {
                    world.setLinearVelocity(c.body, c.linear);
                    world.setAngularVelocity(c.body, c.angular);
                },
                [&](const SetTransformCommand& c) { world.setTransform(c.body, c.position, c.orientation); },
                [&](const MoveKinematicCommand& c) { targets.moves.start(world, c, targets.stepSeconds); },
                [&](const WalkCharacterCommand& c) { targets.characters.walk(c); },
                [&](const SetContactEventsCommand& c) { world.setContactEvents(c.body, c.enabled); },
                [&](const SpawnBodyCommand& c) {
                    const BodyId id = world.createBody(c.def);
                    if (reply && std::holds_alternative<std::promise<BodyId>>(*reply))
                        std::get<std::promise<BodyId>>(*reply).set_value(id);
                },
                [&](const RemoveBodyCommand& c) { world.destroyBody(c.body); },
                [&](const CastRayCommand& c) {
                    auto hit = world.castRay(c.origin, c.direction, c.maxDistance, c.filter);
                    using RayPromise = std::promise<std::optional<RayHit>>;
                    if (reply && std::holds_alternative<RayPromise>(*reply))
                        std::get<RayPromise>(*reply).set_value(hit);
                },
            },
            command);
    } catch (const Error& e) {
        if (reply && !std::holds_alternative<std::monostate>(*reply)) {
            std::visit(
                [&](auto& promise) {
                    if constexpr (!std::is_same_v<std::decay_t<decltype(promise)>, std::monostate>)
                        promise.set_exception(std::current_exception());
                },
                *reply);
        } else {
            errors.emplace_back(e.what());
        }
    }
}

}  // namespace rubble::detail
