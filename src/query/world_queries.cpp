// World's scene queries: validation at the API boundary, then a walk over the static BVH and the moving bodies' tree
// (query_cache.h) that hands each candidate body, or mesh triangle, to the exact test of its shape.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "bounds/bounds.h"
#include "query/query_cache.h"
#include "query/ray_cast.h"
#include "query/shape_cast.h"
#include "query/tree_queries.h"
#include "rubble/error.h"
#include "world/world_impl.h"

namespace rubble {
namespace {

using detail::Aabb;
using detail::Ray;
using detail::RayResult;
using detail::ShapeKind;
using detail::StaticBvh;
using detail::SurfaceHit;
using detail::SweepHit;
using detail::SweepResult;

// ---- Validation --------------------------------------------------------------------------------------------------

/// The unit direction of a user's direction (normalised in double, so that tiny but non-zero directions work).
Vec3 requireDirection(const char* where, Vec3 d) {
    requireFinite(where, "direction", d);
    const double len = std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z);
    if (!(len > 0)) fail(where, "direction must not be zero " + describe(d));
    return {float(d.x / len), float(d.y / len), float(d.z / len)};
}

/// maxDistance may be +infinity (an unbounded ray), not NaN or negative.
float requireMaxDistance(const char* where, float maxDistance) {
    if (std::isnan(maxDistance)) fail(where, "maxDistance is not a number (nan)");
    if (maxDistance < 0) fail(where, "maxDistance must be >= 0 (got " + detail::formatNumber(maxDistance) + ")");
    return maxDistance;
}

Transform requirePose(const char* where, const char* name, const Transform& pose) {
    requireFinite(where, (std::string(name) + ".position").c_str(), pose.position);
    return {pose.position, requireUnit(where, (std::string(name) + ".rotation").c_str(), pose.rotation)};
}

/// The shape a cast or overlap moves: any kind a moving body can have.
const detail::Shape& requireQueryShape(const World::Impl& w, ShapeId id, const char* where) {
    const detail::Shape& shape = w.shapeOf(id, where);
    if (shape.staticOnly())
        fail(where, "shape " + std::to_string(id.index) +
                        " is a triangle mesh or heightfield; only spheres, boxes, capsules, hulls and compounds can be "
                        "cast or tested for overlap");
    return shape;
}

// ---- Bodies as the queries see them -------------------------------------------------------------------------------

/// A body that passed the filter, with what its exact test needs.
struct Candidate {
    BodyId id;
    const detail::Shape* shape = nullptr;
    Transform pose;  ///< of the shape's local origin
};

/// Turns tree primitives into candidates, applying the filter. A mesh's triangles come in runs, so the last body's
/// answer is kept.
class BodyResolver {
public:
    BodyResolver(const World::Impl& w, const QueryFilter& f) : w_(w), filter_(f) {}

    const Candidate* staticBody(std::uint32_t slot) {
        if (lastSet_ == 0 && lastIndex_ == slot) return lastAccepted_ ? &last_ : nullptr;
        lastSet_ = 0, lastIndex_ = slot, lastAccepted_ = false;
        const detail::StaticBodies& b = w_.bodies.statics;
        const detail::BodySlot& s = w_.bodies.slots()[slot];
        const std::uint32_t i = s.dense;
        const BodyId id = w_.bodies.idAt(slot);
        if (!filter_.includeSensors && (b.flags[i] & detail::kFlagSensor)) return nullptr;
        if (!accepts(b.filterCategory[i], b.filterMask[i], id)) return nullptr;
        last_ = {id, &w_.shapes[b.shape[i]], {{b.px[i], b.py[i], b.pz[i]}, {b.qx[i], b.qy[i], b.qz[i], b.qw[i]}}};
        lastAccepted_ = true;
        return &last_;
    }

