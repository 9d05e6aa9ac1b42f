// Continuous-collision stage; see ccd_stage.h.
#include "ccd/ccd_stage.h"

#include <algorithm>
#include <cmath>

#include "bounds/bounds.h"
#include "broadphase/broadphase.h"
#include "broadphase/static_bvh.h"
#include "ccd/time_of_impact.h"
#include "core/parallel.h"
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

/// The convex parts of a shape at `pose`: the shape itself, or each child of a compound.
template <class Emit>
void forEachPart(const Shape& s, const Transform& pose, Emit&& emit) {
    if (s.kind != ShapeKind::Compound) return emit(gjkShapeOf(s, pose));
    for (const CompoundChild& c : s.children)
        emit(gjkShapeOf(*c.shape, {apply(pose, c.local.position), pose.rotation * c.local.rotation}));
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

void ContinuousCollision::run(BodyStorage& storage, const std::vector<Shape>& shapes, const ShapeBoundsTable& extents,
                              const StaticBvh& staticTree, const std::vector<BodyPair>& movingPairs, float linearSlop,
                              TaskPool& pool) {
    MovingBodies& m = storage.moving;
    const std::uint32_t n = std::min<std::uint32_t>(m.size(), static_cast<std::uint32_t>(px_.size()));
    // Which bodies are fast: one pass, flags per body, then the lists in body order.
    hit_.assign(n, 0);
    pool.forChunks(n, kBodyChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) {
            // A sensor (or a body without contact response) pushes nothing, so nothing stops it either.
            if ((m.flags[i] & (kFlagKinematic | kFlagFrozen | kFlagAsleep | kFlagSensor | kFlagNoResponse)) != 0 ||
                m.invMass[i] == 0)
                continue;
            const BodySweep sweep({px_[i], py_[i], pz_[i]}, {qx_[i], qy_[i], qz_[i], qw_[i]},
                                  {m.px[i], m.py[i], m.pz[i]}, {m.qx[i], m.qy[i], m.qz[i], m.qw[i]},
                                  {m.lcx[i], m.lcy[i], m.lcz[i]});
            const std::uint32_t s = m.shape[i];
            const float motion = length(sweep.translation()) + sweep.angle() * extents.reach[s];
            const bool bullet = (m.flags[i] & kFlagBullet) != 0;
            if (motion > 0 && motion >= kFastFraction * extents.inner[s]) hit_[i] = bullet ? 2 : 1;
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
    const Sweeps sweeps{shapes, extents, staticTree, staticTree.scale(), linearSlop};
    pool.forChunks(fast_.size(), kSweepChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t k = begin; k < end; ++k) hit_[fast_[k]] = sweepBody(fast_[k], storage, sweeps, nullptr);
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
                hit_[bullets_[k]] = sweepBody(bullets_[k], storage, sweeps, &bulletTargets_[k]);
        });
    }
    for (const std::uint8_t h : hit_) stats_.hits += h;
}

bool ContinuousCollision::sweepBody(std::uint32_t i, BodyStorage& storage, const Sweeps& sweeps,
                                    const std::vector<std::uint32_t>* dynamicTargets) {
    const std::vector<Shape>& shapes = sweeps.shapes;
    const float linearSlop = sweeps.linearSlop;
    MovingBodies& m = storage.moving;
    const StaticBodies& st = storage.statics;
    const Vec3 c0{px_[i], py_[i], pz_[i]}, c1{m.px[i], m.py[i], m.pz[i]};
    const BodySweep sweep(c0, {qx_[i], qy_[i], qz_[i], qw_[i]}, c1, {m.qx[i], m.qy[i], m.qz[i], m.qw[i]},
                          {m.lcx[i], m.lcy[i], m.lcz[i]});
    const Shape& shape = shapes[m.shape[i]];
    const ShapeBoundsTable& t = sweeps.extents;
    const std::uint32_t s = m.shape[i];
    const float reach = t.reach[s];
    // Everything the body covers during the step lies within this distance of its centre of mass's path.
    const float extent = length(Vec3{t.centerX[s], t.centerY[s], t.centerZ[s]}) + t.radius[s] + linearSlop;
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
        const std::uint32_t d = slots[ref.body].dense;
        if (!filtersAccept(category, mask, st.filterCategory[d], st.filterMask[d]) ||
            (st.flags[d] & (kFlagSensor | kFlagNoResponse)))
            return;
        const Shape& target = shapes[st.shape[d]];
        const Transform pose{{st.px[d], st.py[d], st.pz[d]}, {st.qx[d], st.qy[d], st.qz[d], st.qw[d]}};
        if (ref.triangle == kWholeBody) {
            forEachPart(target, pose, sweepAgainst);
            return;
        }
        const std::array<Vec3, 3> local = triangleOf(target, ref.triangle);
        Vec3 v[3];
        for (int k = 0; k < 3; ++k) v[k] = apply(pose, local[k]);
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
                             sweeps.treeScale);
    const Vec3 grow{pad, pad, pad};
    for (const StaticBvh::Tree* tree : sweeps.staticTree.trees()) overlapTree(*tree, lo - grow, hi + grow, visit);
    if (dynamicTargets)
        for (const std::uint32_t j : *dynamicTargets) {
            if (!filtersAccept(category, mask, m.filterCategory[j], m.filterMask[j]) ||
                (m.flags[j] & (kFlagSensor | kFlagNoResponse)))
                continue;
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
