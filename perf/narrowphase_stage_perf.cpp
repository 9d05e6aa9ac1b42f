// The narrow-phase stage alone on frozen candidate pairs of the standard scenes, at 1 and 2 threads
// (items_per_second = manifolds). The scene runs `steps` steps in a World first; the bodies' poses and velocities
// are then copied into stage-level body storage, bounds and broad phase run once, and only NarrowPhaseStage::run
// is timed. S1 as it starts (exactly aligned cubes: the cheapest clipping) and after 60 steps (poses and velocities
// as the step leaves them: the case the runner's profile shows). S3 after 60 and 90 steps, while the pile meets the
// terrain (bodies reach it after about 50 steps), and after 300, when it has collapsed into a heap on the terrain:
// triangle jobs of spheres, cubes and capsules, and every pair kind among them. The `reused` cases run the stage with
// manifold reuse on: the poses stay frozen, so from the second run on every pair that is worth it reuses its
// manifolds (narrowphase/manifold_reuse.h), which is what a settled scene costs; the others compute every pair.
#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <vector>

#include "bounds/bounds.h"
#include "broadphase/broadphase_stage.h"
#include "core/parallel.h"
#include "narrowphase/narrowphase_stage.h"
#include "rubble/scene.h"
#include "rubble/world.h"
#include "shapes/shape.h"
#include "storage/body_storage.h"
#include "thread_counts.h"

namespace {

using namespace rubble;
using namespace rubble::detail;

struct FrozenScene {
    BodyStorage storage;
    std::vector<Shape> shapes;
    ShapeBoundsTable table;
    BroadPhaseStage broad;
    CandidatePairs candidates;
    NarrowPhaseParams params;
    float reuseDistance = 0;
    std::string file;
    int steps = 0;

    FrozenScene(const char* file_, int steps_) : file(file_), steps(steps_) {
        Scene scene = loadScene(std::string(RUBBLE_SOURCE_DIR "/scenes/") + file);
        params = {scene.settings.contactMargin, scene.settings.timeStep};
        reuseDistance = scene.settings.manifoldReuseDistance;
        // The bodies where the engine's own steps leave them (solver included, if the step has one).
        scene.settings.threads = 2;
        World world(scene.settings);
        const std::vector<BodyId> ids = instantiate(scene, world);
        for (int k = 0; k < steps; ++k) world.step(scene.settings.timeStep);

        for (const ShapeDef& def : scene.shapes) {
            shapes.push_back(buildShape(def));
            if (!shapes.back().staticOnly())
                table.set(static_cast<std::uint32_t>(shapes.size() - 1), shapeBoundsInfo(shapes.back()));
        }
        TaskPool pool(1);
        for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
            const SceneBody& body = scene.bodies[b];
            const Transform pose = world.transform(ids[b]);
            std::uint32_t i;
            if (body.def.type == BodyType::Static) {
                const BodyId id = storage.allocate(BodySet::Static, i);
                StaticBodies& st = storage.statics;
                st.px[i] = pose.position.x, st.py[i] = pose.position.y, st.pz[i] = pose.position.z;
                st.qx[i] = pose.rotation.x, st.qy[i] = pose.rotation.y, st.qz[i] = pose.rotation.z;
                st.qw[i] = pose.rotation.w;
                st.shape[i] = body.shape;
                st.filterCategory[i] = body.def.filter.category;
                st.filterMask[i] = body.def.filter.mask;
                broad.staticAdded(id.index, storage, shapes, pool);
                continue;
            }
            storage.allocate(BodySet::Moving, i);
            MovingBodies& m = storage.moving;
            const Quat q = pose.rotation;
            const Vec3 lc = shapes[body.shape].unitMass.centerOfMass;
            const Vec3 com = pose.position + rotate(q, lc);
            const Vec3 v = world.linearVelocity(ids[b]), w = world.angularVelocity(ids[b]);
            m.px[i] = com.x, m.py[i] = com.y, m.pz[i] = com.z;
            m.qx[i] = q.x, m.qy[i] = q.y, m.qz[i] = q.z, m.qw[i] = q.w;
            m.vx[i] = v.x, m.vy[i] = v.y, m.vz[i] = v.z;
            m.wx[i] = w.x, m.wy[i] = w.y, m.wz[i] = w.z;
            m.lcx[i] = lc.x, m.lcy[i] = lc.y, m.lcz[i] = lc.z;
            m.shape[i] = body.shape;
            m.filterCategory[i] = body.def.filter.category;
            m.filterMask[i] = body.def.filter.mask;
        }
        Bounds bounds;
        updateBounds(storage.moving, table, BoundsParams{params.dt, params.margin}, pool, bounds);
        broad.findPairs(bounds, storage, BroadPhaseKind::Auto, {}, pool, candidates);
    }
};

void runStage(benchmark::State& state, const char* file, int steps, bool reuse) {
    static std::vector<std::unique_ptr<FrozenScene>> cache;
    FrozenScene& scene = *[&] {
        for (auto& s : cache)
            if (s->steps == steps && s->file == file) return s.get();
        cache.push_back(std::make_unique<FrozenScene>(file, steps));
        return cache.back().get();
    }();
    TaskPool pool(static_cast<int>(state.range(0)));
    NarrowPhaseStage stage;
    Contacts contacts;
    NarrowPhaseParams params = scene.params;
    params.reuseDistance = reuse ? scene.reuseDistance : 0.0f;
    for (auto _ : state) {
        stage.run(scene.candidates, scene.storage, scene.shapes, params, pool, contacts);
        benchmark::DoNotOptimize(contacts.manifolds.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * contacts.manifolds.size()));
    state.counters["manifolds"] = static_cast<double>(contacts.manifolds.size());
    state.counters["points"] = contacts.pointCount;
    state.counters["candidates"] =
        static_cast<double>(scene.candidates.moving.size() + scene.candidates.statics.size());
    state.counters["triangles"] = static_cast<double>(scene.candidates.meshTriangles.size());
    state.counters["reused"] = stage.reusedManifolds();
}

}  // namespace

BENCHMARK_CAPTURE(runStage, S1_pyramid_start, "s1_pyramid.json", 0, false)->Apply(atOneAndTwoThreads);
BENCHMARK_CAPTURE(runStage, S1_pyramid_step60, "s1_pyramid.json", 60, false)->Apply(atOneAndTwoThreads);
BENCHMARK_CAPTURE(runStage, S3_mesh_pile_step60, "s3_mesh_pile.json", 60, false)->Apply(atOneAndTwoThreads);
BENCHMARK_CAPTURE(runStage, S3_mesh_pile_step90, "s3_mesh_pile.json", 90, false)->Apply(atOneAndTwoThreads);
BENCHMARK_CAPTURE(runStage, S3_mesh_pile_step300, "s3_mesh_pile.json", 300, false)->Apply(atOneAndTwoThreads);
BENCHMARK_CAPTURE(runStage, S3_mesh_pile_step300_reused, "s3_mesh_pile.json", 300, true)->Apply(atOneAndTwoThreads);
