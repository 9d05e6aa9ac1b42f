// The figures a scene declares, measured over a run (include/rubble/scene.h, SceneFigureMeter).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <variant>

#include "rubble/scene.h"
#include "rubble/world.h"

namespace rubble {
namespace {

/// LateApex looks this far back from the end of the run: longer than the period of a 4 m bounce (1.8 s).
constexpr double kApexWindow = 2.0;
/// Moved counts bodies that ended farther than this from their start, m.
constexpr double kMovedDistance = 0.1;
/// MaxHop starts watching after this long, s: bodies placed a little above the ground land first.
constexpr double kHopSettling = 1.0;
/// MaxHop measures the terrain's slope between heights this far apart, m.
constexpr float kSlopeStep = 0.02f;

bool wants(const std::vector<SceneFigure>& figures, SceneFigure f) {
    return std::find(figures.begin(), figures.end(), f) != figures.end();
}

std::string format(const char* pattern, double value) {
    char text[128];
    std::snprintf(text, sizeof text, pattern, value);
    return text;
}

}  // namespace

std::string_view sceneFigureName(SceneFigure f) {
    switch (f) {
        case SceneFigure::MaxDisplacement:
            return "max_displacement";
        case SceneFigure::Tunnelled:
            return "tunnelled";
        case SceneFigure::MaxSpeed:
            return "max_speed";
        case SceneFigure::FinalSpeed:
            return "final_speed";
        case SceneFigure::Moved:
            return "moved";
        case SceneFigure::Escaped:
            return "escaped";
        case SceneFigure::LateApex:
            return "late_apex";
        case SceneFigure::JointStretch:
            return "joint_stretch";
        case SceneFigure::MaxHop:
            return "max_hop";
    }
    return "unknown";
}

SceneFigureMeter::SceneFigureMeter(const Scene& scene, const World& world, const std::vector<BodyId>& bodies)
    : figures_(scene.figures) {
    for (const BodyId id : bodies) {
        if (world.bodyType(id) == BodyType::Static) {
            const Vec3 p = world.position(id);
            staticMin_ =
                anyStatic_ ? Vec3{std::min(staticMin_.x, p.x), std::min(staticMin_.y, p.y), std::min(staticMin_.z, p.z)}
                           : p;
            staticMax_ =
                anyStatic_ ? Vec3{std::max(staticMax_.x, p.x), std::max(staticMax_.y, p.y), std::max(staticMax_.z, p.z)}
                           : p;
            anyStatic_ = true;
        }
        if (world.bodyType(id) != BodyType::Dynamic) continue;
        dynamic_.push_back(id);
        starts_.push_back(world.centerOfMass(id));
    }
    if (wants(figures_, SceneFigure::MaxHop))
        for (std::size_t i = 0; i < bodies.size() && i < scene.bodies.size(); ++i)
            if (const auto* sphere = std::get_if<SphereDef>(&scene.shapes[scene.bodies[i].shape]);
                sphere && world.bodyType(bodies[i]) == BodyType::Dynamic)
                spheres_.push_back({bodies[i], sphere->radius});
    if (!wants(figures_, SceneFigure::JointStretch)) return;
    for (const SceneJoint& j : scene.joints) {
        if (std::holds_alternative<SpringJointDef>(j.def) || j.bodyA >= bodies.size() || j.bodyB >= bodies.size())
            continue;
        const Transform a = world.transform(bodies[j.bodyA]), b = world.transform(bodies[j.bodyB]);
        JointAnchors anchors{bodies[j.bodyA], bodies[j.bodyB], applyInverse(a, j.anchorA), applyInverse(b, j.anchorB)};
        if (const auto* rod = std::get_if<DistanceJointDef>(&j.def))
            anchors.length = rod->length ? *rod->length : length(j.anchorB - j.anchorA);
        joints_.push_back(anchors);
    }
}

void SceneFigureMeter::record(const World& world) {
    time_ += world.settings().timeStep;
    if (time_ > kHopSettling)
        for (const auto& [id, radius] : spheres_) {
            // The gap along the surface's normal: on a slope a resting sphere's centre is radius / cos(slope) above
            // the surface straight below it. The slope comes from the heights a few centimetres to each side.
            const Vec3 c = world.centerOfMass(id);
            float ground = 0, east = 0, west = 0, north = 0, south = 0;
            if (!world.terrainHeightAt(c.x, c.z, ground) || !world.terrainHeightAt(c.x + kSlopeStep, c.z, east) ||
                !world.terrainHeightAt(c.x - kSlopeStep, c.z, west) ||
                !world.terrainHeightAt(c.x, c.z + kSlopeStep, north) ||
                !world.terrainHeightAt(c.x, c.z - kSlopeStep, south))
                continue;
            const double gx = (east - west) / (2 * kSlopeStep), gz = (north - south) / (2 * kSlopeStep);
            const double gap = (c.y - ground) / std::sqrt(1 + gx * gx + gz * gz) - radius;
            maxHop_ = std::max(maxHop_, gap);
        }
    const bool speed = wants(figures_, SceneFigure::MaxSpeed), apex = wants(figures_, SceneFigure::LateApex);
    if (!speed && !apex) return;
    double highest = -INFINITY;
    for (const BodyId id : dynamic_) {
        if (speed) maxSpeed_ = std::max(maxSpeed_, static_cast<double>(length(world.linearVelocity(id))));
        if (apex) highest = std::max(highest, static_cast<double>(world.centerOfMass(id).y));
    }
    if (!apex) return;
    apexes_.emplace_back(time_, highest);
    const auto old =
        std::find_if(apexes_.begin(), apexes_.end(), [&](const auto& a) { return a.first >= time_ - kApexWindow; });
    apexes_.erase(apexes_.begin(), old);
}

double SceneFigureMeter::value(const World& world, SceneFigure figure) const {
    for (const Result& r : results(world))
        if (r.figure == figure) return r.value;
    return NAN;
}

std::vector<SceneFigureMeter::Result> SceneFigureMeter::results(const World& world) const {
    std::vector<Result> out;
    const auto distanceFromStart = [&](std::size_t i) {
        return static_cast<double>(length(world.centerOfMass(dynamic_[i]) - starts_[i]));
    };
    const double count = static_cast<double>(dynamic_.size());
    for (const SceneFigure f : figures_) {
        switch (f) {
            case SceneFigure::MaxDisplacement: {
                double largest = 0;
                for (std::size_t i = 0; i < dynamic_.size(); ++i) largest = std::max(largest, distanceFromStart(i));
                out.push_back({f, largest, format("largest displacement from start: %.4f m", largest)});
                break;
            }
            case SceneFigure::Tunnelled: {
                double tunnelled = 0;
                for (const BodyId id : dynamic_) {
                    const Vec3 c = world.centerOfMass(id);
                    float h = 0;
                    if (world.terrainHeightAt(c.x, c.z, h) && c.y < h - 0.5f) ++tunnelled;
                }
                out.push_back(
                    {f, tunnelled,
                     format("bodies tunnelled through the terrain: %.0f", tunnelled) + format(" of %.0f", count)});
                break;
            }
            case SceneFigure::MaxSpeed:
                out.push_back({f, maxSpeed_, format("largest speed during the run: %.4f m/s", maxSpeed_)});
                break;
            case SceneFigure::FinalSpeed: {
                double fastest = 0;
                for (const BodyId id : dynamic_)
                    fastest = std::max(fastest, static_cast<double>(length(world.linearVelocity(id))));
                out.push_back({f, fastest, format("largest speed at the end: %.4f m/s", fastest)});
                break;
            }
            case SceneFigure::Moved: {
                double moved = 0;
                for (std::size_t i = 0; i < dynamic_.size(); ++i) moved += distanceFromStart(i) > kMovedDistance;
                out.push_back(
                    {f, moved, format("bodies that moved more than 0.1 m: %.0f", moved) + format(" of %.0f", count)});
                break;
            }
            case SceneFigure::Escaped: {
                double escaped = 0;
                for (const BodyId id : dynamic_) {
                    const Vec3 c = world.centerOfMass(id);
                    const bool inside = anyStatic_ && c.x >= staticMin_.x && c.x <= staticMax_.x &&
                                        c.y >= staticMin_.y && c.y <= staticMax_.y && c.z >= staticMin_.z &&
                                        c.z <= staticMax_.z;
                    escaped += !inside;
                }
                out.push_back(
                    {f, escaped,
                     format("bodies outside the static bodies' box: %.0f", escaped) + format(" of %.0f", count)});
                break;
            }
            case SceneFigure::JointStretch: {
                double largest = 0;
                for (const JointAnchors& j : joints_) {
                    const double apart =
                        length(apply(world.transform(j.b), j.localB) - apply(world.transform(j.a), j.localA));
                    largest = std::max(largest, std::fabs(apart - j.length));
                }
                out.push_back({f, largest, format("largest joint stretch: %.4f m", largest)});
                break;
            }
            case SceneFigure::MaxHop:
                out.push_back({f, maxHop_, format("highest hop of a sphere over the terrain: %.4f m", maxHop_)});
                break;
            case SceneFigure::LateApex: {
                double highest = -INFINITY;
                for (const auto& a : apexes_) highest = std::max(highest, a.second);
                out.push_back({f, highest, format("highest centre over the last 2 s: %.4f m", highest)});
                break;
            }
        }
    }
    return out;
}

}  // namespace rubble
