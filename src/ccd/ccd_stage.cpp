// Continuous-collision stage; see ccd_stage.h.
#include "ccd/ccd_stage.h"

#include <algorithm>
#include <cmath>

#include "bounds.h"
#include "broadphase/broadphase.h"
#include "broadphase/static_bvh.h"
#include "ccd/time_of_impact.h"
#include "parallel.h"
#include "query/tree_queries.h"

namespace rubble::detail {
namespace {

constexpr std::size_t kBodyChunk = 1024;
constexpr std::size_t kSweepChunk = 16;
/// Box2D's test: a body is fast when it moves more in a step than this fraction of its smallest extent.
constexpr float kFastFraction = 0.5f;

Transform movingPose(const MovingBodies& m, std::uint32_t i) {
    const Quat q{m.qx[i], m.qy[i], m.qz[i], m.qw[i]};
    return {Vec3{m.px[i], m.py[i], m.pz[i]} - rotate(q, {m.lcx[i], m.lcy[i], m.lcz[i]}), q};
}

/// Smallest distance from the centre of mass `center` (shape frame) to the shape's surface, a bound from below.
float innerExtent(const Shape& s, Vec3 center) {
    switch (s.kind) {
        case ShapeKind::Sphere:
        case ShapeKind::Capsule:
            return s.radius;
        case ShapeKind::Box:
            return std::min({s.halfExtents.x, s.halfExtents.y, s.halfExtents.z});
        case ShapeKind::ConvexHull: {
            float inner = INFINITY;
            for (std::uint32_t f = 0; f < s.hull->faceCount(); ++f)
                inner = std::min(inner, s.hull->faceOffsets[f] - dot(s.hull->faceNormals[f], center));
            return std::max(inner, 0.0f);
        }
        case ShapeKind::Compound: {
            float inner = INFINITY;
            for (const CompoundChild& c : s.children)
                inner = std::min(inner, innerExtent(*c.shape, applyInverse(c.local, center)));
            return inner;
        }
        default:
            return 0;
    }
}

/// The convex parts of a shape at `pose`: the shape itself, or each child of a compound.
template <class Emit>
void forEachPart(const Shape& s, const Transform& pose, Emit&& emit) {
    if (s.kind != ShapeKind::Compound) return emit(gjkShapeOf(s, pose));
    for (const CompoundChild& c : s.children)
        emit(gjkShapeOf(*c.shape, {apply(pose, c.local.position), pose.rotation * c.local.rotation}));
}

bool filtersMeet(std::uint32_t categoryA, std::uint32_t maskA, std::uint32_t categoryB, std::uint32_t maskB) {
    return (categoryA & maskB) != 0 && (categoryB & maskA) != 0;
}

}  // namespace

void ContinuousCollision::begin(const MovingBodies& m, TaskPool& pool) {
    const std::uint32_t n = m.size();
    for (AlignedVector<float>* v : {&px_, &py_, &pz_, &qx_, &qy_, &qz_, &qw_}) v->resize(n);
    pool.forChunks(n, kBodyChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        std::copy(m.px.begin() + begin, m.px.begin() + end, px_.begin() + begin);
        std::copy(m.py.begin() + begin, m.py.begin() + end, py_.begin() + begin);
        std::copy(m.pz.begin() + begin, m.pz.begin() + end, pz_.begin() + begin);
        std::copy(m.qx.begin() + begin, m.qx.begin() + end, qx_.begin() + begin);
        std::copy(m.qy.begin() + begin, m.qy.begin() + end, qy_.begin() + begin);
        std::copy(m.qz.begin() + begin, m.qz.begin() + end, qz_.begin() + begin);
        std::copy(m.qw.begin() + begin, m.qw.begin() + end, qw_.begin() + begin);
    });
}

