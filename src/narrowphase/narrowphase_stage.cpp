#include "narrowphase/narrowphase_stage.h"

#include <algorithm>

#include "broadphase/static_bvh.h"
#include "narrowphase/box_box.h"
#include "narrowphase/convex_pairs.h"
#include "narrowphase/hull_pairs.h"
#include "narrowphase/triangle_pairs.h"
#include "parallel.h"
#include "shapes/mesh_adjacency.h"

namespace rubble::detail {
namespace {

/// Pairs per parallel task: enough work to amortise a task, small enough for two threads to balance.
constexpr std::size_t kChunk = 256;

struct Posed {
    Transform pose;  ///< of the shape's local origin
    const Shape* shape;
};

Posed posed(const BodyStorage& storage, const std::vector<Shape>& shapes, std::uint32_t i, bool isStatic) {
    if (isStatic) {
        const StaticBodies& s = storage.statics;
        return {{{s.px[i], s.py[i], s.pz[i]}, {s.qx[i], s.qy[i], s.qz[i], s.qw[i]}}, &shapes[s.shape[i]]};
    }
    const MovingBodies& m = storage.moving;
    const Quat q{m.qx[i], m.qy[i], m.qz[i], m.qw[i]};
    const Vec3 origin = Vec3{m.px[i], m.py[i], m.pz[i]} - rotate(q, {m.lcx[i], m.lcy[i], m.lcz[i]});
    return {{origin, q}, &shapes[m.shape[i]]};
}

const Shape& shapeOf(const BodyStorage& storage, const std::vector<Shape>& shapes, std::uint32_t i, bool isStatic) {
    return shapes[isStatic ? storage.statics.shape[i] : storage.moving.shape[i]];
}

/// A side of a contact pair: the body's shape, or the compound child the pair names, posed in the world.
Posed posedSide(const BodyStorage& storage, const std::vector<Shape>& shapes, const ContactPair& p, bool sideB) {
    Posed body = sideB ? posed(storage, shapes, p.b, p.bStatic) : posed(storage, shapes, p.a, p.aStatic);
    const std::uint16_t child = sideB ? p.childB : p.childA;
    if (child == kNoChild) return body;
    const CompoundChild& c = body.shape->children[child];
    return {{apply(body.pose, c.local.position), body.pose.rotation * c.local.rotation}, c.shape.get()};
}

CapsuleSegment segmentOf(const Posed& p) { return capsuleSegmentOf(p.pose, p.shape->halfHeight, p.shape->radius); }

/// World vertices and active-edge mask of triangle t of a static mesh or heightfield.
void triangleOf(const Posed& mesh, std::uint32_t t, TriangleVertices& vertices, std::uint8_t& activeEdges) {
    if (mesh.shape->kind == ShapeKind::TriangleMesh) {
        const TriangleMesh& m = *mesh.shape->mesh;
        for (int k = 0; k < 3; ++k) vertices[k] = apply(mesh.pose, m.vertices[m.indices[3 * std::size_t(t) + k]]);
        activeEdges = m.activeEdges.empty() ? kAllEdgesActive : m.activeEdges[t];
    } else {
        const std::array<Vec3, 3> local = heightfieldTriangle(*mesh.shape->heightfield, t);
        for (int k = 0; k < 3; ++k) vertices[k] = apply(mesh.pose, local[k]);
        activeEdges = heightfieldActiveEdges(*mesh.shape->heightfield, t);
    }
}

/// Centre of a sphere side. A whole moving sphere's centre is its centre of mass, so only the position rows are
/// read: the common case (S4) then touches 3 arrays per side instead of every pose array.
Vec3 sphereCenter(const BodyStorage& storage, const std::vector<Shape>& shapes, const ContactPair& p, bool sideB) {
    const std::uint32_t i = sideB ? p.b : p.a;
    if (!(sideB ? p.bStatic : p.aStatic) && (sideB ? p.childB : p.childA) == kNoChild)
        return {storage.moving.px[i], storage.moving.py[i], storage.moving.pz[i]};
    return posedSide(storage, shapes, p, sideB).pose.position;
}

float sphereRadius(const BodyStorage& storage, const std::vector<Shape>& shapes, const ContactPair& p, bool sideB) {
    const std::uint32_t i = sideB ? p.b : p.a;
    const bool isStatic = sideB ? p.bStatic : p.aStatic;
    const std::uint16_t child = sideB ? p.childB : p.childA;
    const Shape& shape = shapeOf(storage, shapes, i, isStatic);
    return child == kNoChild ? shape.radius : shape.children[child].shape->radius;
}

/// The capsule-box kernel sees the capsule as A; the stage's order has the box first. Same contact seen from the
/// other body: the normal turns round and the points move across the overlap onto the capsule.
void collideBoxCapsule(const Posed& box, const Posed& capsule, float margin, Manifold& out) {
    collideCapsuleBox(segmentOf(capsule), box.pose, box.shape->halfExtents, margin, out);
    for (int p = 0; p < out.pointCount; ++p) out.points[p].position += out.normal * out.points[p].depth;
    out.normal = -out.normal;
}

/// One pair through its scalar kernel; for triangle kernels B is the mesh and `triangle` picks the triangle.
template <class HullMap>
void collide(PairKernel kernel, const Posed& a, const Posed& b, std::uint32_t triangle, float margin,
             const HullMap& hulls, Manifold& out) {
    auto adjacency = [&](const Posed& p) -> const HullAdjacency& { return *hulls.at(p.shape->hull.get()).adjacency; };
    out.pointCount = 0;
    TriangleVertices tri;
    std::uint8_t active = 0;
    if (kernel == PairKernel::SphereTriangle || kernel == PairKernel::CapsuleTriangle ||
        kernel == PairKernel::BoxTriangle)
        triangleOf(b, triangle, tri, active);
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
            collideSphereTriangle(a.pose.position, a.shape->radius, tri, active, margin, out);
            break;
        case PairKernel::CapsuleTriangle:
            collideCapsuleTriangle(segmentOf(a), tri, active, margin, out);
            break;
        case PairKernel::BoxTriangle:
            collideBoxTriangle(a.pose, a.shape->halfExtents, tri, active, margin, out);
            break;
        case PairKernel::Unsupported:
        case PairKernel::Count:
            break;
    }
}

}  // namespace

