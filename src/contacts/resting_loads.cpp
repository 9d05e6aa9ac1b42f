#include "contacts/resting_loads.h"

// GCC 12 reports Eigen's AVX-512 paths for 6x6 doubles as reading uninitialised lanes (a known false positive of its
// maybe-uninitialized analysis through the intrinsics headers) at -O2 and above.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/parallel.h"

namespace rubble::detail {
namespace {

constexpr std::uint32_t kFixed = ~0u;
constexpr std::uint32_t kNotResting = ~0u;
/// A contact whose normal leans further than this from the vertical (cosine with up, ~75 degrees) holds nothing up
/// by its normal force alone; side contacts in a wall are the common case.
constexpr float kMinSupportCosine = 0.25f;
/// Rounds of the active set: points that came out pulling are dropped and the rest solved again.
constexpr int kActiveSetRounds = 4;
/// balance(): the regularisation as a share of the mean squared size of the columns, and the refinements that take
/// its bias back from the directions the points span well (each leaves ~2% of the last one's error there).
constexpr double kRegularisation = 1e-2;
constexpr int kRefinements = 3;
/// A body counts as resting on a support while it approaches it no faster than this many times what gravity adds
/// in one substep: a body at rest gained g h before the solve, one landing from a few millimetres more. A landing
/// body is stopped by the iterations; seeding it as if it were at rest is a guess without grounds, and the impulses
/// that stopped it last step are no load to pass down.
constexpr float kRestingApproachSteps = 2.0f;
/// The supports' guess lifts a body by at most this many times the load along gravity, whatever the least-squares
/// answer: a guess beyond the load is energy that the iterations would have to take back.
constexpr float kMaxLift = 1.5f;
/// Manifolds per task of the scan for supports.
constexpr std::size_t kManifoldChunk = 2048;

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

/// Point forces f >= 0 with sum f_i column_i = wanted (force, torque), least-norm among the exact answers.
/// Regularised (Tikhonov, relative to the columns' mean size, then refined three times), so that what the points can
/// balance is balanced to float precision while what they can hardly balance (a sideways load on supports whose
/// normals differ by a hair) is left unbalanced instead of being bought with huge opposing forces: the answer is at
/// most a few times the load, however the points lie. The iterations balance what is left.
template <class SupportPoint>
void balance(std::vector<SupportPoint>& points, const Vec6& wanted) {
    const auto columnOf = [](const SupportPoint& p) {
        Vec6 c;
        for (int i = 0; i < 6; ++i) c(i) = p.column[i];
        return c;
    };
    for (int round = 0; round < kActiveSetRounds; ++round) {
        Mat6 normal = Mat6::Zero();
        int active = 0;
        for (const SupportPoint& p : points)
            if (p.active) normal += columnOf(p) * columnOf(p).transpose(), ++active;
        if (active == 0) return;
        normal.diagonal().array() += kRegularisation * normal.trace() / active + 1e-30;
        const Eigen::LDLT<Mat6> solver = normal.ldlt();
        Vec6 y = solver.solve(wanted);
        for (int refine = 0; refine < kRefinements; ++refine) {
            Vec6 residual = wanted;
            for (const SupportPoint& p : points)
                if (p.active) residual -= columnOf(p) * columnOf(p).dot(y);
            y += solver.solve(residual);
        }
        bool dropped = false;
        for (SupportPoint& p : points) {
            p.force = p.active ? static_cast<float>(columnOf(p).dot(y)) : 0.0f;
            if (p.force < 0) p.force = 0, p.active = false, dropped = true;
        }
        if (!dropped) return;
    }
}

}  // namespace

std::uint32_t RestingLoads::seed(const Contacts& contacts, std::span<const std::uint8_t> carried,
                                 const MovingBodies& bodies, const RestingLoadParams& params, TaskPool& pool,
                                 std::vector<PointImpulse>& impulses) {
    const float g = length(params.gravity);
    if (!(g > 0) || !(params.h > 0)) return 0;
    const Vec3 up = params.gravity * (-1.0f / g);
    const std::size_t bodyCount = bodies.px.size();
    const std::size_t manifoldCount = contacts.manifolds.size();
    const auto heightOf = [&](std::uint32_t i) {
        return bodies.px[i] * up.x + bodies.py[i] * up.y + bodies.pz[i] * up.z;
    };
    const auto touching = [&](const Manifold& m) {
        for (int i = 0; i < m.pointCount; ++i)
            if (m.points[i].depth >= -params.touchDistance) return true;
        return false;
    };
    const auto supportOf = [&](std::size_t m, Support& out) {
        const ContactPair& p = contacts.pairs[m];
        const Manifold& manifold = contacts.manifolds[m];
        const float normalUp = dot(manifold.normal, up);
        if (std::fabs(normalUp) < kMinSupportCosine) return false;
        // The normal points from A to B: B rests on A when it points up.
        const bool upperIsB = normalUp > 0;
        if (upperIsB ? p.bStatic : p.aStatic) return false;
        const std::uint32_t upper = upperIsB ? p.b : p.a;
        if (!(bodies.invMass[upper] > 0)) return false;
        std::uint32_t lower = upperIsB ? p.a : p.b;
        if ((upperIsB ? p.aStatic : p.bStatic) || !(bodies.invMass[lower] > 0))
            lower = kFixed;
        else if (!(heightOf(lower) < heightOf(upper)))  // strictly lower, so that the order below has no cycles
            return false;
        if (!touching(manifold)) return false;
        out = {static_cast<std::uint32_t>(m), upper, lower, upperIsB};
        return true;
    };
    const auto isCarried = [&](std::size_t m) { return m < carried.size() && carried[m] != 0; };
    const auto velocityAt = [&](std::uint32_t body, bool isStatic, Vec3 point) {
        if (isStatic) return Vec3{0, 0, 0};
        const Vec3 arm = point - Vec3{bodies.px[body], bodies.py[body], bodies.pz[body]};
        return Vec3{bodies.vx[body], bodies.vy[body], bodies.vz[body]} +
               cross(Vec3{bodies.wx[body], bodies.wy[body], bodies.wz[body]}, arm);
    };
    // Whether the upper body of a support moves toward the lower one no faster than a body at rest would.
    const float restingApproach = kRestingApproachSteps * g * params.h;
    const auto atRest = [&](const Support& s) {
        const ContactPair& p = contacts.pairs[s.manifold];
        const Manifold& manifold = contacts.manifolds[s.manifold];
        const Vec3 push = s.upperIsB ? manifold.normal : manifold.normal * -1.0f;
        for (int i = 0; i < manifold.pointCount; ++i) {
            const Vec3 at = manifold.points[i].position;
            const Vec3 relative = s.upperIsB ? velocityAt(p.b, p.bStatic, at) - velocityAt(p.a, p.aStatic, at)
                                             : velocityAt(p.a, p.aStatic, at) - velocityAt(p.b, p.bStatic, at);
            if (!(dot(relative, push) >= -restingApproach)) return false;
        }
        return true;
    };
    // The first manifold from m on that carried nothing. Most manifolds carry their impulses: memchr jumps to the
    // next one that does not.
    const std::size_t carriedCount = std::min(carried.size(), manifoldCount);
    const auto nextNew = [&](std::size_t m) {
        if (m >= carriedCount) return m;
        const void* zero = std::memchr(carried.data() + m, 0, carriedCount - m);
        return zero ? static_cast<std::size_t>(static_cast<const std::uint8_t*>(zero) - carried.data()) : carriedCount;
    };

    // The bodies that rest on a new contact, top down.
    if (restingOf_.size() != bodyCount) restingOf_.assign(bodyCount, kNotResting);
    resting_.clear();
    for (std::size_t m = nextNew(0); m < manifoldCount; m = nextNew(m + 1)) {
        Support s;
        if (!supportOf(m, s) || !atRest(s)) continue;
        if (restingOf_[s.upper] == kNotResting) {
            restingOf_[s.upper] = 0;
            resting_.push_back(s.upper);
        }
    }
    if (resting_.empty()) return 0;
    std::sort(resting_.begin(), resting_.end(), [&](std::uint32_t x, std::uint32_t y) {
        const float hx = heightOf(x), hy = heightOf(y);
        return hx > hy || (hx == hy && x < y);
    });
    for (std::size_t k = 0; k < resting_.size(); ++k) restingOf_[resting_[k]] = static_cast<std::uint32_t>(k);

    // Each resting body's supports, and the supports through which something rests on it, grouped by body. Every
    // manifold is looked at, in parallel; the supports found are taken in manifold order.
    const auto resting = [&](std::uint32_t index, bool isStatic) {
        return !isStatic && restingOf_[index] != kNotResting;
    };
    const std::size_t chunks = TaskPool::chunkCount(manifoldCount, kManifoldChunk);
    if (chunkSupports_.size() < chunks) chunkSupports_.resize(chunks);
    pool.forChunks(manifoldCount, kManifoldChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::vector<Support>& found = chunkSupports_[c];
        found.clear();
        for (std::size_t m = begin; m < end; ++m) {
            const ContactPair& p = contacts.pairs[m];
            Support s;
            if ((resting(p.a, p.aStatic) || resting(p.b, p.bStatic)) && supportOf(m, s)) found.push_back(s);
        }
    });
    supports_.clear();
    links_.clear();
    for (std::size_t c = 0; c < chunks; ++c)
        for (const Support& s : chunkSupports_[c]) {
            const std::uint32_t upper = restingOf_[s.upper];
            const std::uint32_t lower = s.lower == kFixed ? kNotResting : restingOf_[s.lower];
            if (upper == kNotResting && lower == kNotResting) continue;
            const auto at = static_cast<std::uint32_t>(supports_.size());
            supports_.push_back(s);
            if (upper != kNotResting) links_.push_back({upper, at, false});
            if (lower != kNotResting) links_.push_back({lower, at, true});
        }
    linkStart_.assign(resting_.size() + 1, 0);
    for (const Link& l : links_) ++linkStart_[l.body + 1];
    for (std::size_t k = 0; k < resting_.size(); ++k) linkStart_[k + 1] += linkStart_[k];
    grouped_.resize(links_.size());
    linkFill_.assign(linkStart_.begin(), linkStart_.end() - 1);
    for (const Link& l : links_) grouped_[linkFill_[l.body]++] = l;  // manifold order within a body
    links_.swap(grouped_);

