#include "narrowphase/narrowphase_stage.h"

#include <algorithm>
#include <cassert>
#include <tuple>

#include "bounds/bounds.h"
#include "broadphase/static_bvh.h"
#include "core/parallel.h"
#include "narrowphase/box_box.h"
#include "narrowphase/convex_pairs.h"
#include "narrowphase/hull_pairs.h"
#include "narrowphase/mesh_manifolds.h"
#include "narrowphase/triangle_pairs.h"
#include "narrowphase/triangle_reach.h"
#include "shapes/mesh_adjacency.h"
#include "simd/simd.h"
#include "simd/transpose.h"
#include "simd/vec.h"

namespace rubble::detail {
namespace {

using simd::FloatW;
using simd::Vec3W;

/// Candidates per parallel task: enough work to amortise a task, small enough for two threads to balance.
constexpr std::size_t kChunk = 256;
/// Chunks per task when their results are copied to the output.
constexpr std::size_t kMergeChunks = 8;

/// Moving bodies per task when their rows are written.
constexpr std::size_t kRowChunk = 1024;
/// Columns of MovingRows' pose and motion rows.
enum PoseColumn : std::size_t { kComX, kComY, kComZ, kRotX, kRotY, kRotZ, kRotW, kLocalComX };
enum MotionColumn : std::size_t { kVelX, kVelY, kVelZ, kSpinX, kSpinY, kSpinZ, kLocalComY, kLocalComZ };
static_assert(kLocalComX + 1 == simd::kRowFloats && kLocalComZ + 1 == simd::kRowFloats, "rows hold eight floats");

/// Pairs the batched kernels take at a time: four SIMD batches, so that their lanes and manifolds stay in L1.
constexpr std::size_t kBlock = 64;
static_assert(kBlock % simd::kLanes == 0, "blocks hold whole batches");

/// Input lanes of a block: per side the shape's pose (origin and orientation; a sphere's centre) and size (half
/// extents; a sphere's radius in x), then each pair's margin.
enum InputLane : std::size_t { kPx, kPy, kPz, kQx, kQy, kQz, kQw, kSx, kSy, kSz, kSideLanes };
constexpr std::size_t kSideB = kSideLanes;
constexpr std::size_t kMarginLane = 2 * kSideLanes;
constexpr std::size_t kInputLanes = kMarginLane + 1;

/// How each side of a batched kernel's pairs is laid out in the input lanes. Sphere: centre in the position lanes,
/// radius in size x. Box: origin, orientation, half extents. Capsule: centre, half axis (in the orientation lanes
/// x, y, z), radius in size x.
enum class SideForm : std::uint8_t { Sphere, Box, Capsule };

}  // namespace

struct NarrowPhaseStage::Scratch {
    /// Jobs of the chunk for each batched kernel.
    std::vector<std::uint32_t> batched[static_cast<int>(BatchedKernel::Count)];
    alignas(64) float in[kInputLanes][kBlock];
    /// Results of the closed-form kernels: normal xyz, point xyz, depth, second point xyz, depth.
    alignas(64) float out[11][kBlock];
    alignas(64) std::uint32_t feature[2][kBlock];
    alignas(64) std::int32_t count[kBlock];
    /// A body's run of triangle jobs: world vertices (SoA, x y z of vertex 0, 1, 2), active edges and the reach
    /// tests' verdicts, padded to whole SIMD batches; grown, never shrunk.
    std::vector<float> triangles[9];
    std::vector<std::uint8_t> activeEdges;
    std::unique_ptr<bool[]> inReach;
    std::size_t inReachCapacity = 0;
    std::vector<BoxTriangleAxis> boxAxes;  ///< a box's SAT per triangle
};

namespace {

struct Posed {
    Transform pose;  ///< of the shape's local origin
    const Shape* shape;
};

/// Body i's row in MovingRows::pose or ::motion.
[[gnu::always_inline]] inline const float* rowOf(const AlignedVector<float>& rows, std::uint32_t i) {
    return rows.data() + std::size_t{i} * simd::kRowFloats;
}

// Always inlined, as posedSide: returned through memory, the pose is written in pieces and read back whole, which
// stalls on store forwarding in the per-pair loop.
[[gnu::always_inline]] inline Posed posed(const BodyStorage& storage, const MovingRows& rows,
                                          const std::vector<Shape>& shapes, std::uint32_t i, bool isStatic) {
    if (isStatic) {
        const StaticBodies& s = storage.statics;
        return {{{s.px[i], s.py[i], s.pz[i]}, {s.qx[i], s.qy[i], s.qz[i], s.qw[i]}}, &shapes[s.shape[i]]};
    }
    const float* pose = rowOf(rows.pose, i);
    const float* motion = rowOf(rows.motion, i);
    const Quat q{pose[kRotX], pose[kRotY], pose[kRotZ], pose[kRotW]};
    const Vec3 origin = Vec3{pose[kComX], pose[kComY], pose[kComZ]} -
                        rotate(q, {pose[kLocalComX], motion[kLocalComY], motion[kLocalComZ]});
    return {{origin, q}, &shapes[storage.moving.shape[i]]};
}

/// A side of a contact pair: the body's shape, or the compound child the pair names, posed in the world.
[[gnu::always_inline]] inline Posed posedSide(const BodyStorage& storage, const MovingRows& rows,
                                              const std::vector<Shape>& shapes, const ContactPair& p, bool sideB) {
    Posed body = sideB ? posed(storage, rows, shapes, p.b, p.bStatic) : posed(storage, rows, shapes, p.a, p.aStatic);
    const std::uint16_t child = sideB ? p.childB : p.childA;
    if (child == kNoChild) return body;
    const CompoundChild& c = body.shape->children[child];
    return {{apply(body.pose, c.local.position), body.pose.rotation * c.local.rotation}, c.shape.get()};
}

/// The shape of one side of a pair (the compound child it names).
const Shape& sideShape(const BodyStorage& storage, const std::vector<Shape>& shapes, const ContactPair& p, bool sideB) {
    const std::uint32_t i = sideB ? p.b : p.a;
    const Shape& body = shapes[(sideB ? p.bStatic : p.aStatic) ? storage.statics.shape[i] : storage.moving.shape[i]];
    const std::uint16_t child = sideB ? p.childB : p.childA;
    return child == kNoChild ? body : *body.children[child].shape;
}

/// How far a shape's surface lies beyond its core: a sphere's or capsule's radius, 0 for polytopes and triangles.
float roundingOf(const Shape& shape) {
    return shape.kind == ShapeKind::Sphere || shape.kind == ShapeKind::Capsule ? shape.radius : 0.0f;
}

CapsuleSegment segmentOf(const Posed& p) { return capsuleSegmentOf(p.pose, p.shape->halfHeight, p.shape->radius); }

/// A body against a static mesh or heightfield: what all its triangle jobs (which come in a row) share, worked out
/// once. Terrain usually sits at the origin unrotated; its vertices are then used as stored.
struct MeshSide {
    const TriangleMesh* mesh = nullptr;  ///< else a heightfield
    const Heightfield* heightfield = nullptr;
    bool identity = false;
    Mat3 rotation;
    Vec3 position;
    TriangleBox box;         ///< body A when it is a box
    CapsuleSegment capsule;  ///< body A when it is a capsule

