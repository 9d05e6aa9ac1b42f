// Random programs of API calls: shapes, bodies and joints created and destroyed (stale and null handles included),
// steps of any length, forces, impulses, poses and velocities, settings changed between steps, and queries. Each
// program runs on two worlds in lockstep, one stepping on 1 thread and one on 2, which the engine promises end bit for
// bit alike. After every call:
// - both worlds did the same thing: the same handle, or the same refusal (a rubble::Error with the same message);
// - the body storage holds its invariants (every live slot points at a row that points back, every array has its
//   set's length) and counts the bodies the program holds;
// - the two worlds' states hash alike, and every body not frozen has a finite state.
// Queries must answer alike in both worlds. Bad numbers (one draw in sixteen is any float bit pattern) must be
// refused, never simulated.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "fuzz_support.h"
#include "rubble/error.h"
#include "rubble/world.h"
#include "world/world_access.h"

namespace {

using namespace rubble;
using fuzz::check;
using fuzz::FuzzInput;

constexpr std::size_t kMaxHandles = 256;  // bodies, shapes and joints each, live or not: keeps a step in milliseconds
constexpr int kMaxSteps = 40;

/// What a call did: the handle or value it returned, or the message it was refused with.
struct Outcome {
    bool refused = false;
    std::string message;
};

class Twins {
public:
    Twins() : worlds_{World(settingsFor(0)), World(settingsFor(1))} {}

    /// Runs `call` on both worlds and checks that they agree on whether and why it was refused.
    template <class Call>
    auto both(const char* what, Call call) {
        using Result = decltype(call(worlds_[0], 0));
        std::optional<Result> results[2];
        Outcome outcomes[2];
        for (int k = 0; k < 2; ++k) {
            try {
                results[k] = call(worlds_[k], k);
            } catch (const Error& e) {
                outcomes[k] = {true, e.what()};
            }
        }
        check(outcomes[0].refused == outcomes[1].refused && outcomes[0].message == outcomes[1].message,
              std::string(what) + ": 1 and 2 threads disagree: '" + outcomes[0].message + "' vs '" +
                  outcomes[1].message + "'");
        if (trace_)
            std::fprintf(stderr, "%s%s%s\n", what, outcomes[0].refused ? ": refused: " : "",
                         outcomes[0].message.c_str());
        if (outcomes[0].refused)
            check(!outcomes[0].message.empty(), std::string(what) + ": a refusal without words");
        else
            check(*results[0] == *results[1], std::string(what) + ": 1 and 2 threads returned different results");
        return results[0];
    }

    World& first() { return worlds_[0]; }
    WorldSettings settings = settingsFor(0);

    static WorldSettings settingsFor(int k) {
        WorldSettings s;
        s.threads = k + 1;
        return s;
    }