void ContinuousCollision::run(BodyStorage& storage, const std::vector<Shape>& shapes, const StaticBvh& staticTree,
                              const std::vector<BodyPair>& movingPairs, float linearSlop, TaskPool& pool) {
    MovingBodies& m = storage.moving;
    const std::uint32_t n = std::min<std::uint32_t>(m.size(), static_cast<std::uint32_t>(px_.size()));
    // Which bodies are fast: one pass, flags per body, then the lists in body order.
    hit_.assign(n, 0);
    pool.forChunks(n, kBodyChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) {
            if ((m.flags[i] & (kFlagKinematic | kFlagFrozen | kFlagAsleep)) != 0 || m.invMass[i] == 0) continue;
            const BodySweep sweep({px_[i], py_[i], pz_[i]}, {qx_[i], qy_[i], qz_[i], qw_[i]},
                                  {m.px[i], m.py[i], m.pz[i]}, {m.qx[i], m.qy[i], m.qz[i], m.qw[i]},
                                  {m.lcx[i], m.lcy[i], m.lcz[i]});
            const Shape& s = shapes[m.shape[i]];
            const float motion = length(sweep.translation()) + sweep.angle() * rotationReach(s);
            const bool bullet = (m.flags[i] & kFlagBullet) != 0;
            if (motion > 0 && motion >= kFastFraction * innerExtent(s, {m.lcx[i], m.lcy[i], m.lcz[i]}))
                hit_[i] = bullet ? 2 : 1;
        }
    });
    fast_.clear();
    bullets_.clear();
    for (std::uint32_t i = 0; i < n; ++i)
        if (hit_[i] == 1)
            fast_.push_back(i);
        else if (hit_[i] == 2)
            bullets_.push_back(i);
    stats_ = {};
    stats_.fastBodies = static_cast<std::uint32_t>(fast_.size() + bullets_.size());
    if (stats_.fastBodies == 0) return;

    std::fill(hit_.begin(), hit_.end(), std::uint8_t{0});
    pool.forChunks(fast_.size(), kSweepChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t k = begin; k < end; ++k)
            hit_[fast_[k]] = sweepBody(fast_[k], storage, shapes, staticTree, nullptr, linearSlop);
    });
    if (!bullets_.empty()) {
        // A bullet's dynamic targets: the other non-bullet bodies of its candidate pairs.
        bulletTargets_.resize(bullets_.size());
        for (auto& targets : bulletTargets_) targets.clear();
        for (const BodyPair& p : movingPairs)
            for (int side = 0; side < 2; ++side) {
                const std::uint32_t self = side == 0 ? p.a : p.b, other = side == 0 ? p.b : p.a;
                if (self >= n || other >= m.size() || (m.flags[other] & kFlagBullet) != 0) continue;
                const auto at = std::lower_bound(bullets_.begin(), bullets_.end(), self);
                if (at != bullets_.end() && *at == self) bulletTargets_[at - bullets_.begin()].push_back(other);
            }
        pool.forChunks(bullets_.size(), kSweepChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
            for (std::size_t k = begin; k < end; ++k)
                hit_[bullets_[k]] = sweepBody(bullets_[k], storage, shapes, staticTree, &bulletTargets_[k], linearSlop);
        });
    }
    for (const std::uint8_t h : hit_) stats_.hits += h;
}