    void prepare(const Posed& a, const Posed& meshBody) {
        const Shape& shape = *meshBody.shape;
        mesh = shape.kind == ShapeKind::TriangleMesh ? shape.mesh.get() : nullptr;
        heightfield = mesh ? nullptr : shape.heightfield.get();
        const Transform& pose = meshBody.pose;
        identity = pose.rotation == Quat{} && pose.position.x == 0 && pose.position.y == 0 && pose.position.z == 0;
        position = pose.position;
        rotation = rotationMatrix(pose.rotation);
        if (a.shape->kind == ShapeKind::Box) box = triangleBox(a.pose, a.shape->halfExtents);
        if (a.shape->kind == ShapeKind::Capsule) capsule = segmentOf(a);
    }

    /// World vertices and active-edge mask of triangle t.
    void triangle(std::uint32_t t, TriangleVertices& vertices, std::uint8_t& activeEdges) const {
        if (mesh) {
            const std::uint32_t* index = &mesh->indices[3 * std::size_t(t)];
            for (int k = 0; k < 3; ++k) vertices[k] = mesh->vertices[index[k]];
            activeEdges = mesh->activeEdges.empty() ? kAllEdgesActive : mesh->activeEdges[t];
        } else {
            vertices = heightfieldTriangle(*heightfield, t);
            activeEdges = heightfieldActiveEdges(*heightfield, t);
        }
        if (!identity)
            for (Vec3& v : vertices) v = rotation * v + position;
    }
};

/// Centre of a sphere side. A whole moving sphere's centre is its centre of mass, so only its pose row is read, not
/// the motion row that posed() needs for the local centre of mass.
Vec3 sphereCenter(const BodyStorage& storage, const MovingRows& rows, const std::vector<Shape>& shapes,
                  const ContactPair& p, bool sideB) {
    const std::uint32_t i = sideB ? p.b : p.a;
    if (!(sideB ? p.bStatic : p.aStatic) && (sideB ? p.childB : p.childA) == kNoChild) {
        const float* pose = rowOf(rows.pose, i);
        return {pose[kComX], pose[kComY], pose[kComZ]};
    }
    return posedSide(storage, rows, shapes, p, sideB).pose.position;
}

/// The capsule-box kernel sees the capsule as A; the stage's order has the box first. Same contact seen from the
/// other body: the normal turns round and the points move across the overlap onto the capsule.
void collideBoxCapsule(const Posed& box, const Posed& capsule, float margin, Manifold& out) {
    collideCapsuleBox(segmentOf(capsule), box.pose, box.shape->halfExtents, margin, out);
    for (int p = 0; p < out.pointCount; ++p) out.points[p].position += out.normal * out.points[p].depth;
    out.normal = -out.normal;
}

/// One pair through its scalar kernel (not the triangle kernels: collideTriangles).
template <class HullMap>
void collide(PairKernel kernel, const Posed& a, const Posed& b, float margin, const HullMap& hulls, Manifold& out) {
    auto adjacency = [&](const Posed& p) -> const HullAdjacency& { return *hulls.at(p.shape->hull.get()).adjacency; };
    out.pointCount = 0;
    switch (kernel) {
        case PairKernel::SphereSphere:
            collideSpheres(a.pose.position, a.shape->radius, b.pose.position, b.shape->radius, margin, out);
            break;
        case PairKernel::SphereBox:
            collideSphereBox(a.pose.position, a.shape->radius, b.pose, b.shape->halfExtents, margin, out);
            break;
        case PairKernel::SphereCapsule:
            collideSphereCapsule(a.pose.position, a.shape->radius, segmentOf(b), margin, out);
            break;
        case PairKernel::BoxBox:
            collideBoxes(a.pose, a.shape->halfExtents, b.pose, b.shape->halfExtents, margin, out);
            break;
        case PairKernel::CapsuleCapsule:
            collideCapsules(segmentOf(a), segmentOf(b), margin, out);
            break;
        case PairKernel::SphereHull:
            // A sphere is a capsule whose segment has no length.
            collideCapsuleHull({a.pose.position, {}, a.shape->radius}, *b.shape->hull, adjacency(b), b.pose, margin,
                               out);
            break;
        case PairKernel::BoxCapsule:
            collideBoxCapsule(a, b, margin, out);
            break;
        case PairKernel::BoxHull:
            collideBoxHull(a.pose, a.shape->halfExtents, *b.shape->hull, adjacency(b), b.pose, margin, out);
            break;
        case PairKernel::CapsuleHull:
            collideCapsuleHull(segmentOf(a), *b.shape->hull, adjacency(b), b.pose, margin, out);
            break;
        case PairKernel::HullHull:
            collideHulls(*a.shape->hull, adjacency(a), a.pose, *b.shape->hull, adjacency(b), b.pose, margin, out);
            break;
        case PairKernel::SphereTriangle:
        case PairKernel::CapsuleTriangle:
        case PairKernel::BoxTriangle:
        case PairKernel::HullTriangle:
        case PairKernel::Count:
            break;  // triangles: collideTriangles
    }
}

/// Body A against the triangles of a run job (against the mesh `mesh`, prepared for A): the vertices of all of them
/// are fetched first, the reach tests (triangle_reach.h) run over them in SIMD lanes, and the exact kernel only sees
/// the triangles they leave. Touching triangles are appended to the chunk's mesh manifolds, those that share a normal
/// merged (mesh_manifolds.h).
template <class HullMap>
void collideTriangles(const NarrowPhaseStage::Job& job, const std::uint32_t* triangles, const Posed& a,
                      const MeshSide& mesh, float margin, const HullMap& hulls, NarrowPhaseStage::Chunk& chunk,
                      NarrowPhaseStage::Scratch& s) {
    const std::size_t count = job.triangles, padded = triangleLanesPadded(count);
    for (std::vector<float>& lane : s.triangles)
        if (lane.size() < padded) lane.resize(padded);
    if (s.activeEdges.size() < count) s.activeEdges.resize(count);
    if (s.inReachCapacity < padded) {
        s.inReach = std::make_unique<bool[]>(padded);
        s.inReachCapacity = padded;
    }
    for (std::size_t k = 0; k < count; ++k) {
        TriangleVertices tri;
        mesh.triangle(triangles[k], tri, s.activeEdges[k]);
        for (int v = 0; v < 3; ++v) {
            s.triangles[3 * v][k] = tri[v].x;
            s.triangles[3 * v + 1][k] = tri[v].y;
            s.triangles[3 * v + 2][k] = tri[v].z;
        }
    }
    // The padding repeats the last triangle: finite values the wide tests may read.
    for (std::vector<float>& lane : s.triangles)
        std::fill(lane.begin() + count, lane.begin() + padded, lane[count - 1]);
    const TriangleLanes lanes{{s.triangles[0].data(), s.triangles[3].data(), s.triangles[6].data()},
                              {s.triangles[1].data(), s.triangles[4].data(), s.triangles[7].data()},
                              {s.triangles[2].data(), s.triangles[5].data(), s.triangles[8].data()}};
    bool* inReach = s.inReach.get();
    switch (job.kernel) {
        case PairKernel::SphereTriangle:
            sphereTrianglesInReach(a.pose.position, a.shape->radius, margin, lanes, count, inReach);
            break;
        case PairKernel::CapsuleTriangle:
            capsuleTrianglesInReach(mesh.capsule, margin, lanes, count, inReach);
            break;
        case PairKernel::BoxTriangle:
            // The box kernel's whole SAT runs in lanes (most of the triangles a box reaches touch it).
            if (s.boxAxes.size() < padded) s.boxAxes.resize(padded);
            boxTriangleAxes(mesh.box, margin, lanes, count, s.boxAxes.data());
            for (std::size_t k = 0; k < count; ++k) inReach[k] = s.boxAxes[k].kind >= 0;
            break;
        default:
            std::fill(inReach, inReach + count, true);  // hulls: no reach test, every triangle to the kernel
            break;
    }
    const std::size_t firstOutput = chunk.meshManifolds.size();
    Manifold out;
    for (std::size_t k = 0; k < count; ++k) {
        if (!inReach[k]) continue;
        TriangleVertices tri;
        for (int v = 0; v < 3; ++v)
            tri[v] = {s.triangles[3 * v][k], s.triangles[3 * v + 1][k], s.triangles[3 * v + 2][k]};
        const std::uint8_t active = s.activeEdges[k];
        out.pointCount = 0;
        switch (job.kernel) {
            case PairKernel::SphereTriangle:
                collideSphereTriangle(a.pose.position, a.shape->radius, tri, active, margin, out);
                break;
            case PairKernel::CapsuleTriangle:
                collideCapsuleTriangle(mesh.capsule, tri, active, margin, out, /*inReach=*/true);
                break;
            case PairKernel::BoxTriangle:
                collideBoxTriangle(mesh.box, tri, active, margin, s.boxAxes[k], out);
                break;
            case PairKernel::HullTriangle:
                collideHullTriangle(*a.shape->hull, *hulls.at(a.shape->hull.get()).adjacency, a.pose, tri, active,
                                    margin, out);
                break;
            default:
                break;
        }
        if (out.pointCount == 0) continue;
        ContactPair pair = job.pair;
        pair.triangle = triangles[k];
        chunk.meshPairs.push_back(pair);
        chunk.meshManifolds.push_back(out);
    }
    mergeTriangleManifolds(chunk.meshPairs, chunk.meshManifolds, firstOutput);
}

/// Memory of the triangle runs after job j while job j runs (its kernels take microseconds): the vertices of job
/// j + 1's triangles, whose indices the previous call fetched, and the indices of job j + 2's. Terrain is read in no
/// particular order, so these are mostly cache misses otherwise. Only for the same mesh as job j (the usual case).
/// Always inlined: GCC judges a function that only prefetches free of effects and may delete calls to it.
[[gnu::always_inline]] inline void prefetchTriangles(const NarrowPhaseStage::Chunk& chunk, std::size_t j,
                                                     const std::vector<std::uint32_t>& meshTriangles,
                                                     const MeshSide& mesh) {
    if (mesh.mesh == nullptr) return;
    const std::uint32_t* indices = mesh.mesh->indices.data();
    const Vec3* vertices = mesh.mesh->vertices.data();
    const ContactPair& pair = chunk.jobs[j].pair;
    for (std::size_t ahead = 1; ahead <= 2 && j + ahead < chunk.jobs.size(); ++ahead) {
        const NarrowPhaseStage::Job& next = chunk.jobs[j + ahead];
        if (next.triangles == 0 || next.reuse != NarrowPhaseStage::kNoReuse || next.pair.b != pair.b ||
            !next.pair.bStatic)
            return;
        for (std::uint32_t k = 0; k < next.triangles; ++k) {
            const std::uint32_t* triangle = indices + 3 * std::size_t(meshTriangles[next.firstTriangle + k]);
            if (ahead == 2) {
                __builtin_prefetch(triangle);
                continue;
            }
            for (int v = 0; v < 3; ++v) __builtin_prefetch(vertices + triangle[v]);
        }
    }
}

/// The pair's margin for this step (see NarrowPhaseStage::run): the fixed margin plus how far the two surfaces can
/// close in dt. Written once for both lane types so that batched and one-at-a-time pairs get the same margins.
template <class F>
F speculativeMargin(const NarrowPhaseParams& params, const Vec3W<F>& vA, const Vec3W<F>& wA, const F& reachA,
                    const Vec3W<F>& vB, const Vec3W<F>& wB, const F& reachB) {
    const F dt(params.dt), two(2.0f);
    const F turnA = simd::min(simd::length(wA) * dt, two) * reachA;
    const F turnB = simd::min(simd::length(wB) * dt, two) * reachB;
    return F(params.margin) + simd::length(vB - vA) * dt + turnA + turnB;
}

/// Whether a pair's manifolds are worth keeping for reuse: not those of the kernels that run in SIMD lanes (sphere,
/// capsule and box pairs but capsule-box), which cost less than a lookup and a copy.
bool worthReusing(ShapeKind first, ShapeKind second) {
    const auto batched = [](ShapeKind k) {
        return k == ShapeKind::Sphere || k == ShapeKind::Capsule || k == ShapeKind::Box;
    };
    const bool capsuleBox = (first == ShapeKind::Capsule && second == ShapeKind::Box) ||
                            (first == ShapeKind::Box && second == ShapeKind::Capsule);
    return capsuleBox || !(batched(first) && batched(second));
}

/// What bounds the approach of one side of a pair: its velocities and the reach of its shape (zero for statics).
template <class F>
struct Motion {
    Vec3W<F> v = Vec3W<F>::zero(), w = Vec3W<F>::zero();
    F reach = F(0.0f);
};

Motion<float> motionOf(const BodyStorage& storage, const MovingRows& rows, const ShapeTables& tables,
                       const ContactPair& p, bool sideB) {
    if (sideB ? p.bStatic : p.aStatic) return {};
    const std::uint32_t i = sideB ? p.b : p.a;
    const float* motion = rowOf(rows.motion, i);
    return {{motion[kVelX], motion[kVelY], motion[kVelZ]},
            {motion[kSpinX], motion[kSpinY], motion[kSpinZ]},
            tables.reach[storage.moving.shape[i]]};
}

/// The size columns of ShapeTables for a shape (see there).
Vec3 sizeOf(const Shape& shape) {
    switch (shape.kind) {
        case ShapeKind::Box:
            return shape.halfExtents;
        case ShapeKind::Sphere:
            return {shape.radius, 0, 0};
        case ShapeKind::Capsule:
            return {shape.radius, shape.halfHeight, 0};
        default:
            return {};
    }
}

/// One side of SIMD-width pairs, as the batched kernels take it.
struct SideLanes {
    Vec3W<FloatW> position;  ///< shape origin (a sphere's or capsule's centre)
    simd::QuatW<FloatW> q;
    Vec3W<FloatW> size;  ///< as ShapeTables
    Motion<FloatW> motion;
};

/// How the pairs of a batch reach one side's data: all whole moving bodies and all whole static bodies are
/// gathered lane-wide; anything else (compound children, a mix) goes lane by lane.
enum class SideSource { Moving, Static, Mixed };

/// Side `sideB` of the pairs jobs[0 .. kLanes) (jobs of `chunk`), gathered into lanes. Whole moving bodies: the shape
/// origin from the centre of mass (com - R lc, as posed() computes it), except that a sphere is at its centre of
/// mass (as sphereCenter() has it).
RUBBLE_FLATTEN SideLanes gatherSide(const NarrowPhaseStage::Chunk& chunk, const std::uint32_t* jobs, bool sideB,
                                    SideForm form, const BodyStorage& storage, const MovingRows& rows,
                                    const std::vector<Shape>& shapes, const ShapeTables& tables) {
    using simd::IntW;
    alignas(64) std::int32_t body[simd::kLanes], shape[simd::kLanes];
    bool allMoving = true, allStatic = true, oneShape = true;
    const MovingBodies& m = storage.moving;
    const StaticBodies& st = storage.statics;
    for (std::size_t k = 0; k < simd::kLanes; ++k) {
        const ContactPair& p = chunk.jobs[jobs[k]].pair;
        const std::uint32_t i = sideB ? p.b : p.a;
        const bool isStatic = sideB ? p.bStatic : p.aStatic;
        const bool whole = (sideB ? p.childB : p.childA) == kNoChild;
        allMoving = allMoving && whole && !isStatic;
        allStatic = allStatic && whole && isStatic;
        body[k] = static_cast<std::int32_t>(i);
        shape[k] = static_cast<std::int32_t>(isStatic ? st.shape[i] : m.shape[i]);
        oneShape = oneShape && shape[k] == shape[0];
    }
    const SideSource source = allMoving ? SideSource::Moving : (allStatic ? SideSource::Static : SideSource::Mixed);
    SideLanes side;
    if (source != SideSource::Mixed) {
        const IntW index = simd::loadInt<IntW>(body), shapeIndex = simd::loadInt<IntW>(shape);
        // Per-shape values: one load when every lane has the same shape (a pile of one kind of box), else gathered.
        auto perShape = [&](const std::vector<float>& table) {
            return oneShape ? FloatW(table[static_cast<std::size_t>(shape[0])])
                            : simd::gather(table.data(), shapeIndex);
        };
        auto vec = [&](const AlignedVector<float>& x, const AlignedVector<float>& y, const AlignedVector<float>& z) {
            return Vec3W<FloatW>{simd::gather(x.data(), index), simd::gather(y.data(), index),
                                 simd::gather(z.data(), index)};
        };
        if (source == SideSource::Moving) {
            FloatW pose[simd::kRowFloats], motion[simd::kRowFloats];
            simd::loadRowsTransposed(rows.pose.data(), body, pose);
            simd::loadRowsTransposed(rows.motion.data(), body, motion);
            side.position = {pose[kComX], pose[kComY], pose[kComZ]};
            side.q = {pose[kRotX], pose[kRotY], pose[kRotZ], pose[kRotW]};
            if (form != SideForm::Sphere)
                side.position = side.position - simd::rotate(side.q, Vec3W<FloatW>{pose[kLocalComX], motion[kLocalComY],
                                                                                   motion[kLocalComZ]});
            side.motion = {{motion[kVelX], motion[kVelY], motion[kVelZ]},
                           {motion[kSpinX], motion[kSpinY], motion[kSpinZ]},
                           perShape(tables.reach)};
        } else {
            side.position = vec(st.px, st.py, st.pz);
            side.q = {simd::gather(st.qx.data(), index), simd::gather(st.qy.data(), index),
                      simd::gather(st.qz.data(), index), simd::gather(st.qw.data(), index)};
        }
        side.size = {perShape(tables.sizeX), perShape(tables.sizeY), perShape(tables.sizeZ)};
        return side;
    }
    // Lane by lane, through the same helpers as the one-pair kernels.
    alignas(64) float lanes[17][simd::kLanes];
    for (std::size_t k = 0; k < simd::kLanes; ++k) {
        const ContactPair& p = chunk.jobs[jobs[k]].pair;
        const Posed posed = posedSide(storage, rows, shapes, p, sideB);
        const Vec3 position =
            form == SideForm::Sphere ? sphereCenter(storage, rows, shapes, p, sideB) : posed.pose.position;
        const Quat q = posed.pose.rotation;
        const Vec3 size = sizeOf(*posed.shape);
        const Motion<float> motion = motionOf(storage, rows, tables, p, sideB);
        const float values[17] = {position.x, position.y, position.z, q.x,        q.y,         q.z,
                                  q.w,        size.x,     size.y,     size.z,     motion.v.x,  motion.v.y,
                                  motion.v.z, motion.w.x, motion.w.y, motion.w.z, motion.reach};
        for (std::size_t f = 0; f < 17; ++f) lanes[f][k] = values[f];
    }
    auto load = [&](std::size_t f) { return simd::load<FloatW>(lanes[f]); };
    auto load3 = [&](std::size_t f) { return Vec3W<FloatW>{load(f), load(f + 1), load(f + 2)}; };
    side.position = load3(0);
    side.q = {load(3), load(4), load(5), load(6)};
    side.size = load3(7);
    side.motion = {load3(10), load3(13), load(16)};
    return side;
}

/// Pairs [k0, k0 + kLanes) of a block into its input lanes; `jobs` holds the block's jobs, `count` of them valid
/// (lanes past the end repeat the last job, so every gather reads a real body; their results are not used).
void gatherBatch(const NarrowPhaseStage::Chunk& chunk, const std::uint32_t* jobs, std::size_t count, std::size_t k0,
                 SideForm formA, SideForm formB, const BodyStorage& storage, const MovingRows& rows,
                 const std::vector<Shape>& shapes, const ShapeTables& tables, const NarrowPhaseParams& params,
                 NarrowPhaseStage::Scratch& s) {
    std::uint32_t batch[simd::kLanes];
    for (std::size_t k = 0; k < simd::kLanes; ++k) batch[k] = jobs[std::min(k0 + k, count - 1)];
    const SideLanes a = gatherSide(chunk, batch, false, formA, storage, rows, shapes, tables);
    const SideLanes b = gatherSide(chunk, batch, true, formB, storage, rows, shapes, tables);
    for (const auto& [side, form, base] : {std::tuple{&a, formA, std::size_t{0}}, std::tuple{&b, formB, kSideB}}) {
        side->position.store(s.in[base + kPx], s.in[base + kPy], s.in[base + kPz], k0);
        side->size.store(s.in[base + kSx], s.in[base + kSy], s.in[base + kSz], k0);
        if (form == SideForm::Capsule) {
            // The capsule's segment: centre -/+ this half axis (capsuleSegmentOf).
            const Vec3W<FloatW> axis = simd::rotate(side->q, Vec3W<FloatW>{FloatW(0.0f), side->size.y, FloatW(0.0f)});
            axis.store(s.in[base + kQx], s.in[base + kQy], s.in[base + kQz], k0);
        } else {
            side->q.store(s.in[base + kQx], s.in[base + kQy], s.in[base + kQz], s.in[base + kQw], k0);
        }
    }
    simd::store(s.in[kMarginLane] + k0, speculativeMargin<FloatW>(params, a.motion.v, a.motion.w, a.motion.reach,
                                                                  b.motion.v, b.motion.w, b.motion.reach));
}

/// The jobs of one batched kernel in a chunk, a block at a time: each side's pose, size and motion gathered into
/// lanes, margins in SIMD, then the kernel. Box-box writes each job's manifold in place; the closed-form kernels
/// leave SoA results that are copied into the jobs' manifolds.
void collideBatched(BatchedKernel kernel, const std::vector<std::uint32_t>& list, NarrowPhaseStage::Chunk& chunk,
                    NarrowPhaseStage::Scratch& s, const BodyStorage& storage, const MovingRows& rows,
                    const std::vector<Shape>& shapes, const ShapeTables& tables, const NarrowPhaseParams& params) {
    const auto& in = s.in;
    const std::size_t b = kSideB;
    const float* margin = in[kMarginLane];
    static constexpr SideForm kForms[static_cast<int>(BatchedKernel::Count)][2] = {
        {SideForm::Sphere, SideForm::Sphere},
        {SideForm::Sphere, SideForm::Box},
        {SideForm::Sphere, SideForm::Capsule},
        {SideForm::Capsule, SideForm::Capsule},
        {SideForm::Box, SideForm::Box}};
    const SideForm formA = kForms[static_cast<int>(kernel)][0], formB = kForms[static_cast<int>(kernel)][1];
    const PairContacts result{s.out[0],     s.out[1], s.out[2], s.out[3], s.out[4], s.out[5],  s.out[6],
                              s.feature[0], s.count,  s.out[7], s.out[8], s.out[9], s.out[10], s.feature[1]};
    for (std::size_t first = 0; first < list.size(); first += kBlock) {
        const std::uint32_t* jobs = list.data() + first;
        const std::size_t n = std::min(kBlock, list.size() - first);
        for (std::size_t k0 = 0; k0 < n; k0 += simd::kLanes)
            gatherBatch(chunk, jobs, n, k0, formA, formB, storage, rows, shapes, tables, params, s);
        switch (kernel) {
            case BatchedKernel::BoxBox:
                collideBoxesBatch(
                    {in[kPx],     in[kPy],     in[kPz],     in[kQx],     in[kQy],     in[kQz],     in[kQw],
                     in[kSx],     in[kSy],     in[kSz],     in[b + kPx], in[b + kPy], in[b + kPz], in[b + kQx],
                     in[b + kQy], in[b + kQz], in[b + kQw], in[b + kSx], in[b + kSy], in[b + kSz], margin},
                    n, chunk.manifolds.data(), jobs, /*padded=*/true);
                continue;
            case BatchedKernel::SphereSphere:
                collideSpheresBatch(
                    {in[kPx], in[kPy], in[kPz], in[kSx], in[b + kPx], in[b + kPy], in[b + kPz], in[b + kSx], margin}, n,
                    params.margin, result);
                break;
            case BatchedKernel::SphereBox:
                collideSphereBoxesBatch(
                    {in[kPx], in[kPy], in[kPz], in[kSx], in[b + kPx], in[b + kPy], in[b + kPz], in[b + kQx],
                     in[b + kQy], in[b + kQz], in[b + kQw], in[b + kSx], in[b + kSy], in[b + kSz], margin},
                    n, params.margin, result);
                break;
            case BatchedKernel::SphereCapsule:
                collideSphereCapsulesBatch({in[kPx], in[kPy], in[kPz], in[kSx], in[b + kPx], in[b + kPy], in[b + kPz],
                                            in[b + kQx], in[b + kQy], in[b + kQz], in[b + kSx], margin},
                                           n, params.margin, result);
                break;
            case BatchedKernel::CapsuleCapsule:
                collideCapsulesBatch(
                    {in[kPx], in[kPy], in[kPz], in[kQx], in[kQy], in[kQz], in[kSx], in[b + kPx], in[b + kPy],
                     in[b + kPz], in[b + kQx], in[b + kQy], in[b + kQz], in[b + kSx], margin},
                    n, params.margin, result);
                break;
            case BatchedKernel::Count:
                break;
        }
        for (std::size_t k = 0; k < n; ++k) {
            Manifold& m = chunk.manifolds[jobs[k]];
            m.pointCount = s.count[k];
            m.normal = {s.out[0][k], s.out[1][k], s.out[2][k]};
            m.points[0] = {{s.out[3][k], s.out[4][k], s.out[5][k]}, s.out[6][k], s.feature[0][k]};
            if (m.pointCount > 1)
                m.points[1] = {{s.out[7][k], s.out[8][k], s.out[9][k]}, s.out[10][k], s.feature[1][k]};
        }
    }
}

}  // namespace

NarrowPhaseStage::NarrowPhaseStage() = default;
NarrowPhaseStage::~NarrowPhaseStage() = default;

void NarrowPhaseStage::prepareShapes(const std::vector<Shape>& shapes) {
    const std::size_t n = shapes.size();
    for (auto* table : {&tables_.sizeX, &tables_.sizeY, &tables_.sizeZ, &tables_.reach}) table->resize(n);
    tables_.kind.resize(n);
    knownHull_.resize(n, nullptr);
    auto ensureAdjacency = [&](const std::shared_ptr<const ConvexHull>& hull) {
        HullEntry& entry = hullAdjacency_[hull.get()];
        if (!entry.adjacency) {
            entry.hull = hull;
            entry.adjacency = std::make_unique<HullAdjacency>(buildHullAdjacency(*hull));
        }
    };
    // Every hull any shape holds gets its adjacency here, so the parallel part only reads the map. A per-slot
    // pointer makes the common case (hull seen before) one comparison: a hull in the map is kept alive by it, so an
    // equal address is the same hull.
    for (std::size_t s = 0; s < n; ++s) {
        const Shape& shape = shapes[s];
        tables_.kind[s] = shape.kind;
        const Vec3 size = sizeOf(shape);
        tables_.sizeX[s] = size.x, tables_.sizeY[s] = size.y, tables_.sizeZ[s] = size.z;
        tables_.reach[s] = rotationReach(shape);
        if (shape.kind == ShapeKind::ConvexHull && shape.hull && knownHull_[s] != shape.hull.get()) {
            ensureAdjacency(shape.hull);
            knownHull_[s] = shape.hull.get();
        } else if (shape.kind == ShapeKind::Compound) {
            for (const CompoundChild& child : shape.children)
                if (child.shape->kind == ShapeKind::ConvexHull) ensureAdjacency(child.shape->hull);
        }
    }
}

void NarrowPhaseStage::prepareRows(const MovingBodies& m, TaskPool& pool) {
    const std::size_t n = m.size();
    rows_.pose.resize(n * simd::kRowFloats);
    rows_.motion.resize(n * simd::kRowFloats);
    pool.forChunks(n, kRowChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) {
            float* pose = rows_.pose.data() + i * simd::kRowFloats;
            float* motion = rows_.motion.data() + i * simd::kRowFloats;
            pose[kComX] = m.px[i], pose[kComY] = m.py[i], pose[kComZ] = m.pz[i];
            pose[kRotX] = m.qx[i], pose[kRotY] = m.qy[i], pose[kRotZ] = m.qz[i], pose[kRotW] = m.qw[i];
            pose[kLocalComX] = m.lcx[i];
            motion[kVelX] = m.vx[i], motion[kVelY] = m.vy[i], motion[kVelZ] = m.vz[i];
            motion[kSpinX] = m.wx[i], motion[kSpinY] = m.wy[i], motion[kSpinZ] = m.wz[i];
            motion[kLocalComY] = m.lcy[i], motion[kLocalComZ] = m.lcz[i];
        }
    });
}

