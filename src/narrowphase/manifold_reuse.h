#pragma once
// Manifold reuse (contact recycling): a pair whose bodies have hardly moved relative to each other since its
// manifolds were computed gets those manifolds again instead of running its kernels, as Box3D recycles its contacts
// (within 5 cm of relative motion) and Jolt's body pair cache reuses its (1 mm, 2 degrees). The test is one bound on
// how far any point of the first body's shape has moved relative to the second body, so a long body that turns a
// little is not taken for still, and neither body may have turned more than 2 degrees. The recycled manifolds
// keep their feature ids (the contact cache warm-starts them exactly), their normal and their anchors' offsets from
// the bodies' centres, and each depth follows the relative motion of the bodies at that point along the normal
// (moveManifold), so a resting pair's depth does not freeze while the solver moves its bodies.
//
// The stage keeps, per parallel chunk of candidates, an entry for every candidate whose pair is recycled (all but
// sphere and capsule pairs: pair_kernels.h, recycled()): the bodies' poses and the speculative margin when its
// manifolds were computed, and those manifolds. A reused entry is copied forward unchanged, so the motion is always
// measured from the step that computed it and the manifolds are computed again once it adds up to the tolerance.
#include <cstdint>
#include <vector>

#include "narrowphase/hull_pairs.h"
#include "narrowphase/manifold.h"
#include "rubble/math.h"

namespace rubble::detail {

/// Pose of a body as the stage reads it: centre of mass and orientation of a moving body, origin and orientation of a
/// static one.
struct BodyPose {
    Vec3 position;
    Quat rotation;
};

/// The rigid motion of a body from one pose to another: a point w fixed on the body goes to to + turn (w - from).
/// Written about the body's own point, not the world origin, so that it keeps its precision far from the origin.
struct PoseChange {
    Vec3 from, to;
    Quat turn;
};

inline PoseChange poseChange(const BodyPose& then, const BodyPose& now) {
    return {then.position, now.position, now.rotation * conjugate(then.rotation)};
}
inline Vec3 carry(const PoseChange& c, Vec3 w) { return c.to + rotate(c.turn, w - c.from); }

/// A bound on how far any point within `reachA` of body A's reference point has moved relative to body B, given both
/// bodies' motions: the motion at A's point, plus reachA times the angle between the two turns (2 sin of half of
/// it, from the vector part of their quotient, which keeps its precision at small angles).
inline float relativeDisplacement(const PoseChange& a, const PoseChange& b, float reachA) {
    const Vec3 atPoint = a.to - b.to - rotate(b.turn, a.from - b.from);
    const Quat between = conjugate(b.turn) * a.turn;
    return length(atPoint) + 2.0f * reachA * length(Vec3{between.x, between.y, between.z});
}

/// Neither body may have turned more than 2 degrees (as Jolt's body pair cache allows) since a manifold was computed
/// for it to be recycled: its normal is kept in the world, so a pair that turns together (a box on a tilting
/// platform) must be computed again. The turn's vector part is the sine of half its angle: this is sin(1 degree).
inline constexpr float kRecycleHalfTurnSine = 0.0174524f;

inline bool turnedLittle(const PoseChange& c) {
    return c.turn.x * c.turn.x + c.turn.y * c.turn.y + c.turn.z * c.turn.z <=
           kRecycleHalfTurnSine * kRecycleHalfTurnSine;
}

/// A manifold computed between A and B, recycled as Box3D recycles its contacts: the contact keeps the shape it had
/// when it was computed and only its depths follow the bodies. The normal stays as it was in the world; each anchor
/// keeps its offset from its own body's centre (B's at the point, A's at the point plus shiftA, their centres'
/// relative translation since); each depth is the roundings less the separation along the kept normal of the two
/// sides' cores (a sphere's centre, a capsule's segment, a polytope's surface point) carried with their bodies:
/// exact for a pair that only translates, right to first order otherwise. Everything is formed relative to the
/// bodies' own points, so that bodies far from the origin keep their depths' precision.
///
/// Why the normal and the anchors' offsets are kept: soft contacts sag under load, so a stack leans a little, and a
/// normal that turns with the lower body, or loads that move with the bodies' turn, push a leaning stack sideways
/// and lean it further. S5's wall, one cube deep, tipped out of its plane after about 6 s when every step's contacts
/// followed the bodies; with its contacts kept as they were computed it stands (docs/solver_defaults.md).
inline void moveManifold(const Manifold& then, const PoseChange& a, const PoseChange& b, float radiusA, float radiusB,
                         Manifold& now) {
    const Vec3 n = then.normal;
    now.normal = n;
    now.pointCount = then.pointCount;
    now.shiftA = (a.to - a.from) - (b.to - b.from);
    const Vec3 between = a.to - b.to;
    for (int i = 0; i < then.pointCount; ++i) {
        const ContactPoint& p = then.points[i];
        // B lies along +n from the point; A's surface point is `depth` further on, its core `radiusA` back.
        const Vec3 coreA = (p.position - a.from) + n * (p.depth - radiusA);
        const Vec3 coreB = rotate(b.turn, (p.position - b.from) + n * radiusB);
        now.points[i].position = b.to + (p.position - b.from);
        now.points[i].depth = dot(between + rotate(a.turn, coreA) - coreB, n) + radiusA + radiusB;
        now.points[i].feature = p.feature;
    }
}

/// What the stage keeps from one step to the next, per chunk of candidates (see the file comment).
class ManifoldReuse {
public:
    /// A manifold as computed, with what its ContactPair held besides the bodies.
    struct Stored {
        Manifold manifold;
        float radiusA = 0, radiusB = 0;  ///< roundings of the two shapes (see moveManifold)
        std::uint32_t triangle = ~0u;
        std::uint16_t childA = 0, childB = 0;
        bool swapped = false;  ///< A is the candidate's second body
    };
    /// One candidate pair: the bodies and shapes it was computed for, their poses and the margin then, its manifolds.
    struct Entry {
        std::uint64_t order = 0;  ///< the candidates' canonical order (see orderOf)
        std::uint64_t slots = 0, generations = 0;
        std::uint32_t shapeFirst = 0, shapeSecond = 0;
        BodyPose first, second;
        float margin = 0;
        std::uint32_t firstStored = 0, storedCount = 0;  ///< in its chunk's `stored`
        /// A pair of two whole polytopes (one job): the SAT's last deciding axis, given to its next computation.
        SatHint hint;
    };
    struct ChunkCache {
        std::vector<Entry> entries;  ///< ascending `order`
        std::vector<Stored> stored;
    };
    /// Key of a candidate in canonical order: moving pairs by dense indices, then moving-static pairs and meshes by
    /// moving dense index and static slot (CandidatePairs' orders). Dense indices change when bodies are removed; an
    /// entry found by order is used only if its slots and generations match as well.
    enum class Section : std::uint64_t { Moving, Static, Mesh };
    static std::uint64_t orderOf(Section section, std::uint32_t first, std::uint32_t second) {
        return (static_cast<std::uint64_t>(section) << 62) | (std::uint64_t{first & 0x3FFFFFFFu} << 32) | second;
    }