bool ContinuousCollision::sweepBody(std::uint32_t i, BodyStorage& storage, const std::vector<Shape>& shapes,
                                    const StaticBvh& staticTree, const std::vector<std::uint32_t>* dynamicTargets,
                                    float linearSlop) {
    MovingBodies& m = storage.moving;
    const StaticBodies& st = storage.statics;
    const Vec3 c0{px_[i], py_[i], pz_[i]}, c1{m.px[i], m.py[i], m.pz[i]};
    const BodySweep sweep(c0, {qx_[i], qy_[i], qz_[i], qw_[i]}, c1, {m.qx[i], m.qy[i], m.qz[i], m.qw[i]},
                          {m.lcx[i], m.lcy[i], m.lcz[i]});
    const Shape& shape = shapes[m.shape[i]];
    const float reach = rotationReach(shape);
    const ShapeBoundsInfo bounds = shapeBoundsInfo(shape);
    // Everything the body covers during the step lies within this distance of its centre of mass's path.
    const float extent = length(Vec3{bounds.centerX, bounds.centerY, bounds.centerZ}) + bounds.radius + linearSlop;
    const Vec3 lo =
        Vec3{std::min(c0.x, c1.x), std::min(c0.y, c1.y), std::min(c0.z, c1.z)} - Vec3{extent, extent, extent};
    const Vec3 hi =
        Vec3{std::max(c0.x, c1.x), std::max(c0.y, c1.y), std::max(c0.z, c1.z)} + Vec3{extent, extent, extent};

    const float gap = linearSlop, tolerance = 0.25f * linearSlop;
    float first = 1;
    const auto sweepAgainst = [&](const GjkShape& target) {
        forEachPart(shape, Transform{}, [&](const GjkShape& part) {
            const TimeOfImpact toi = timeOfImpact(part, sweep, reach, target, gap, tolerance);
            if (toi.state == TimeOfImpact::State::Hit) first = std::min(first, toi.t);
        });
    };
    const std::uint32_t category = m.filterCategory[i], mask = m.filterMask[i];
    const auto& slots = storage.slots();
    const auto visit = [&](const StaticBvh::PrimitiveRef& ref) {
        const std::uint32_t s = slots[ref.body].dense;
        if (!filtersMeet(category, mask, st.filterCategory[s], st.filterMask[s])) return;
        const Shape& target = shapes[st.shape[s]];
        const Transform pose{{st.px[s], st.py[s], st.pz[s]}, {st.qx[s], st.qy[s], st.qz[s], st.qw[s]}};
        if (ref.triangle == kWholeBody) {
            forEachPart(target, pose, sweepAgainst);
            return;
        }
        Vec3 v[3];
        if (target.mesh) {
            const std::uint32_t* index = &target.mesh->indices[3 * std::size_t(ref.triangle)];
            for (int k = 0; k < 3; ++k) v[k] = apply(pose, target.mesh->vertices[index[k]]);
        } else {
            const std::array<Vec3, 3> local = heightfieldTriangle(*target.heightfield, ref.triangle);
            for (int k = 0; k < 3; ++k) v[k] = apply(pose, local[k]);
        }
        // Only a body whose centre of mass crossed the triangle's plane went into or through it; one that slid
        // along a floor meets the next triangle's edge without having to stop there.
        const Vec3 normal = cross(v[1] - v[0], v[2] - v[0]);
        const float before = dot(normal, c0 - v[0]), after = dot(normal, c1 - v[0]);
        if ((before > 0) == (after > 0)) return;
        GjkShape triangle;
        triangle.core = GjkShape::Core::Points;
        triangle.points = v;
        triangle.pointCount = 3;
        sweepAgainst(triangle);
    };
    const float pad = boxPad(std::max({std::fabs(lo.x), std::fabs(lo.y), std::fabs(lo.z), std::fabs(hi.x),
                                       std::fabs(hi.y), std::fabs(hi.z)}) +
                             treeScale(staticTree.mainTree()));
    const Vec3 grow{pad, pad, pad};
    overlapTree(staticTree.mainTree(), lo - grow, hi + grow, visit);
    overlapTree(staticTree.secondaryTree(), lo - grow, hi + grow, visit);
    if (dynamicTargets)
        for (const std::uint32_t j : *dynamicTargets) {
            if (!filtersMeet(category, mask, m.filterCategory[j], m.filterMask[j])) continue;
            forEachPart(shapes[m.shape[j]], movingPose(m, j), sweepAgainst);
        }
    if (!(first < 1)) return false;
    const Transform pose = sweep.at(first);
    const Vec3 c = c0 + (c1 - c0) * first;
    m.px[i] = c.x, m.py[i] = c.y, m.pz[i] = c.z;
    m.qx[i] = pose.rotation.x, m.qy[i] = pose.rotation.y, m.qz[i] = pose.rotation.z, m.qw[i] = pose.rotation.w;
    return true;
}

}  // namespace rubble::detail