void NarrowPhaseStage::run(const CandidatePairs& candidates, const BodyStorage& storage,
                           const std::vector<Shape>& shapes, const NarrowPhaseParams& params, TaskPool& pool,
                           Contacts& out) {
    prepareShapes(shapes);
    prepareRows(storage.moving, pool);
    while (scratch_.size() < static_cast<std::size_t>(pool.threadCount()))
        scratch_.push_back(std::make_unique<Scratch>());

    // One index space over the candidates in canonical order: moving pairs, moving-static pairs, then every
    // triangle the broad phase handed over (so a body on a mesh spreads over chunks like any other work).
    const std::size_t movingCount = candidates.moving.size(), staticCount = candidates.statics.size();
    const std::size_t units = movingCount + staticCount + candidates.meshTriangles.size();
    const std::size_t chunkCount = TaskPool::chunkCount(units, kChunk);
    if (chunks_.size() < chunkCount) chunks_.resize(chunkCount);
    const bool reuse = params.reuseDistance > 0;
    if (reuse)
        reuse_.begin(chunkCount, storage.layoutChanges());
    else
        reuse_.clear();

    pool.forChunks(units, kChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int worker) {
        Chunk& chunk = chunks_[c];
        chunk.jobs.clear();
        chunk.reuses.clear();
        chunk.pending.clear();
        ManifoldReuse::ChunkCache* cache = reuse ? &reuse_.current(c) : nullptr;
        ManifoldReuse::Finder finder(reuse_);
        // A candidate whose kernels cost more than a lookup: its manifolds again if its bodies have hardly moved
        // (true: its jobs are made), else an entry that takes this step's manifolds (pending until they are made).
        auto reuseOrKeep = [&](ManifoldReuse::Section section, std::uint32_t first, std::uint32_t second,
                               bool secondStatic) {
            const MovingBodies& m = storage.moving;
            const StaticBodies& st = storage.statics;
            const std::uint32_t shape1 = m.shape[first], shape2 = secondStatic ? st.shape[second] : m.shape[second];
            if (!worthReusing(tables_.kind[shape1], tables_.kind[shape2])) return false;
            // Written in place (a whole Entry built on the stack and copied in stalls on store forwarding).
            const auto entryIndex = static_cast<std::uint32_t>(cache->entries.size());
            ManifoldReuse::Entry& now = cache->entries.emplace_back();
            now.order = ManifoldReuse::orderOf(section, first,
                                               section == ManifoldReuse::Section::Moving ? second : st.slot[second]);
            now.shapeFirst = shape1, now.shapeSecond = shape2;
            // The bodies' slots and generations (the slot map is read at random): compared only when bodies were
            // added or removed since last step, else taken over with a reused entry.
            const auto identify = [&] {
                const std::uint32_t slot1 = m.slot[first], slot2 = secondStatic ? st.slot[second] : m.slot[second];
                now.slots = (std::uint64_t{slot1} << 32) | slot2;
                now.generations =
                    (std::uint64_t{storage.idAt(slot1).generation} << 32) | storage.idAt(slot2).generation;
            };
            const bool sameBodies = reuse_.sameBodies();
            if (!sameBodies) identify();
            const auto movingPose = [&](std::uint32_t i) {
                const float* pose = rowOf(rows_.pose, i);
                return BodyPose{{pose[kComX], pose[kComY], pose[kComZ]},
                                {pose[kRotX], pose[kRotY], pose[kRotZ], pose[kRotW]}};
            };
            now.first = movingPose(first);
            if (secondStatic)
                now.second = {{st.px[second], st.py[second], st.pz[second]},
                              {st.qx[second], st.qy[second], st.qz[second], st.qw[second]}};
            else
                now.second = movingPose(second);
            const ContactPair asPair{first, second, false, secondStatic};
            const Motion<float> motion1 = motionOf(storage, rows_, tables_, asPair, false);
            const Motion<float> motion2 = motionOf(storage, rows_, tables_, asPair, true);
            now.margin = speculativeMargin<float>(params, motion1.v, motion1.w, motion1.reach, motion2.v, motion2.w,
                                                  motion2.reach);
            const ManifoldReuse::Finder::Found found = finder.find(now.order);
            if (found.entry != nullptr && found.entry->shapeFirst == shape1 && found.entry->shapeSecond == shape2 &&
                (sameBodies || (found.entry->slots == now.slots && found.entry->generations == now.generations))) {
                const ManifoldReuse::Entry& then = *found.entry;
                const PoseChange change1 = poseChange(then.first, now.first);
                const PoseChange change2 = poseChange(then.second, now.second);
                const float moved = relativeDisplacement(change1, change2, tables_.reach[shape1]);
                // Points the old margin left out were further apart than it, and can have closed by `moved`
                // since: the surfaces must not be able to close the rest in this step.
                if (moved <= params.reuseDistance && now.margin - params.margin + moved < then.margin) {
                    // Kept as computed then, under this step's order.
                    const std::uint64_t order = now.order;
                    const auto firstStored = static_cast<std::uint32_t>(cache->stored.size());
                    now = then;
                    now.order = order;
                    now.firstStored = firstStored;
                    cache->stored.insert(cache->stored.end(), found.stored, found.stored + then.storedCount);
                    const auto addReuse = [&](const ContactPair& pair, std::uint32_t triangles, bool swapped,
                                              std::uint32_t stored, std::uint32_t count) {
                        Job& job = chunk.jobs.emplace_back();
                        job.pair = pair;
                        job.triangles = triangles;
                        job.reuse = static_cast<std::uint32_t>(chunk.reuses.size());
                        Reuse& r = chunk.reuses.emplace_back();
                        r.a = swapped ? change2 : change1;
                        r.b = swapped ? change1 : change2;
                        r.firstStored = stored, r.count = count;
                    };
                    if (then.storedCount == 0) return true;
                    if (section == ManifoldReuse::Section::Mesh) {
                        const ManifoldReuse::Stored& s = *found.stored;
                        addReuse({first, second, false, true, s.triangle, s.childA, s.childB}, then.storedCount, false,
                                 firstStored, then.storedCount);
                        return true;
                    }
                    for (std::uint32_t k = 0; k < then.storedCount; ++k) {
                        const ManifoldReuse::Stored& s = found.stored[k];
                        addReuse(s.swapped
                                     ? ContactPair{second, first, secondStatic, false, s.triangle, s.childA, s.childB}
                                     : ContactPair{first, second, false, secondStatic, s.triangle, s.childA, s.childB},
                                 0, s.swapped, firstStored + k, 1);
                    }
                    return true;
                }
            }
            if (sameBodies) identify();
            const auto jobsNow = static_cast<std::uint32_t>(chunk.jobs.size());
            chunk.pending.push_back({entryIndex, first, jobsNow, jobsNow});
            return false;
        };
        // Closes the pending entry reuseOrKeep opened for the candidate whose jobs were just made.
        auto closePending = [&](std::size_t pendingBefore) {
            if (chunk.pending.size() > pendingBefore)
                chunk.pending.back().jobEnd = static_cast<std::uint32_t>(chunk.jobs.size());
        };
        // A is the body whose shape kind is lower, so each kernel sees its shapes in its own argument order.
        // Compounds expand into one job per child (per child pair for two compounds), in child order.
        // `run`: for a body against a mesh, the index of its first triangle in meshTriangles, and `runLength` the
        // number of its triangles; else ~0u. A compound's child gets the whole run.
        auto addJob = [&](std::uint32_t first, bool firstStatic, std::uint32_t second, bool secondStatic,
                          std::uint32_t run, std::uint32_t runLength = 0) {
            const std::uint32_t triangle = run == ~0u ? ~0u : candidates.meshTriangles[run];
            const std::uint32_t runStart = run == ~0u ? 0u : run;
            const std::uint32_t shape1 = firstStatic ? storage.statics.shape[first] : storage.moving.shape[first];
            const std::uint32_t shape2 = secondStatic ? storage.statics.shape[second] : storage.moving.shape[second];
            const ShapeKind kind1 = tables_.kind[shape1], kind2 = tables_.kind[shape2];
            if (kind1 != ShapeKind::Compound && kind2 != ShapeKind::Compound) {
                Job job;
                if (kind2 < kind1) {
                    job.pair = {second, first, secondStatic, firstStatic, triangle, kNoChild, kNoChild};
                    job.kernel = pairKernel(kind2, kind1);
                } else {
                    job.pair = {first, second, firstStatic, secondStatic, triangle, kNoChild, kNoChild};
                    job.kernel = pairKernel(kind1, kind2);
                }
                job.firstTriangle = runStart, job.triangles = runLength;
                chunk.jobs.push_back(job);
                return;
            }
            const Shape& s1 = shapes[shape1];
            const Shape& s2 = shapes[shape2];
            const bool compound1 = s1.kind == ShapeKind::Compound, compound2 = s2.kind == ShapeKind::Compound;
            const std::size_t n1 = compound1 ? s1.children.size() : 1, n2 = compound2 ? s2.children.size() : 1;
            for (std::size_t c1 = 0; c1 < n1; ++c1)
                for (std::size_t c2 = 0; c2 < n2; ++c2) {
                    const ShapeKind k1 = compound1 ? s1.children[c1].shape->kind : s1.kind;
                    const ShapeKind k2 = compound2 ? s2.children[c2].shape->kind : s2.kind;
                    const auto child1 = compound1 ? static_cast<std::uint16_t>(c1) : kNoChild;
                    const auto child2 = compound2 ? static_cast<std::uint16_t>(c2) : kNoChild;
                    Job job;
                    if (k2 < k1) {
                        job.pair = {second, first, secondStatic, firstStatic, triangle, child2, child1};
                        job.kernel = pairKernel(k2, k1);
                    } else {
                        job.pair = {first, second, firstStatic, secondStatic, triangle, child1, child2};
                        job.kernel = pairKernel(k1, k2);
                    }
                    job.firstTriangle = runStart, job.triangles = runLength;
                    chunk.jobs.push_back(job);
                }
        };
        for (std::size_t u = begin; u < std::min(end, movingCount); ++u) {
            const BodyPair& p = candidates.moving[u];
            const std::size_t pendingBefore = chunk.pending.size();
            if (reuse && reuseOrKeep(ManifoldReuse::Section::Moving, p.a, p.b, false)) continue;
            addJob(p.a, false, p.b, false, ~0u);
            closePending(pendingBefore);
        }
        for (std::size_t u = std::max(begin, movingCount); u < std::min(end, movingCount + staticCount); ++u) {
            const BodyPair& p = candidates.statics[u - movingCount];
            const std::size_t pendingBefore = chunk.pending.size();
            if (reuse && reuseOrKeep(ManifoldReuse::Section::Static, p.a, p.b, true)) continue;
            addJob(p.a, false, p.b, true, ~0u);
            closePending(pendingBefore);
        }
        // A body against a mesh (always B): one job for each run of its triangles that starts in the chunk, the
        // whole run, so that the run's manifolds can be merged (mesh_manifolds.h) and are reused or kept whole.
        // Mesh pairs hold consecutive runs of meshTriangles, so the pair of the chunk's first triangle is found once
        // and then followed.
        if (end > movingCount + staticCount) {
            const auto first =
                static_cast<std::uint32_t>(std::max(begin, movingCount + staticCount) - movingCount - staticCount);
            auto mesh = std::upper_bound(candidates.meshes.begin(), candidates.meshes.end(), first,
                                         [](std::uint32_t t, const MeshPair& m) { return t < m.firstTriangle; }) -
                        1;
            const auto last = static_cast<std::uint32_t>(end - movingCount - staticCount);
            // A run that started in an earlier chunk is that chunk's.
            auto t = mesh->firstTriangle < first ? mesh->firstTriangle + mesh->triangleCount : first;
            for (; t < last; ++mesh) {
                const std::uint32_t runEnd = mesh->firstTriangle + mesh->triangleCount;
                if (t >= runEnd) continue;
                const std::size_t pendingBefore = chunk.pending.size();
                if (reuse && reuseOrKeep(ManifoldReuse::Section::Mesh, mesh->moving, mesh->staticBody, true)) {
                    t = runEnd;
                    continue;
                }
                // One job over the whole run (a compound body: one per child, in child order).
                addJob(mesh->moving, false, mesh->staticBody, true, t, runEnd - t);
                t = runEnd;
                closePending(pendingBefore);
            }
        }
        runChunk(chunk, *scratch_[static_cast<std::size_t>(worker)], storage, shapes, candidates.meshTriangles, params,
                 cache);
        if (cache) keepComputed(chunk, *cache, storage, shapes);
    });

    // Each chunk's touching jobs go to the output at the offset its predecessors leave: canonical order on any
    // number of threads, one copy per manifold, and no output element constructed only to be overwritten.
    if (reuse) reuse_.finish();
    std::size_t total = 0;
    std::uint32_t points = 0;
    reusedManifolds_ = 0;
    for (std::size_t c = 0; c < chunkCount; ++c) {
        chunks_[c].offset = total;
        total += chunks_[c].touching;
        points += chunks_[c].points;
        reusedManifolds_ += chunks_[c].reused;
    }
    out.pairs.resize(total);
    out.manifolds.resize(total);
    out.pointCount = points;
    pool.forChunks(chunkCount, kMergeChunks, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t c = begin; c < end; ++c) {
            const Chunk& chunk = chunks_[c];
            std::size_t o = chunk.offset;
            for (std::size_t j = 0; j < chunk.jobs.size() && chunk.jobs[j].triangles == 0; ++j) {
                if (chunk.manifolds[j].pointCount == 0) continue;
                out.pairs[o] = chunk.jobs[j].pair;
                out.manifolds[o] = chunk.manifolds[j];
                ++o;
            }
            for (std::size_t k = 0; k < chunk.meshPairs.size(); ++k, ++o) {
                out.pairs[o] = chunk.meshPairs[k];
                out.manifolds[o] = chunk.meshManifolds[k];
            }
        }
    });
}