    /// Walks last step's entries in ascending order for one chunk; starts with a binary search.
    class Finder {
    public:
        struct Found {
            const Entry* entry = nullptr;
            const Stored* stored = nullptr;  ///< the entry's first manifold
        };
        explicit Finder(const ManifoldReuse& reuse) : reuse_(&reuse) {}
        /// Last step's entry of the candidate with this order, if any; orders must be asked in ascending order.
        Found find(std::uint64_t order);

    private:
        const ManifoldReuse* reuse_;
        std::size_t chunk_ = 0, index_ = 0;
        bool started_ = false;
    };

    /// Starts a step whose candidates fill `chunkCount` chunks: this step's caches are emptied. `layoutChanges`:
    /// BodyStorage::layoutChanges now.
    void begin(std::size_t chunkCount, std::uint64_t layoutChanges);
    ChunkCache& current(std::size_t chunk) { return current_[chunk]; }
    /// Whether last step's entries were made with the bodies at the same dense indices as now: an entry found by
    /// its order then names the same bodies, and their slots and generations need not be compared.
    bool sameBodies() const { return sameBodies_; }
    /// Ends the step: this step's entries become the ones the next step finds.
    void finish();
    /// Forgets everything (reuse switched off).
    void clear();

private:
    std::vector<ChunkCache> previous_, current_;
    std::size_t currentCount_ = 0;
    std::uint64_t previousLayout_ = 0, currentLayout_ = 0;
    bool havePrevious_ = false, sameBodies_ = false;
    /// Per chunk of previous_: the largest order in it or any chunk before it (0 if none), for the binary search.
    std::vector<std::uint64_t> previousLast_;
};

}  // namespace rubble::detail