    const Candidate* movingBody(std::uint32_t dense) {
        if (lastSet_ == 1 && lastIndex_ == dense) return lastAccepted_ ? &last_ : nullptr;
        lastSet_ = 1, lastIndex_ = dense, lastAccepted_ = false;
        const detail::MovingBodies& m = w_.bodies.moving;
        const bool kinematic = (m.flags[dense] & detail::kFlagKinematic) != 0;
        if (!(kinematic ? filter_.includeKinematic : filter_.includeDynamic)) return nullptr;
        if (!filter_.includeSensors && (m.flags[dense] & detail::kFlagSensor)) return nullptr;
        const std::uint32_t slot = m.slot[dense];
        const BodyId id = w_.bodies.idAt(slot);
        if (!accepts(m.filterCategory[dense], m.filterMask[dense], id)) return nullptr;
        const Quat q = w_.orientationOf(dense);
        last_ = {id,
                 &w_.shapes[m.shape[dense]],
                 {w_.comOf(dense) - rotate(q, {m.lcx[dense], m.lcy[dense], m.lcz[dense]}), q}};
        lastAccepted_ = true;
        return &last_;
    }

private:
    bool accepts(std::uint32_t category, std::uint32_t mask, BodyId id) const {
        if ((category & filter_.mask) == 0 || (filter_.category & mask) == 0) return false;
        if (id == filter_.ignore) return false;
        return !filter_.accept || filter_.accept(id);
    }

    const World::Impl& w_;
    const QueryFilter& filter_;
    int lastSet_ = -1;  ///< 0 static, 1 moving
    std::uint32_t lastIndex_ = 0;
    bool lastAccepted_ = false;
    Candidate last_;
};

Transform compose(const Transform& outer, const Transform& inner) {
    return {apply(outer, inner.position), outer.rotation * inner.rotation};
}

float maxAbs(Vec3 v) { return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}); }

/// Calls onPrimitive(candidate, triangle) for every accepted body (triangle = kWholeBody) or mesh triangle whose
/// box the box [lo, hi] swept along dir enters within maxT (a ray when lo == hi), nearest boxes first per tree.
/// onPrimitive may lower maxT. Static trees first, then the moving bodies' tree.
template <class OnPrimitive>
void sweepWorld(const World::Impl& w, const detail::QueryTrees& trees, const QueryFilter& filter, Vec3 lo, Vec3 hi,
                Vec3 dir, const float& maxT, OnPrimitive&& onPrimitive) {
    BodyResolver bodies(w, filter);
    const Vec3 center = (lo + hi) * 0.5f, extent = (hi - lo) * 0.5f;
    const float queryScale = maxAbs(lo) + maxAbs(hi);
    if (filter.includeStatic) {
        const detail::TreeSweep sweep(center, dir, extent, detail::boxPad(trees.staticScale + queryScale));
        for (const StaticBvh::Tree* tree : trees.statics)
            detail::sweepTree(*tree, sweep, maxT, [&](const StaticBvh::PrimitiveRef& p, float) {
                if (const Candidate* c = bodies.staticBody(p.body)) onPrimitive(*c, p.triangle);
            });
    }
    if (filter.includeKinematic || filter.includeDynamic) {
        const detail::TreeSweep sweep(center, dir, extent, detail::boxPad(trees.movingScale + queryScale));
        for (const StaticBvh::Tree* tree : trees.moving)
            detail::sweepTree(*tree, sweep, maxT, [&](const StaticBvh::PrimitiveRef& p, float) {
                if (const Candidate* c = bodies.movingBody(p.body)) onPrimitive(*c, detail::kWholeBody);
            });
    }
}

/// The same for bodies and triangles whose box overlaps [lo, hi].
template <class OnPrimitive>
void overlapWorld(const World::Impl& w, const detail::QueryTrees& trees, const QueryFilter& filter, Vec3 lo, Vec3 hi,
                  OnPrimitive&& onPrimitive) {
    BodyResolver bodies(w, filter);
    const float queryScale = maxAbs(lo) + maxAbs(hi);
    if (filter.includeStatic) {
        const float pad = detail::boxPad(trees.staticScale + queryScale);
        const Vec3 p{pad, pad, pad};
        for (const StaticBvh::Tree* tree : trees.statics)
            detail::overlapTree(*tree, lo - p, hi + p, [&](const StaticBvh::PrimitiveRef& ref) {
                if (const Candidate* c = bodies.staticBody(ref.body)) onPrimitive(*c, ref.triangle);
            });
    }
    if (filter.includeKinematic || filter.includeDynamic) {
        const float pad = detail::boxPad(trees.movingScale + queryScale);
        const Vec3 p{pad, pad, pad};
        for (const StaticBvh::Tree* tree : trees.moving)
            detail::overlapTree(*tree, lo - p, hi + p, [&](const StaticBvh::PrimitiveRef& ref) {
                if (const Candidate* c = bodies.movingBody(ref.body)) onPrimitive(*c, detail::kWholeBody);
            });
    }
}

