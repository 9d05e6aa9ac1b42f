#pragma once
// Where the narrow phase reads the two sides of a pair: each moving body's pose and motion copied into rows, the
// per-shape tables, and a side posed in the world (the compound child it names, when it names one). The one-pair,
// triangle-run and batched kernels all read their sides through these, so they see the same poses.
#include <cstdint>
#include <vector>

#include "broadphase/broadphase.h"
#include "contacts/contacts.h"
#include "narrowphase/convex_pairs.h"
#include "shapes/shape.h"
#include "storage/body_storage.h"

namespace rubble::detail {

class TaskPool;

/// Floats per row of MovingRows (a row is loaded and transposed whole: simd/transpose.h).
inline constexpr std::size_t kPairRowFloats = 8;

/// Per shape slot, what job building and the batched kernels read (SoA, for SIMD gathers); refreshed every run.
struct ShapeTables {
    std::vector<ShapeKind> kind;
    /// Box: half extents; sphere: (radius, 0, 0); capsule: (radius, half height, 0).
    std::vector<float> sizeX, sizeY, sizeZ;
    std::vector<float> reach;  ///< rotationReach (shapes/shape_extents.h)

    void prepare(const std::vector<Shape>& shapes);
};

/// The size columns of ShapeTables for a shape (see there).
Vec3 sizeOf(const Shape& shape);

/// The pose and motion of each moving body in a candidate pair as two rows of eight floats (indexed by dense index),
/// copied from the SoA storage at the start of every run. A pair reads two cache lines per body instead of one per
/// field, and a SIMD batch of pairs takes each side in two row transposes instead of sixteen gathers. Rows of bodies
/// in no pair are left stale: nothing reads them.
struct MovingRows {
    /// Per body: centre of mass x y z, orientation x y z w, local centre of mass x (the shape origin is the centre of
    /// mass less the rotated local centre).
    AlignedVector<float> pose;
    /// Per body: linear velocity x y z, angular velocity x y z, local centre of mass y z.
    AlignedVector<float> motion;

    /// Writes the rows of the candidates' moving bodies: every row when the pairs' sides number a quarter of the
    /// bodies or more, else only theirs (a million sparse bodies with forty thousand pairs pay for the pairs).
    void write(const MovingBodies& bodies, const CandidatePairs& candidates, TaskPool& pool);

private:
    void writeRows(const MovingBodies& bodies, std::size_t begin, std::size_t end);
    std::vector<std::uint8_t> inPair_;  ///< per moving body, while writing: in a candidate pair (else all zero)
};

/// Columns of MovingRows' pose and motion rows.
enum PoseColumn : std::size_t { kComX, kComY, kComZ, kRotX, kRotY, kRotZ, kRotW, kLocalComX };
enum MotionColumn : std::size_t { kVelX, kVelY, kVelZ, kSpinX, kSpinY, kSpinZ, kLocalComY, kLocalComZ };
static_assert(kLocalComX + 1 == kPairRowFloats && kLocalComZ + 1 == kPairRowFloats, "rows hold eight floats");

/// Body i's row in MovingRows::pose or ::motion.
[[gnu::always_inline]] inline const float* rowOf(const AlignedVector<float>& rows, std::uint32_t i) {
    return rows.data() + std::size_t{i} * kPairRowFloats;
}

/// A shape placed in the world.
struct Posed {
    Transform pose;  ///< of the shape's local origin
    const Shape* shape;
};

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
const Shape& sideShape(const BodyStorage& storage, const std::vector<Shape>& shapes, const ContactPair& p, bool sideB);

/// Centre of a sphere side. A whole moving sphere's centre is its centre of mass, so only its pose row is read, not
/// the motion row that posed() needs for the local centre of mass.
Vec3 sphereCenter(const BodyStorage& storage, const MovingRows& rows, const std::vector<Shape>& shapes,
                  const ContactPair& p, bool sideB);

/// How far a shape's surface lies beyond its core: a sphere's or capsule's radius, 0 for polytopes and triangles.
inline float roundingOf(const Shape& shape) {
    return shape.kind == ShapeKind::Sphere || shape.kind == ShapeKind::Capsule ? shape.radius : 0.0f;
}

inline CapsuleSegment segmentOf(const Posed& p) {
    return capsuleSegmentOf(p.pose, p.shape->halfHeight, p.shape->radius);
}

}  // namespace rubble::detail
