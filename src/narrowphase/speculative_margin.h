#pragma once
// A pair's speculative margin (see NarrowPhaseStage::run): the fixed margin plus how far the two surfaces can close
// in a step. Written once over the lane type so that batched and one-at-a-time pairs get the same margins.
#include "narrowphase/pair_sides.h"
#include "simd/vec.h"

namespace rubble::detail {

/// What bounds the approach of one side of a pair: its velocities and the reach of its shape (zero for statics).
template <class F>
struct Motion {
    simd::Vec3W<F> v = simd::Vec3W<F>::zero(), w = simd::Vec3W<F>::zero();
    F reach = F(0.0f);
};

inline Motion<float> motionOf(const BodyStorage& storage, const MovingRows& rows, const ShapeTables& tables,
                              const ContactPair& p, bool sideB) {
    if (sideB ? p.bStatic : p.aStatic) return {};
    const std::uint32_t i = sideB ? p.b : p.a;
    const float* motion = rowOf(rows.motion, i);
    return {{motion[kVelX], motion[kVelY], motion[kVelZ]},
            {motion[kSpinX], motion[kSpinY], motion[kSpinZ]},
            tables.reach[storage.moving.shape[i]]};
}

/// `margin`: the fixed margin; `step`: the time the contacts must cover.
template <class F>
F speculativeMargin(float margin, float step, const Motion<F>& a, const Motion<F>& b) {
    const F dt(step), two(2.0f);
    const F turnA = simd::min(simd::length(a.w) * dt, two) * a.reach;
    const F turnB = simd::min(simd::length(b.w) * dt, two) * b.reach;
    return F(margin) + simd::length(b.v - a.v) * dt + turnA + turnB;
}

}  // namespace rubble::detail