// ---- Exact tests per candidate ------------------------------------------------------------------------------------

/// Calls emit(t, worldNormal, child) for each solid part of the candidate (the body, or each compound child) that the
/// ray enters within ray.maxT.
template <class Emit>
void rayBody(const Candidate& c, const Ray& ray, bool fromInside, Emit&& emit) {
    const Ray local = detail::toLocal(c.pose, ray);
    auto test = [&](const detail::Shape& part, const Ray& partRay, const Quat& toWorld, std::uint32_t child) {
        SurfaceHit h;
        const RayResult r = detail::rayConvex(part, partRay, h);
        if (r == RayResult::Miss || (r == RayResult::StartsInside && !fromInside)) return;
        emit(h.t, r == RayResult::StartsInside ? -ray.dir : rotate(toWorld, h.normal), child);
    };
    if (c.shape->kind != ShapeKind::Compound) return test(*c.shape, local, c.pose.rotation, kNoIndex);
    for (std::uint32_t i = 0; i < c.shape->children.size(); ++i) {
        const detail::CompoundChild& child = c.shape->children[i];
        test(*child.shape, detail::toLocal(child.local, local), c.pose.rotation * child.local.rotation, i);
    }
}

/// One convex piece of a cast or overlap shape at its pose; child is its index in a compound, else kNoIndex.
struct Part {
    const detail::Shape* shape;
    Transform pose;
    std::uint32_t child;
};

std::vector<Part> partsOf(const detail::Shape& shape, const Transform& pose) {
    std::vector<Part> parts;
    if (shape.kind != ShapeKind::Compound) {
        parts.push_back({&shape, pose, kNoIndex});
    } else {
        for (std::uint32_t i = 0; i < shape.children.size(); ++i)
            parts.push_back({shape.children[i].shape.get(), compose(pose, shape.children[i].local), i});
    }
    return parts;
}

Aabb partsBounds(const std::vector<Part>& parts) {
    Aabb box = detail::worldBounds(*parts.front().shape, parts.front().pose);
    for (const Part& p : parts) {
        const Aabb b = detail::worldBounds(*p.shape, p.pose);
        box.min = {std::min(box.min.x, b.min.x), std::min(box.min.y, b.min.y), std::min(box.min.z, b.min.z)};
        box.max = {std::max(box.max.x, b.max.x), std::max(box.max.y, b.max.y), std::max(box.max.z, b.max.z)};
    }
    return box;
}

/// Sweeps a part against one convex piece of a body. A sphere against a sphere or capsule is a ray against the
/// piece grown by the radius; everything else goes through GJK.
SweepResult sweepPart(const Part& q, const detail::Shape& target, const Transform& targetPose, Vec3 dir, float maxT,
                      SweepHit& hit) {
    if (q.shape->kind == ShapeKind::Sphere && (target.kind == ShapeKind::Sphere || target.kind == ShapeKind::Capsule)) {
        const float radius = q.shape->radius + target.radius;
        const Ray local = detail::toLocal(targetPose, Ray{q.pose.position, dir, maxT});
        SurfaceHit h;
        const RayResult r =
            target.kind == ShapeKind::Sphere
                ? detail::raySphere({}, radius, local, h)
                : detail::rayCapsule({0, -target.halfHeight, 0}, {0, target.halfHeight, 0}, radius, local, h);
        if (r != RayResult::Hit) return r == RayResult::Miss ? SweepResult::Miss : SweepResult::StartsInside;
        // The contact is on the target's surface: the swept centre less the cast sphere's radius along the normal.
        const Vec3 point = local.origin + local.dir * h.t - h.normal * q.shape->radius;
        hit = {h.t, apply(targetPose, point), rotate(targetPose.rotation, h.normal)};
        return SweepResult::Hit;
    }
    return detail::sweepConvex(detail::gjkShapeOf(*q.shape, q.pose), dir, maxT, detail::gjkShapeOf(target, targetPose),
                               hit);
}