void NarrowPhaseStage::runChunk(Chunk& chunk, Scratch& scratch, const BodyStorage& storage,
                                const std::vector<Shape>& shapes, const std::vector<std::uint32_t>& meshTriangles,
                                const NarrowPhaseParams& params, const ManifoldReuse::ChunkCache* cache) const {
    const std::size_t n = chunk.jobs.size();
    if (chunk.manifolds.size() < n) chunk.manifolds.resize(n);
    chunk.meshPairs.clear();
    chunk.meshManifolds.clear();
    std::uint32_t reused = 0;
    for (auto& list : scratch.batched) list.clear();
    // Pairs with a batched kernel are collected for it; every other pair runs here, one at a time, with its own
    // speculative margin. A body on a mesh is one job per triangle, all in a row: they run together
    // (collideTriangles), their poses and margin worked out once.
    MeshSide mesh;
    for (std::uint32_t j = 0; j < n; ++j) {
        Job& job = chunk.jobs[j];
        if (job.reuse != kNoReuse) {
            const Reuse& r = chunk.reuses[job.reuse];
            const ManifoldReuse::Stored* stored = cache->stored.data() + r.firstStored;
            reused += r.count;
            if (job.triangles == 0) {
                moveManifold(stored->manifold, r.a, r.b, stored->radiusA, stored->radiusB, chunk.manifolds[j]);
                continue;
            }
            for (std::uint32_t k = 0; k < r.count; ++k) {
                ContactPair pair = job.pair;
                pair.triangle = stored[k].triangle, pair.childA = stored[k].childA, pair.childB = stored[k].childB;
                chunk.meshPairs.push_back(pair);
                moveManifold(stored[k].manifold, r.a, r.b, stored[k].radiusA, stored[k].radiusB,
                             chunk.meshManifolds.emplace_back());
            }
            continue;
        }
        const BatchedKernel batched = batchedKernel(job.kernel);
        if (batched != BatchedKernel::Count) {
            scratch.batched[static_cast<int>(batched)].push_back(j);
            continue;
        }
        const ContactPair& p = job.pair;
        const Motion<float> motionA = motionOf(storage, rows_, tables_, p, false);
        const Motion<float> motionB = motionOf(storage, rows_, tables_, p, true);
        const float margin =
            speculativeMargin<float>(params, motionA.v, motionA.w, motionA.reach, motionB.v, motionB.w, motionB.reach);
        const Posed a = posedSide(storage, rows_, shapes, p, false);
        const Posed b = posedSide(storage, rows_, shapes, p, true);
        if (job.triangles == 0) {
            collide(job.kernel, a, b, margin, hullAdjacency_, chunk.manifolds[j]);
            continue;
        }
        mesh.prepare(a, b);
        prefetchTriangles(chunk, j, meshTriangles, mesh);
        job.firstOutput = static_cast<std::uint32_t>(chunk.meshPairs.size());
        collideTriangles(job, meshTriangles.data() + job.firstTriangle, a, mesh, margin, hullAdjacency_, chunk,
                         scratch);
        job.outputCount = static_cast<std::uint32_t>(chunk.meshPairs.size()) - job.firstOutput;
    }
    for (int kernel = 0; kernel < static_cast<int>(BatchedKernel::Count); ++kernel)
        if (!scratch.batched[kernel].empty())
            collideBatched(static_cast<BatchedKernel>(kernel), scratch.batched[kernel], chunk, scratch, storage, rows_,
                           shapes, tables_, params);

    // Counted in locals: the compiler cannot keep the chunk's fields in registers across the loop.
    std::uint32_t touching = static_cast<std::uint32_t>(chunk.meshManifolds.size()), points = 0;
    for (std::size_t j = 0; j < n && chunk.jobs[j].triangles == 0; ++j) {
        const int count = chunk.manifolds[j].pointCount;
        touching += count > 0 ? 1u : 0u;
        points += static_cast<std::uint32_t>(count);
    }
    for (const Manifold& m : chunk.meshManifolds) points += static_cast<std::uint32_t>(m.pointCount);
    chunk.touching = touching;
    chunk.points = points;
    chunk.reused = reused;
}

