#pragma once
// A bare body storage with shapes and their bound table, for tests that run the collision stages (bounds, broad
// phase, narrow phase) directly, without a World.
#include <cstdint>
#include <vector>

#include "bounds/bounds.h"
#include "broadphase/broadphase_stage.h"
#include "core/parallel.h"
#include "narrowphase/narrowphase_stage.h"
#include "shapes/shape.h"
#include "storage/body_storage.h"

namespace rubble::test {

using namespace rubble::detail;

struct StageScene {
    BodyStorage storage;
    std::vector<Shape> shapes;
    ShapeBoundsTable table;
    TaskPool editPool{1};  ///< for the static BVH's batch builds as bodies are added

    std::uint32_t addShape(const ShapeDef& def) {
        shapes.push_back(buildShape(def));
        const auto index = static_cast<std::uint32_t>(shapes.size() - 1);
        if (!shapes.back().staticOnly()) table.set(index, shapeBoundsInfo(shapes.back()));
        return index;
    }

    std::uint32_t addMoving(std::uint32_t shape, Vec3 origin, Quat q, Vec3 v = {}, Vec3 w = {}) {
        std::uint32_t i;
        storage.allocate(BodySet::Moving, i);
        MovingBodies& m = storage.moving;
        const Vec3 lc = shapes[shape].unitMass.centerOfMass;
        const Vec3 com = origin + rotate(q, lc);
        m.px[i] = com.x, m.py[i] = com.y, m.pz[i] = com.z;
        m.qx[i] = q.x, m.qy[i] = q.y, m.qz[i] = q.z, m.qw[i] = q.w;
        m.lcx[i] = lc.x, m.lcy[i] = lc.y, m.lcz[i] = lc.z;
        m.vx[i] = v.x, m.vy[i] = v.y, m.vz[i] = v.z;
        m.wx[i] = w.x, m.wy[i] = w.y, m.wz[i] = w.z;
        m.shape[i] = shape;
        m.filterCategory[i] = 1;
        m.filterMask[i] = ~0u;
        return i;
    }

    void addStatic(std::uint32_t shape, Vec3 p, BroadPhaseStage& stage) {
        std::uint32_t i;
        const BodyId id = storage.allocate(BodySet::Static, i);
        StaticBodies& s = storage.statics;
        s.px[i] = p.x, s.py[i] = p.y, s.pz[i] = p.z;
        s.qw[i] = 1;
        s.shape[i] = shape;
        s.filterCategory[i] = 1;
        s.filterMask[i] = ~0u;
        stage.staticAdded(id.index, storage, shapes, editPool);
    }

    Transform poseOf(std::uint32_t i, bool isStatic) const {
        if (isStatic) {
            const StaticBodies& s = storage.statics;
            return {{s.px[i], s.py[i], s.pz[i]}, {s.qx[i], s.qy[i], s.qz[i], s.qw[i]}};
        }
        const MovingBodies& m = storage.moving;
        const Quat q{m.qx[i], m.qy[i], m.qz[i], m.qw[i]};
        return {Vec3{m.px[i], m.py[i], m.pz[i]} - rotate(q, {m.lcx[i], m.lcy[i], m.lcz[i]}), q};
    }
    const Shape& shapeOf(std::uint32_t i, bool isStatic) const {
        return shapes[isStatic ? storage.statics.shape[i] : storage.moving.shape[i]];
    }
};

/// Bounds, broad phase and narrow phase over the scene at a 60 Hz step, as the world runs them.
inline Contacts runStages(StageScene& scene, BroadPhaseStage& broad, int threads, float margin,
                          CandidatePairs& candidates) {
    TaskPool pool(threads);
    Bounds bounds;
    updateBounds(scene.storage.moving, scene.table, BoundsParams{1.0f / 60, margin}, pool, bounds);
    broad.findPairs(bounds, scene.storage, BroadPhaseKind::Auto, {}, pool, candidates);
    NarrowPhaseStage narrow;
    Contacts contacts;
    narrow.run(candidates, scene.storage, scene.shapes, NarrowPhaseParams{margin, 1.0f / 60}, pool, contacts);
    return contacts;
}

}  // namespace rubble::test