    void checkState(std::size_t liveBodies) {
        for (World& w : worlds_) {
            const std::string problem = detail::WorldAccess::of(w).bodies.checkInvariants();
            check(problem.empty(), "body storage: " + problem);
            check(w.bodyCount() == liveBodies, "the world counts " + std::to_string(w.bodyCount()) +
                                                   " bodies, the program holds " + std::to_string(liveBodies));
        }
        check(worlds_[0].stateHash() == worlds_[1].stateHash(), "1 and 2 threads reached different states");
    }

private:
    World worlds_[2];
    /// RUBBLE_FUZZ_TRACE=1 prints every call and its refusal, to read what a failing program did.
    bool trace_ = std::getenv("RUBBLE_FUZZ_TRACE") != nullptr;
};

Vec3 vec(FuzzInput& in, float range) {
    return {in.mostlyIn(-range, range), in.mostlyIn(-range, range), in.mostlyIn(-range, range)};
}

Quat rotation(FuzzInput& in) {
    Quat q{in.in(-1, 1), in.in(-1, 1), in.in(-1, 1), in.in(-1, 1)};
    if ((in.byte() & 15) != 0) {  // mostly unit; otherwise as drawn, which the API refuses unless nearly unit
        const float n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
        if (n > 1e-3f)
            q = {q.x / n, q.y / n, q.z / n, q.w / n};
        else
            q = Quat{};
    }
    return q;
}

ShapeDef shapeDef(FuzzInput& in) {
    switch (in.below(7)) {
        case 0:
            return SphereDef{in.mostlyIn(0.05f, 2)};
        case 1:
            return BoxDef{{in.mostlyIn(0.05f, 2), in.mostlyIn(0.05f, 2), in.mostlyIn(0.05f, 2)}};
        case 2:
            return CapsuleDef{in.mostlyIn(0.05f, 1), in.mostlyIn(0, 1)};
        case 3: {
            ConvexHullDef hull;
            const std::uint32_t n = 4 + in.below(12);
            for (std::uint32_t i = 0; i < n; ++i) hull.points.push_back(vec(in, 1));
            return hull;
        }
        case 4: {
            CompoundDef compound;
            const std::uint32_t n = 1 + in.below(3);
            for (std::uint32_t i = 0; i < n; ++i) {
                CompoundChildDef child;
                if (in.flag())
                    child.shape = SphereDef{in.mostlyIn(0.05f, 1)};
                else
                    child.shape = BoxDef{{in.mostlyIn(0.05f, 1), in.in(0.05f, 1), in.in(0.05f, 1)}};
                child.local = Transform{vec(in, 1), rotation(in)};
                compound.children.push_back(child);
            }
            return compound;
        }
        case 5: {
            const float h = in.mostlyIn(1, 30), y = in.in(-2, 2);
            TriangleMeshDef mesh;
            mesh.vertices = {{-h, y, -h}, {h, y + in.in(-1, 1), -h}, {h, y, h}, {-h, y + in.in(-1, 1), h}};
            mesh.indices = {0, 2, 1, 0, 3, 2};
            if (in.flag()) mesh.indices.push_back(in.byte());  // not a whole triangle, or out of range
            return mesh;
        }
        default: {
            HeightfieldDef field;
            field.rows = 2 + in.below(4);
            field.columns = 2 + in.below(4);
            for (std::uint32_t i = 0; i < field.rows * field.columns; ++i) field.heights.push_back(in.mostlyIn(-1, 1));
            field.spacing = {in.in(0.5f, 8), in.in(0.5f, 2), in.in(0.5f, 8)};
            return field;
        }
    }
}

/// A step's events as text, to compare the twins' (the same on any thread count).
std::string describeEvents(const World& w) {
    std::string out;
    const auto pair = [&](char kind, BodyId a, BodyId b) {
        out += kind + std::to_string(a.index) + "," + std::to_string(b.index) + " ";
    };
    for (const ContactBeginEvent& e : w.contactEvents().begins) pair('b', e.a, e.b);
    for (const ContactEndEvent& e : w.contactEvents().ends) pair('e', e.a, e.b);
    for (const ContactHitEvent& e : w.contactEvents().hits) pair('h', e.a, e.b);
    for (const SensorBeginEvent& e : w.sensorEvents().begins) pair('s', e.sensor, e.visitor);
    for (const SensorEndEvent& e : w.sensorEvents().ends) pair('t', e.sensor, e.visitor);
    return out;
}

template <class Handle>
Handle pick(FuzzInput& in, const std::vector<Handle>& handles) {
    if (handles.empty() || (in.byte() & 31) == 0) return Handle{in.byte(), in.byte()};  // null, stale or unknown
    return handles[in.below(static_cast<std::uint32_t>(handles.size()))];
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    FuzzInput in(data, size);
    Twins twins;
    std::vector<ShapeId> shapes;
    std::vector<BodyId> bodies;
    std::vector<JointId> joints;
    int steps = 0;
    auto liveBodies = [&] {
        return static_cast<std::size_t>(
            std::count_if(bodies.begin(), bodies.end(), [&](BodyId b) { return twins.first().isValid(b); }));
    };

    while (!in.empty() && steps < kMaxSteps) {
        switch (in.below(14)) {
            case 0: {
                const ShapeDef def = shapeDef(in);
                if (shapes.size() == kMaxHandles) break;
                if (auto id = twins.both("createShape", [&](World& w, int) { return w.createShape(def); }))
                    shapes.push_back(*id);
                break;
            }
            case 1: {
                if (bodies.size() == kMaxHandles) break;
                BodyDef def;
                def.type = static_cast<BodyType>(in.below(3));
                def.shape = pick(in, shapes);
                def.position = vec(in, 20);
                def.orientation = rotation(in);
                def.linearVelocity = vec(in, 10);
                def.angularVelocity = vec(in, 10);
                def.material = {in.mostlyIn(0, 1), in.mostlyIn(0, 1), in.mostlyIn(10, 5000)};
                def.filter = {1u << in.below(4), in.flag() ? 0xFFFFFFFFu : in.u32()};
                def.linearDamping = in.mostlyIn(0, 1);
                def.gravityScale = in.mostlyIn(-1, 2);
                def.allowSleep = in.flag();
                def.bullet = in.flag();
                // Derived from what was drawn, not drawn anew: the corpus and the findings keep their meaning.
                def.contactEvents = def.allowSleep != def.bullet;
                def.sensor = def.filter.category == 8 && def.bullet;
                def.contactResponse = !(def.filter.category == 4 && def.bullet);
                if (auto id = twins.both("createBody", [&](World& w, int) { return w.createBody(def); }))
                    bodies.push_back(*id);
                break;
            }
            case 2: {
                const BodyId id = pick(in, bodies);
                twins.both("destroyBody", [&](World& w, int) { return (w.destroyBody(id), 0); });
                break;
            }
            case 3: {
                float dt = 1.0f / 60;
                switch (in.below(6)) {
                    case 0:
                        dt = 1.0f / 120;
                        break;
                    case 1:
                        dt = 1.0f / 30;
                        break;
                    case 2:
                        dt = in.in(1e-5f, 0.1f);
                        break;
                    case 3:
                        dt = in.bits();
                        break;
                    default:
                        break;
                }
                std::string events[2];
                twins.both("step", [&](World& w, int k) { return (w.step(dt), events[k] = describeEvents(w), 0); });
                check(events[0] == events[1], "a step's events differ on 1 and 2 threads");
                ++steps;
                break;
            }
            case 4: {
                const BodyId id = pick(in, bodies);
                const Vec3 v = vec(in, 100), p = vec(in, 20);
                const std::uint32_t kind = in.below(6);
                twins.both("force or impulse", [&](World& w, int) {
                    switch (kind) {
                        case 0:
                            w.addForce(id, v);
                            break;
                        case 1:
                            w.addTorque(id, v);
                            break;
                        case 2:
                            w.addForceAtPoint(id, v, p);
                            break;
                        case 3:
                            w.applyLinearImpulse(id, v);
                            break;
                        case 4:
                            w.applyAngularImpulse(id, v);
                            break;
                        default:
                            w.applyImpulseAtPoint(id, v, p);
                            break;
                    }
                    return 0;
                });
                break;
            }
            case 5: {
                const BodyId id = pick(in, bodies);
                const Vec3 v = vec(in, 20);
                const Quat q = rotation(in);
                const std::uint32_t kind = in.below(3);
                std::string contacts[2];
                // A kinematic body is moved to the pose instead of set there (every third time), and every call also
                // turns the body's events on or off and lists its contacts, with no input drawn for them: the corpus
                // and the findings keep their meaning.
                twins.both("pose, velocity, kinematic move, events or contacts", [&](World& w, int k) {
                    if (kind == 0 && w.bodyType(id) == BodyType::Kinematic && q.w > 0.5f)
                        w.moveKinematic(id, v, q, 1.0f / 60);
                    else if (kind == 0)
                        w.setTransform(id, v, q);
                    else if (kind == 1)
                        w.setLinearVelocity(id, v);
                    else
                        w.setAngularVelocity(id, v);
                    w.setContactEvents(id, q.x > 0);
                    std::vector<BodyContact> found;
                    w.contactsOf(id, found);
                    for (const BodyContact& c : found)
                        contacts[k] += std::to_string(c.other.index) + ":" + std::to_string(c.pointCount) + " ";
                    return 0;
                });
                check(contacts[0] == contacts[1], "contactsOf answered differently on 1 and 2 threads");
                break;
            }
            case 6: {
                WorldSettings s = twins.settings;
                s.substeps = in.flag() ? static_cast<int>(in.byte()) - 8 : 1 + static_cast<int>(in.below(4));
                s.velocityIterations = static_cast<int>(in.below(5));
                s.positionIterations = static_cast<int>(in.below(3));
                s.effects = EffectSet{in.byte() & EffectSet::all().bits};
                s.broadPhase = static_cast<BroadPhaseKind>(in.below(3));
                s.integrator = static_cast<Integrator>(in.below(4));
                s.solver.positionCorrection = static_cast<PositionCorrection>(in.below(3));
                s.solver.warmStarting = in.flag();
                s.solver.seedRestingLoads = in.flag();
                s.gravity = vec(in, 20);
                s.contactMargin = in.mostlyIn(0.001f, 0.1f);
                if (twins.both("setSettings", [&](World& w, int k) {
                        WorldSettings mine = s;
                        mine.threads = k + 1;
                        w.setSettings(mine);
                        return 0;
                    }))
                    twins.settings = s;
                break;
            }
            case 7: {
                const Vec3 o = vec(in, 30), d = vec(in, 1);
                const float reach = in.mostlyIn(0, 100), radius = in.mostlyIn(0, 1);
                const ShapeId cast = pick(in, shapes);
                const std::uint32_t kind = in.below(5);
                auto describe = [&](World& w, int) {
                    std::vector<BodyId> found;
                    std::string answer;
                    auto add = [&](BodyId b, float distance) {
                        answer += std::to_string(b.index) + ":" + std::to_string(b.generation) + "@" +
                                  std::to_string(distance) + " ";
                    };
                    if (kind == 0) {
                        if (auto hit = w.castRay(o, d, reach)) add(hit->body, hit->distance);
                    } else if (kind == 1) {
                        if (auto hit = w.castSphere(o, radius, d, reach)) add(hit->body, hit->distance);
                    } else if (kind == 2) {
                        if (auto hit = w.castShape(cast, Transform{o, Quat{}}, d, reach)) add(hit->body, hit->distance);
                    } else if (kind == 3) {
                        w.overlapAabb(o - Vec3{radius, radius, radius} * 10, o + Vec3{radius, radius, radius} * 10,
                                      found);
                    } else {
                        w.overlapShape(cast, Transform{o, Quat{}}, found);
                    }
                    for (BodyId b : found) add(b, 0);
                    return answer;
                };
                std::string answers[2];
                twins.both("query", [&](World& w, int k) { return (answers[k] = describe(w, k), 0); });
                check(answers[0] == answers[1], "a query answered differently on 1 and 2 threads");
                break;
            }
            case 8: {
                if (joints.size() == kMaxHandles) break;
                const BodyId a = pick(in, bodies), b = pick(in, bodies);
                const Vec3 anchorA = vec(in, 1), anchorB = vec(in, 1);
                const std::uint32_t kind = in.below(4);
                const float number = in.mostlyIn(0, 50);
                auto make = [&](World& w, int) {
                    auto base = [&](JointBase& j) {
                        j.bodyA = a;
                        j.bodyB = b;
                        j.localAnchorA = anchorA;
                        j.localAnchorB = anchorB;
                        j.breakForce = number > 40 ? number : j.breakForce;
                    };
                    if (kind == 0) {
                        DistanceJointDef j;
                        base(j);
                        return w.createJoint(j);
                    }
                    if (kind == 1) {
                        SpringJointDef j;
                        base(j);
                        j.stiffness = number;
                        return w.createJoint(j);
                    }
                    if (kind == 2) {
                        BallJointDef j;
                        base(j);
                        return w.createJoint(j);
                    }
                    HingeJointDef j;
                    base(j);
                    j.enableLimit = number > 25;
                    j.lowerAngle = -1;
                    j.upperAngle = 0.5f;
                    j.enableMotor = number < 10;
                    j.motorSpeed = number;
                    j.maxMotorTorque = number;
                    return w.createJoint(j);
                };
                if (auto id = twins.both("createJoint", make)) joints.push_back(*id);
                break;
            }
            case 9: {
                const JointId id = pick(in, joints);
                twins.both("destroyJoint", [&](World& w, int) { return (w.destroyJoint(id), 0); });
                break;
            }
            case 10: {
                const BodyId id = pick(in, bodies);
                const Material m{in.mostlyIn(0, 1), in.mostlyIn(0, 1), in.mostlyIn(1, 5000)};
                const CollisionFilter f{in.u32(), in.u32()};
                const bool material = in.flag();
                twins.both("setMaterial or setFilter", [&](World& w, int) {
                    if (material)
                        w.setMaterial(id, m);
                    else
                        w.setFilter(id, f);
                    return 0;
                });
                break;
            }
            case 11: {
                const ShapeId id = pick(in, shapes);
                twins.both("destroyShape", [&](World& w, int) { return (w.destroyShape(id), 0); });
                break;
            }
            case 12: {
                const BodyId id = pick(in, bodies);
                twins.both("wakeUp", [&](World& w, int) { return (w.wakeUp(id), 0); });
                break;
            }
            default: {
                const JointId id = pick(in, joints);
                const float speed = in.mostlyIn(-10, 10), torque = in.mostlyIn(0, 100);
                const bool enable = in.flag();
                twins.both("setHingeMotor",
                           [&](World& w, int) { return (w.setHingeMotor(id, enable, speed, torque), 0); });
                break;
            }
        }
        twins.checkState(liveBodies());
        for (BodyId b : bodies) {
            if (!twins.first().isValid(b) || twins.first().isFrozen(b)) continue;
            const Vec3 p = twins.first().position(b), v = twins.first().linearVelocity(b);
            // Each component on its own: a sum of finite ones can overflow (a velocity of 3e38 m/s is finite).
            bool finite = true;
            for (const float c : {p.x, p.y, p.z, v.x, v.y, v.z}) finite = finite && std::isfinite(c);
            check(finite, "a body not frozen has a non-finite state");
        }
    }
    return 0;
}