    std::uint32_t written = 0;
    std::vector<SupportPoint>& points = points_;
    const float invH = 1.0f / params.h;
    for (std::size_t k = 0; k < resting_.size(); ++k) {
        const std::uint32_t body = resting_[k];
        const Vec3 centre{bodies.px[body], bodies.py[body], bodies.pz[body]};
        // What the new supports must balance: the weight, the loads of what rests on this body (impulses carried or
        // written, since everything above came first), less what the supports it kept from last step carry.
        Vec3 force = params.gravity * (bodies.gravityScale[body] / bodies.invMass[body]);
        Vec3 torque{0, 0, 0};
        points.clear();
        bool landing = false;
        for (std::uint32_t l = linkStart_[k]; l < linkStart_[k + 1]; ++l) {
            const Support& s = supports_[links_[l].support];
            const Manifold& manifold = contacts.manifolds[s.manifold];
            const bool kept = isCarried(s.manifold);
            // A body that approaches a support faster than one at rest is landing: it gets no guess. A contact
            // above that is not at rest carries an impact, which is no load to pass down.
            if (!links_[l].above && !atRest(s)) {
                landing = true;
                break;
            }
            if (links_[l].above && kept && !atRest(s)) continue;
            // Direction in which the support pushes the upper body.
            const Vec3 push = s.upperIsB ? manifold.normal : manifold.normal * -1.0f;
            for (int i = 0; i < manifold.pointCount; ++i) {
                const Vec3 arm = manifold.points[i].position - centre;
                const float impulse = impulses[std::size_t{s.manifold} * kMaxManifoldPoints + i].normal;
                if (links_[l].above || kept) {
                    const Vec3 load = push * ((links_[l].above ? -impulse : impulse) * invH);
                    force = force + load;
                    torque = torque + cross(arm, load);
                } else if (manifold.points[i].depth >= -params.touchDistance) {
                    const Vec3 turn = cross(arm, push);
                    points.push_back({{push.x, push.y, push.z, turn.x, turn.y, turn.z}});
                }
            }
        }
        if (landing) continue;
        Vec6 wanted;
        wanted << -force.x, -force.y, -force.z, -torque.x, -torque.y, -torque.z;
        balance(points, wanted);
        const float load = std::max(0.0f, -dot(force, up));
        float lift = 0;
        for (const SupportPoint& p : points)
            lift += p.force * (p.column[0] * up.x + p.column[1] * up.y + p.column[2] * up.z);
        const float scale = lift > kMaxLift * load ? kMaxLift * load / lift : 1.0f;
        std::size_t next = 0;
        for (std::uint32_t l = linkStart_[k]; l < linkStart_[k + 1]; ++l) {
            const Support& s = supports_[links_[l].support];
            if (links_[l].above || isCarried(s.manifold)) continue;
            const Manifold& manifold = contacts.manifolds[s.manifold];
            ++written;
            for (int i = 0; i < manifold.pointCount; ++i) {
                if (manifold.points[i].depth < -params.touchDistance) continue;
                const float f = points[next++].force * scale;
                // A guess that is not finite (a degenerate manifold) is no guess: the point starts from zero.
                impulses[std::size_t{s.manifold} * kMaxManifoldPoints + i].normal =
                    std::isfinite(f) ? f * params.h : 0.0f;
            }
        }
    }
    for (const std::uint32_t body : resting_) restingOf_[body] = kNotResting;
    return written;
}

}  // namespace rubble::detail