void NarrowPhaseStage::keepComputed(Chunk& chunk, ManifoldReuse::ChunkCache& cache, const BodyStorage& storage,
                                    const std::vector<Shape>& shapes) {
    auto keep = [&](const Manifold& m, const ContactPair& pair, bool swapped) {
        ManifoldReuse::Stored& s = cache.stored.emplace_back();
        s.manifold = m;
        s.radiusA = roundingOf(sideShape(storage, shapes, pair, false));
        s.radiusB = roundingOf(sideShape(storage, shapes, pair, true));
        s.triangle = pair.triangle, s.childA = pair.childA, s.childB = pair.childB, s.swapped = swapped;
    };
    for (const PendingEntry& p : chunk.pending) {
        ManifoldReuse::Entry& entry = cache.entries[p.entry];
        entry.firstStored = static_cast<std::uint32_t>(cache.stored.size());
        for (std::uint32_t j = p.jobBegin; j < p.jobEnd; ++j) {
            const Job& job = chunk.jobs[j];
            if (job.triangles == 0) {
                if (chunk.manifolds[j].pointCount > 0)
                    keep(chunk.manifolds[j], job.pair, job.pair.aStatic || job.pair.a != p.firstBody);
                continue;
            }
            for (std::uint32_t k = job.firstOutput; k < job.firstOutput + job.outputCount; ++k)
                keep(chunk.meshManifolds[k], chunk.meshPairs[k], false);
        }
        entry.storedCount = static_cast<std::uint32_t>(cache.stored.size()) - entry.firstStored;
    }
}

}  // namespace rubble::detail