/// Sweeps a part against one triangle (in the frame of meshPose). Spheres use the closed form; other parts GJK.
SweepResult sweepPartTriangle(const Part& q, const Vec3 (&tri)[3], const Transform& meshPose, Vec3 dir, float maxT,
                              bool backFaces, SweepHit& hit) {
    if (q.shape->kind == ShapeKind::Sphere) {
        const Quat toLocal = conjugate(meshPose.rotation);
        const Vec3 center = rotate(toLocal, q.pose.position - meshPose.position), localDir = rotate(toLocal, dir);
        const SweepResult r = detail::sweepSphereTriangle(center, q.shape->radius, localDir, maxT, tri[0], tri[1],
                                                          tri[2], backFaces, hit);
        if (r == SweepResult::Hit) hit = {hit.t, apply(meshPose, hit.point), rotate(meshPose.rotation, hit.normal)};
        return r;
    }
    if (detail::degenerateTriangle(tri[0], tri[1], tri[2])) return SweepResult::Miss;
    const Vec3 normal = rotate(meshPose.rotation, cross(tri[1] - tri[0], tri[2] - tri[0]));
    if (!backFaces && dot(normal, dir) >= 0) return SweepResult::Miss;
    return detail::sweepConvex(detail::gjkShapeOf(*q.shape, q.pose), dir, maxT, detail::gjkTriangle(tri, meshPose),
                               hit);
}

bool overlapPart(const Part& q, const detail::Shape& target, const Transform& targetPose) {
    if (q.shape->kind == ShapeKind::Sphere && target.kind == ShapeKind::Sphere) {
        const Vec3 d = q.pose.position - targetPose.position;
        const float r = q.shape->radius + target.radius;
        return dot(d, d) <= r * r;
    }
    return detail::overlapConvex(detail::gjkShapeOf(*q.shape, q.pose), detail::gjkShapeOf(target, targetPose));
}

bool overlapPartTriangle(const Part& q, const Vec3 (&tri)[3], const Transform& meshPose) {
    if (detail::degenerateTriangle(tri[0], tri[1], tri[2])) return false;
    if (q.shape->kind == ShapeKind::Sphere) {
        const Vec3 center = rotate(conjugate(meshPose.rotation), q.pose.position - meshPose.position);
        const Vec3 d = center - detail::closestPointOnTriangle(center, tri[0], tri[1], tri[2]);
        return dot(d, d) <= q.shape->radius * q.shape->radius;
    }
    return detail::overlapConvex(detail::gjkShapeOf(*q.shape, q.pose), detail::gjkTriangle(tri, meshPose));
}

/// Calls onPiece(shape, pose, child) for the body's convex pieces: the body itself, or each compound child.
template <class OnPiece>
void forPieces(const Candidate& c, OnPiece&& onPiece) {
    if (c.shape->kind != ShapeKind::Compound) return onPiece(*c.shape, c.pose, kNoIndex);
    for (std::uint32_t i = 0; i < c.shape->children.size(); ++i)
        onPiece(*c.shape->children[i].shape, compose(c.pose, c.shape->children[i].local), i);
}

// ---- Ordering of results ------------------------------------------------------------------------------------------

/// Equal distances are ordered by body slot, then child, then triangle, so results do not depend on tree layout.
template <class Hit>
bool before(const Hit& a, const Hit& b) {
    if (a.distance != b.distance) return a.distance < b.distance;
    if (a.body.index != b.body.index) return a.body.index < b.body.index;
    if (a.child != b.child) return a.child < b.child;
    return a.triangle < b.triangle;
}

bool castBefore(const ShapeCastHit& a, const ShapeCastHit& b) {
    if (before(a, b) || before(b, a)) return before(a, b);
    return a.castChild < b.castChild;
}

// ---- Shape casts and overlaps, shared by the sphere and shape entry points ----------------------------------------

std::optional<ShapeCastHit> castParts(World::Impl& w, const std::vector<Part>& parts, Vec3 start, Vec3 dir,
                                      float maxDistance, const QueryFilter& filter) {
    const detail::QueryTrees& trees = w.queries.prepare(w);
    const Aabb box = partsBounds(parts);
    float maxT = maxDistance;
    std::optional<ShapeCastHit> best;
    auto consider = [&](const Candidate& c, SweepResult r, SweepHit h, std::uint32_t child, std::uint32_t triangle,
                        std::uint32_t castChild) {
        if (r == SweepResult::Miss || (r == SweepResult::StartsInside && !filter.hitFromInside)) return;
        if (r == SweepResult::StartsInside) h = {0, start, -dir};
        const ShapeCastHit hit{c.id, h.point, h.normal, h.t, triangle, child, castChild};
        if (best && !castBefore(hit, *best)) return;
        best = hit;
        maxT = h.t;
    };
    sweepWorld(w, trees, filter, box.min, box.max, dir, maxT, [&](const Candidate& c, std::uint32_t triangle) {
        if (triangle != detail::kWholeBody) {
            const std::array<Vec3, 3> t = detail::triangleOf(*c.shape, triangle);
            const Vec3 tri[3] = {t[0], t[1], t[2]};
            for (const Part& q : parts) {
                SweepHit h;
                consider(c, sweepPartTriangle(q, tri, c.pose, dir, maxT, filter.hitBackFaces, h), h, kNoIndex, triangle,
                         q.child);
            }
            return;
        }
        forPieces(c, [&](const detail::Shape& piece, const Transform& pose, std::uint32_t child) {
            for (const Part& q : parts) {
                SweepHit h;
                consider(c, sweepPart(q, piece, pose, dir, maxT, h), h, child, kNoIndex, q.child);
            }
        });
    });
    return best;
}