NarrowPhaseStage::NarrowPhaseStage() = default;
NarrowPhaseStage::~NarrowPhaseStage() = default;

PairKernel pairKernel(ShapeKind lower, ShapeKind upper) {
    using K = ShapeKind;
    if (lower == K::Sphere) {
        if (upper == K::Sphere) return PairKernel::SphereSphere;
        if (upper == K::Box) return PairKernel::SphereBox;
        if (upper == K::Capsule) return PairKernel::SphereCapsule;
    }
    if (lower == K::Sphere && upper == K::ConvexHull) return PairKernel::SphereHull;
    if (lower == K::Box && upper == K::Box) return PairKernel::BoxBox;
    if (lower == K::Box && upper == K::Capsule) return PairKernel::BoxCapsule;
    if (lower == K::Box && upper == K::ConvexHull) return PairKernel::BoxHull;
    if (lower == K::Capsule && upper == K::Capsule) return PairKernel::CapsuleCapsule;
    if (lower == K::Capsule && upper == K::ConvexHull) return PairKernel::CapsuleHull;
    if (lower == K::ConvexHull && upper == K::ConvexHull) return PairKernel::HullHull;
    if (upper == K::TriangleMesh || upper == K::Heightfield) {
        if (lower == K::Sphere) return PairKernel::SphereTriangle;
        if (lower == K::Capsule) return PairKernel::CapsuleTriangle;
        if (lower == K::Box) return PairKernel::BoxTriangle;
    }
    return PairKernel::Unsupported;
}

