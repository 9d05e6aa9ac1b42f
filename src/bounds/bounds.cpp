#include "bounds/bounds.h"

#include <algorithm>
#include <cmath>

#include "core/parallel.h"
#include "simd/simd.h"
#include "simd/vec.h"
#include "storage/flag_scan.h"

namespace rubble::detail {
namespace {

using simd::FloatW;
using simd::Vec3W;

constexpr std::size_t kChunkSize = 2048;
static_assert(kChunkSize % simd::kLanes == 0, "chunks must hold whole batches");

/// Boxes of the bodies [i, i + lanes), written once for any lane type.
template <class F>
void boundsKernel(const MovingBodies& b, const ShapeBoundsTable& s, const BoundsParams& params, Bounds& out,
                  std::size_t i) {
    using Int = simd::IntOf<F>;
    const Int shape = simd::loadIndex<Int>(b.shape.data() + i);
    const Vec3W<F> localCenter{simd::gather(s.centerX.data(), shape), simd::gather(s.centerY.data(), shape),
                               simd::gather(s.centerZ.data(), shape)};
    const Vec3W<F> half{simd::gather(s.halfX.data(), shape), simd::gather(s.halfY.data(), shape),
                        simd::gather(s.halfZ.data(), shape)};
    const F radius = simd::gather(s.radius.data(), shape);
    const F reach = simd::gather(s.reach.data(), shape);

    const Vec3W<F> com = Vec3W<F>::load(b.px.data(), b.py.data(), b.pz.data(), i);
    const simd::QuatW<F> q = simd::QuatW<F>::load(b.qx.data(), b.qy.data(), b.qz.data(), b.qw.data(), i);
    const simd::Mat3W<F> r = simd::rotationMatrix(q);
    const Vec3W<F> center = r * localCenter + com;
    // A turn by |w| dt moves a point at distance `reach` from the centre of mass by at most |w| dt reach (and never
    // by more than the diameter of its circle).
    const Vec3W<F> w = Vec3W<F>::load(b.wx.data(), b.wy.data(), b.wz.data(), i);
    const F margin = F(params.margin) + simd::min(simd::length(w) * F(params.dt), F(2.0f)) * reach;
    Vec3W<F> extent;
    extent.x = simd::min(simd::abs(r.m[0][0]) * half.x + simd::abs(r.m[0][1]) * half.y + simd::abs(r.m[0][2]) * half.z,
                         radius) +
               margin;
    extent.y = simd::min(simd::abs(r.m[1][0]) * half.x + simd::abs(r.m[1][1]) * half.y + simd::abs(r.m[1][2]) * half.z,
                         radius) +
               margin;
    extent.z = simd::min(simd::abs(r.m[2][0]) * half.x + simd::abs(r.m[2][1]) * half.y + simd::abs(r.m[2][2]) * half.z,
                         radius) +
               margin;
    const Vec3W<F> sweep = Vec3W<F>::load(b.vx.data(), b.vy.data(), b.vz.data(), i) * F(params.dt);
    const Vec3W<F> zero = Vec3W<F>::zero();
    const Vec3W<F> lo = center - extent + simd::min(sweep, zero);
    const Vec3W<F> hi = center + extent + simd::max(sweep, zero);
    lo.store(out.minX.data(), out.minY.data(), out.minZ.data(), i);
    hi.store(out.maxX.data(), out.maxY.data(), out.maxZ.data(), i);
}

}  // namespace

void ShapeBoundsTable::set(std::uint32_t shape, const ShapeBoundsInfo& info) {
    if (shape >= centerX.size())
        for (auto* a : {&centerX, &centerY, &centerZ, &halfX, &halfY, &halfZ, &radius, &reach, &inner})
            a->resize(shape + 1);
    centerX[shape] = info.centerX, centerY[shape] = info.centerY, centerZ[shape] = info.centerZ;
    halfX[shape] = info.halfX, halfY[shape] = info.halfY, halfZ[shape] = info.halfZ;
    radius[shape] = info.radius;
    reach[shape] = info.reach;
    inner[shape] = info.inner;
}

void updateBounds(const MovingBodies& bodies, const ShapeBoundsTable& shapes, const BoundsParams& params,
                  TaskPool& pool, Bounds& out, bool keepSleepers) {
    const std::size_t n = bodies.size();
    out.resize(n);
    const std::uint8_t* flags = bodies.flags.data();
    const auto allAsleep = [&](std::size_t i) { return allHave(flags + i, simd::kLanes, kFlagAsleep); };
    pool.forChunks(n, kChunkSize, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        std::size_t i = begin;
        for (const std::size_t wideEnd = begin + simd::roundDownToLanes<FloatW>(end - begin); i < wideEnd;
             i += simd::kLanes)
            if (!keepSleepers || !allAsleep(i)) boundsKernel<FloatW>(bodies, shapes, params, out, i);
        for (; i < end; ++i) boundsKernel<float>(bodies, shapes, params, out, i);
    });
}

void updateBoundsOf(const MovingBodies& bodies, const ShapeBoundsTable& shapes, const BoundsParams& params,
                    std::span<const std::uint32_t> rows, Bounds& out) {
    for (const std::uint32_t i : rows) boundsKernel<float>(bodies, shapes, params, out, i);
}

void updateBoundsScalar(const MovingBodies& bodies, const ShapeBoundsTable& shapes, const BoundsParams& params,
                        Bounds& out) {
    out.resize(bodies.size());
    for (std::size_t i = 0; i < bodies.size(); ++i) boundsKernel<float>(bodies, shapes, params, out, i);
}

}  // namespace rubble::detail
