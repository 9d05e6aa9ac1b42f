#pragma once
// Random but physically well-formed contact batches, for the solver kernels' agreement test and benchmark.
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "solver/contact_batch.h"

namespace rubble::test {

using detail::ContactBatch;
using detail::kBatchLanes;

/// Random but well-formed constraint rows: unit normal and basis, positive masses, a few overlapping points.
/// Lanes use bodies firstBody + 2 lane and firstBody + 2 lane + 1; the last lane meets the still row `still`.
inline void fillRandomBatch(detail::ContactBatch& b, std::mt19937& rng, std::int32_t still,
                            std::int32_t firstBody = 0) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), pos(0.1f, 1.0f);
    std::memset(static_cast<void*>(&b), 0, sizeof b);
    b.pointCount = 3;
    for (std::size_t lane = 0; lane < kBatchLanes; ++lane) {
        // Distinct bodies per lane (as colouring guarantees); the last lane meets the still row.
        b.bodyA[lane] = firstBody + static_cast<std::int32_t>(2 * lane);
        b.bodyB[lane] = lane + 1 == kBatchLanes ? still : firstBody + static_cast<std::int32_t>(2 * lane + 1);
        Vec3 n{u(rng), u(rng), u(rng)};
        n = n * (1.0f / length(n));
        Vec3 t1 = cross(std::fabs(n.x) < 0.5f ? Vec3{1, 0, 0} : Vec3{0, 1, 0}, n);
        t1 = t1 * (1.0f / length(t1));
        const Vec3 t2 = cross(n, t1);
        b.nx[lane] = n.x, b.ny[lane] = n.y, b.nz[lane] = n.z;
        b.t1x[lane] = t1.x, b.t1y[lane] = t1.y, b.t1z[lane] = t1.z;
        b.t2x[lane] = t2.x, b.t2y[lane] = t2.y, b.t2z[lane] = t2.z;
        b.friction[lane] = 0.6f;
        b.biasRate[lane] = 12.0f, b.massScale[lane] = 0.9f, b.impulseScale[lane] = 0.1f, b.slop[lane] = 0.005f;
        for (int i = 0; i < 3; ++i) {
            ContactBatch::Point& p = b.points[i];
            p.rAx[lane] = u(rng), p.rAy[lane] = u(rng), p.rAz[lane] = u(rng);
            p.rBx[lane] = u(rng), p.rBy[lane] = u(rng), p.rBz[lane] = u(rng);
            p.separation[lane] = 0.02f * u(rng);
            p.normalMass[lane] = pos(rng), p.tangentMass1[lane] = pos(rng), p.tangentMass2[lane] = pos(rng);
            p.normalImpulse[lane] = pos(rng), p.tangentImpulse1[lane] = 0.3f * u(rng);
        }
    }
}

/// Random restitution data for a batch of fillRandomBatch: every point approached fast and pushed.
inline void fillRandomExtras(detail::ContactBatchExtras& e, std::mt19937& rng) {
    std::uniform_real_distribution<float> pos(0.1f, 1.0f);
    std::memset(static_cast<void*>(&e), 0, sizeof e);
    for (std::size_t lane = 0; lane < kBatchLanes; ++lane) {
        e.restitution[lane] = 0.5f;
        for (int i = 0; i < 3; ++i) {
            e.points[i].relativeVelocity[lane] = -3.0f * pos(rng);
            e.points[i].maxNormalImpulse[lane] = pos(rng);
        }
    }
}

/// Random masses for body rows [0, count): positive inverse masses and inertias with small products of inertia; row
/// `still` (the still row) keeps zero masses.
inline void fillRandomMassRows(std::vector<detail::MassRow>& rows, std::size_t count, std::int32_t still,
                               std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), pos(0.1f, 1.0f);
    rows.assign(count, detail::MassRow{});
    for (std::size_t i = 0; i < count; ++i) {
        if (static_cast<std::int32_t>(i) == still) continue;
        detail::MassRow& r = rows[i];
        r.inverseMass = pos(rng);
        r.inverseInertia[0] = pos(rng), r.inverseInertia[1] = pos(rng), r.inverseInertia[2] = pos(rng);
        r.inverseInertia[3] = 0.1f * u(rng), r.inverseInertia[4] = 0.1f * u(rng);
    }
}

}  // namespace rubble::test