std::size_t overlapParts(World::Impl& w, const std::vector<Part>& parts, std::vector<BodyId>& out,
                         const QueryFilter& filter) {
    const detail::QueryTrees& trees = w.queries.prepare(w);
    const Aabb box = partsBounds(parts);
    std::vector<BodyId> found;
    overlapWorld(w, trees, filter, box.min, box.max, [&](const Candidate& c, std::uint32_t triangle) {
        if (!found.empty() && found.back() == c.id) return;  // another triangle of a mesh already in
        bool touches = false;
        if (triangle != detail::kWholeBody) {
            const std::array<Vec3, 3> t = detail::triangleOf(*c.shape, triangle);
            const Vec3 tri[3] = {t[0], t[1], t[2]};
            for (const Part& q : parts) touches = touches || overlapPartTriangle(q, tri, c.pose);
        } else {
            forPieces(c, [&](const detail::Shape& piece, const Transform& pose, std::uint32_t) {
                for (const Part& q : parts) touches = touches || overlapPart(q, piece, pose);
            });
        }
        if (touches) found.push_back(c.id);
    });
    std::sort(found.begin(), found.end(), [](BodyId a, BodyId b) { return a.index < b.index; });
    found.erase(std::unique(found.begin(), found.end()), found.end());
    out.insert(out.end(), found.begin(), found.end());
    return found.size();
}

}  // namespace

// ---- The World members --------------------------------------------------------------------------------------------

std::optional<RayHit> World::castRay(Vec3 origin, Vec3 direction, float maxDistance, const QueryFilter& filter) const {
    static constexpr const char* kWhere = "World::castRay";
    requireFinite(kWhere, "origin", origin);
    const Vec3 dir = requireDirection(kWhere, direction);
    float maxT = requireMaxDistance(kWhere, maxDistance);
    Impl& w = *impl_;
    const detail::QueryTrees& trees = w.queries.prepare(w);
    std::optional<RayHit> best;
    auto consider = [&](const Candidate& c, float t, Vec3 normal, std::uint32_t child, std::uint32_t triangle) {
        const RayHit hit{c.id, origin + dir * t, normal, t, triangle, child};
        if (best && !before(hit, *best)) return;
        best = hit;
        maxT = t;
    };
    sweepWorld(w, trees, filter, origin, origin, dir, maxT, [&](const Candidate& c, std::uint32_t triangle) {
        const Ray ray{origin, dir, maxT};
        if (triangle == detail::kWholeBody) {
            rayBody(c, ray, filter.hitFromInside,
                    [&](float t, Vec3 n, std::uint32_t child) { consider(c, t, n, child, kNoIndex); });
            return;
        }
        const std::array<Vec3, 3> tri = detail::triangleOf(*c.shape, triangle);
        SurfaceHit h;
        if (detail::rayTriangle(detail::toLocal(c.pose, ray), tri[0], tri[1], tri[2], filter.hitBackFaces, h))
            consider(c, h.t, rotate(c.pose.rotation, h.normal), kNoIndex, triangle);
    });
    return best;
}