void NarrowPhaseStage::run(const CandidatePairs& candidates, const BodyStorage& storage,
                           const std::vector<Shape>& shapes, float margin, TaskPool& pool, Contacts& out) {
    out.clear();
    // Jobs in the candidates' canonical order: moving pairs, then moving-static pairs. A is the body whose shape
    // kind is lower, so each kernel sees its shapes in its own argument order.
    jobs_.clear();
    // Compounds expand into one job per child (per child pair for two compounds), in child order.
    auto addJob = [&](std::uint32_t first, bool firstStatic, std::uint32_t second, bool secondStatic,
                      std::uint32_t triangle) {
        const Shape& s1 = shapeOf(storage, shapes, first, firstStatic);
        const Shape& s2 = shapeOf(storage, shapes, second, secondStatic);
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
                jobs_.push_back(job);
            }
    };
    for (const BodyPair& p : candidates.moving) addJob(p.a, false, p.b, false, ~0u);
    for (const BodyPair& p : candidates.statics) addJob(p.a, false, p.b, true, ~0u);
    // A body against a mesh: one job per triangle the broad phase handed over (the mesh is always B).
    for (const MeshPair& p : candidates.meshes)
        for (std::uint32_t k = 0; k < p.triangleCount; ++k)
            addJob(p.moving, false, p.staticBody, true, candidates.meshTriangles[p.firstTriangle + k]);

    // Hull adjacency for every hull a job will meet, built here so the parallel part only reads the map.
    for (const Job& job : jobs_) {
        const PairKernel k = job.kernel;
        if (k != PairKernel::SphereHull && k != PairKernel::BoxHull && k != PairKernel::CapsuleHull &&
            k != PairKernel::HullHull)
            continue;
        for (bool sideB : {false, true}) {
            const Posed p = posedSide(storage, shapes, job.pair, sideB);
            if (p.shape->kind != ShapeKind::ConvexHull) continue;
            HullEntry& entry = hullAdjacency_[p.shape->hull.get()];
            if (!entry.adjacency) {
                entry.hull = p.shape->hull;
                entry.adjacency = std::make_unique<HullAdjacency>(buildHullAdjacency(*p.shape->hull));
            }
        }
    }
    for (auto& bucket : bucket_) bucket.clear();
    for (std::uint32_t j = 0; j < jobs_.size(); ++j) bucket_[static_cast<int>(jobs_[j].kernel)].push_back(j);
    out.unsupportedPairs = static_cast<std::uint32_t>(bucket_[static_cast<int>(PairKernel::Unsupported)].size());
    perJob_.resize(jobs_.size());

    // Sphere-sphere: gathered into SoA and run in SIMD lanes.
    const std::vector<std::uint32_t>& spheres = bucket_[static_cast<int>(PairKernel::SphereSphere)];
    if (!spheres.empty()) {
        const std::size_t n = spheres.size();
        for (auto& a : sphereIn_) a.resize(n);
        for (auto& a : sphereOut_) a.resize(n);
        sphereFeature_.resize(n);
        sphereCount_.resize(n);
        pool.forChunks(n, kChunk * 4, [&](std::size_t, std::size_t begin, std::size_t end, int) {
            for (std::size_t k = begin; k < end; ++k) {
                const ContactPair& p = jobs_[spheres[k]].pair;
                const Vec3 a = sphereCenter(storage, shapes, p, false), b = sphereCenter(storage, shapes, p, true);
                sphereIn_[0][k] = a.x, sphereIn_[1][k] = a.y, sphereIn_[2][k] = a.z;
                sphereIn_[3][k] = sphereRadius(storage, shapes, p, false);
                sphereIn_[4][k] = b.x, sphereIn_[5][k] = b.y, sphereIn_[6][k] = b.z;
                sphereIn_[7][k] = sphereRadius(storage, shapes, p, true);
            }
            const SpherePairs in{sphereIn_[0].data() + begin, sphereIn_[1].data() + begin, sphereIn_[2].data() + begin,
                                 sphereIn_[3].data() + begin, sphereIn_[4].data() + begin, sphereIn_[5].data() + begin,
                                 sphereIn_[6].data() + begin, sphereIn_[7].data() + begin};
            PairContacts result{
                sphereOut_[0].data() + begin, sphereOut_[1].data() + begin,  sphereOut_[2].data() + begin,
                sphereOut_[3].data() + begin, sphereOut_[4].data() + begin,  sphereOut_[5].data() + begin,
                sphereOut_[6].data() + begin, sphereFeature_.data() + begin, sphereCount_.data() + begin};
            collideSpheresBatch(in, end - begin, margin, result);
            for (std::size_t k = begin; k < end; ++k) {
                Manifold& m = perJob_[spheres[k]];
                m.pointCount = sphereCount_[k];
                m.normal = {sphereOut_[0][k], sphereOut_[1][k], sphereOut_[2][k]};
                m.points[0] = {
                    {sphereOut_[3][k], sphereOut_[4][k], sphereOut_[5][k]}, sphereOut_[6][k], sphereFeature_[k]};
            }
        });
    }

    // Every other kernel: one pair at a time, in parallel chunks of its bucket.
    for (int kernel = 0; kernel < static_cast<int>(PairKernel::Unsupported); ++kernel) {
        if (kernel == static_cast<int>(PairKernel::SphereSphere)) continue;
        const std::vector<std::uint32_t>& bucket = bucket_[kernel];
        pool.forChunks(bucket.size(), kChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
            for (std::size_t k = begin; k < end; ++k) {
                const Job& job = jobs_[bucket[k]];
                collide(job.kernel, posedSide(storage, shapes, job.pair, false),
                        posedSide(storage, shapes, job.pair, true), job.pair.triangle, margin, hullAdjacency_,
                        perJob_[bucket[k]]);
            }
        });
    }
    for (std::uint32_t j : bucket_[static_cast<int>(PairKernel::Unsupported)]) perJob_[j].pointCount = 0;

    // Compact in job order: the output does not depend on buckets, chunks or threads.
    for (std::uint32_t j = 0; j < jobs_.size(); ++j) {
        if (perJob_[j].pointCount == 0) continue;
        out.pairs.push_back(jobs_[j].pair);
        out.manifolds.push_back(perJob_[j]);
        out.pointCount += static_cast<std::uint32_t>(perJob_[j].pointCount);
    }
}

}  // namespace rubble::detail