std::size_t World::castRayAll(Vec3 origin, Vec3 direction, float maxDistance, std::vector<RayHit>& hits,
                              const QueryFilter& filter) const {
    static constexpr const char* kWhere = "World::castRayAll";
    requireFinite(kWhere, "origin", origin);
    const Vec3 dir = requireDirection(kWhere, direction);
    const float maxT = requireMaxDistance(kWhere, maxDistance);
    Impl& w = *impl_;
    const detail::QueryTrees& trees = w.queries.prepare(w);
    const std::size_t first = hits.size();
    const Ray ray{origin, dir, maxT};
    sweepWorld(w, trees, filter, origin, origin, dir, maxT, [&](const Candidate& c, std::uint32_t triangle) {
        if (triangle == detail::kWholeBody) {
            rayBody(c, ray, filter.hitFromInside, [&](float t, Vec3 n, std::uint32_t child) {
                hits.push_back({c.id, origin + dir * t, n, t, kNoIndex, child});
            });
            return;
        }
        const std::array<Vec3, 3> tri = detail::triangleOf(*c.shape, triangle);
        SurfaceHit h;
        if (detail::rayTriangle(detail::toLocal(c.pose, ray), tri[0], tri[1], tri[2], filter.hitBackFaces, h))
            hits.push_back({c.id, origin + dir * h.t, rotate(c.pose.rotation, h.normal), h.t, triangle, kNoIndex});
    });
    std::sort(hits.begin() + std::ptrdiff_t(first), hits.end(), before<RayHit>);
    return hits.size() - first;
}

std::optional<ShapeCastHit> World::castSphere(Vec3 center, float radius, Vec3 direction, float maxDistance,
                                              const QueryFilter& filter) const {
    static constexpr const char* kWhere = "World::castSphere";
    requireFinite(kWhere, "center", center);
    requireNonNegative(kWhere, "radius", radius);
    const Vec3 dir = requireDirection(kWhere, direction);
    const float maxT = requireMaxDistance(kWhere, maxDistance);
    detail::Shape sphere;
    sphere.kind = ShapeKind::Sphere;
    sphere.radius = radius;
    sphere.localBounds = {{-radius, -radius, -radius}, {radius, radius, radius}};
    return castParts(*impl_, {{&sphere, {center, {}}, kNoIndex}}, center, dir, maxT, filter);
}

std::optional<ShapeCastHit> World::castShape(ShapeId shape, const Transform& start, Vec3 direction, float maxDistance,
                                             const QueryFilter& filter) const {
    static constexpr const char* kWhere = "World::castShape";
    const detail::Shape& s = requireQueryShape(*impl_, shape, kWhere);
    const Transform pose = requirePose(kWhere, "start", start);
    const Vec3 dir = requireDirection(kWhere, direction);
    const float maxT = requireMaxDistance(kWhere, maxDistance);
    return castParts(*impl_, partsOf(s, pose), pose.position, dir, maxT, filter);
}

std::size_t World::overlapAabb(Vec3 min, Vec3 max, std::vector<BodyId>& bodies, const QueryFilter& filter) const {
    static constexpr const char* kWhere = "World::overlapAabb";
    requireFinite(kWhere, "min", min);
    requireFinite(kWhere, "max", max);
    if (min.x > max.x || min.y > max.y || min.z > max.z)
        fail(kWhere, "min " + describe(min) + " exceeds max " + describe(max) + " on some axis");
    detail::Shape box;
    box.kind = ShapeKind::Box;
    box.halfExtents = (max - min) * 0.5f;
    box.localBounds = {-box.halfExtents, box.halfExtents};
    return overlapParts(*impl_, {{&box, {(min + max) * 0.5f, {}}, kNoIndex}}, bodies, filter);
}

std::size_t World::overlapSphere(Vec3 center, float radius, std::vector<BodyId>& bodies,
                                 const QueryFilter& filter) const {
    static constexpr const char* kWhere = "World::overlapSphere";
    requireFinite(kWhere, "center", center);
    requireNonNegative(kWhere, "radius", radius);
    detail::Shape sphere;
    sphere.kind = ShapeKind::Sphere;
    sphere.radius = radius;
    sphere.localBounds = {{-radius, -radius, -radius}, {radius, radius, radius}};
    return overlapParts(*impl_, {{&sphere, {center, {}}, kNoIndex}}, bodies, filter);
}

std::size_t World::overlapShape(ShapeId shape, const Transform& pose, std::vector<BodyId>& bodies,
                                const QueryFilter& filter) const {
    static constexpr const char* kWhere = "World::overlapShape";
    const detail::Shape& s = requireQueryShape(*impl_, shape, kWhere);
    return overlapParts(*impl_, partsOf(s, requirePose(kWhere, "pose", pose)), bodies, filter);
}

}  // namespace rubble
