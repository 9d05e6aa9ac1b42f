#pragma once
// Static BVH: the moving-vs-static half of the broad phase. Static bodies and every triangle of static meshes and
// heightfields are primitives of one bounding volume hierarchy, built once with a binned surface area heuristic;
// each step the fattened boxes of the moving bodies are queried against it in parallel. Static-static pairs are
// never formed. The same tree will serve ray casts, so its nodes are four-wide with their children's boxes stored
// as SoA lanes: one node visit tests four boxes, for a query box and for a ray slab test alike.
//
// Edits between steps (bodies added or removed) never rebuild the main tree from scratch:
//  - remove() tombstones the body's primitives in place: their boxes become empty (min = +inf, max = -inf), so
//    queries skip them without a check of their own; node bounds stay conservative.
//  - insert() appends to a small secondary tree, rebuilt on the next commit() (O(k log k) for its k primitives).
//  - commit() merges everything into a fresh main tree only when the secondary set exceeds 1/8 of the live main
//    primitives, or tombstones exceed 1/4 of the main tree: a full build is paid once per n/8 inserted or n/4
//    removed primitives, and the main tree's quality never drifts far from a fresh build's.
// Results never depend on which tree holds a primitive: every query sorts its hits.
//
// Queries are coherent across steps: a moving box is looked up grown by an eighth of its size, and the hits of the
// grown box are kept with their boxes. While the body's box stays inside the grown one and the tree is unchanged,
// its hits are those kept hits that overlap it: exactly the tree walk's answer (a primitive is reported when its
// own box overlaps, and every ancestor's box holds its box), found without the walk's cache misses. Resting piles
// walk the tree almost never.
// A heightfield's primitives are its triangles, numbered as src/shapes/shape.h says (heightfieldTriangle).
#include <array>
#include <bit>
#include <cstdint>
#include <span>
#include <vector>

#include "broadphase/broadphase.h"
#include "rubble/math.h"
#include "shapes/shape.h"
#include "storage/aligned_vector.h"

namespace rubble::detail {

class TaskPool;

/// Triangle index of a primitive that stands for a whole body (any shape but a mesh or heightfield).
inline constexpr std::uint32_t kWholeBody = ~0u;

/// One primitive of the static BVH: a world box, the caller's stable id of its body (the world passes the static
/// body's slot) and the triangle of a mesh or heightfield, or kWholeBody.
struct StaticPrimitive {
    Aabb box;
    std::uint32_t body = 0;
    std::uint32_t triangle = kWholeBody;
};

/// Which moving-vs-static pairs a query reports. A static body counts as asleep, so asleep moving bodies are not
/// queried at all. Categories: the pair is kept when (movingCategory & staticMask) and (staticCategory &
/// movingMask) are both non-zero; a null array means all bits set.
struct StaticQueryFilter {
    PairFilter moving;                              ///< moving bodies' category, mask and sleep flags (dense order)
    const std::uint32_t* staticCategory = nullptr;  ///< indexed by primitive body id
    const std::uint32_t* staticMask = nullptr;      ///< indexed by primitive body id
};

/// Shape of the main tree, for tests and the profiler.
struct StaticBvhStats {
    std::uint32_t nodes = 0;
    std::uint32_t depth = 0;       ///< node levels on the longest root-to-leaf path
    std::uint32_t primitives = 0;  ///< main tree, tombstones included
    std::uint32_t tombstones = 0;
    std::uint32_t pending = 0;  ///< primitives in the secondary tree
    /// Expected cost of a random small query under the surface area heuristic: the root, plus the area of every
    /// other node and of every primitive (a primitive lane that passes costs a report, as a node costs a visit),
    /// each relative to the root's area.
    double sahCost = 0;
};

class StaticBvh {
public:
    static constexpr std::uint32_t kQueryChunk = 256;  ///< moving bodies per parallel task (fixed: determinism)
    /// child() of a lane that holds a primitive: the bit is set and the rest is its index in primitives().
    static constexpr std::uint32_t kPrimitiveBit = 1u << 31;
    /// child() of an unused lane (its box is empty: min = +inf, max = -inf, so no box or ray hits it).
    static constexpr std::uint32_t kUnusedLane = ~0u;

    /// A four-wide node, two cache lines. Lane k of each row is child k: lo = (minX[4], minY[4], minZ[4], child[4]),
    /// hi = (maxX[4], maxY[4], maxZ[4], unused[4]). One 16-float row is one AVX-512 register (two AVX, four SSE),
    /// so a node visit tests all four children with two compares. A child is another node or a single primitive:
    /// the nodes just above the primitives are the leaves, holding up to four primitive boxes in SoA form, and a
    /// primitive's box lives only there. Child indices sit in the fourth quarter of lo (bit patterns, read with
    /// child()), which the overlap test ignores.
    struct alignas(64) Node {
        float lo[16];
        float hi[16];

        std::uint32_t child(int k) const { return std::bit_cast<std::uint32_t>(lo[12 + k]); }
        void setChild(int k, std::uint32_t c) { lo[12 + k] = std::bit_cast<float>(c); }
        Aabb box(int k) const { return {{lo[k], lo[4 + k], lo[8 + k]}, {hi[k], hi[4 + k], hi[8 + k]}}; }
        void setBox(int k, const Aabb& b);
    };
    /// What a primitive lane refers to.
    struct PrimitiveRef {
        std::uint32_t body, triangle;
    };
    struct Tree {
        AlignedVector<Node> nodes;
        std::vector<PrimitiveRef> primitives;  ///< in leaf order
        std::uint32_t depth = 0;               ///< node levels on the longest root-to-leaf path
    };

    /// Replaces the whole content with `primitives`. Deterministic: the tree depends only on the input order and
    /// values, never on the thread count (large inputs build independent subtrees in parallel).
    void build(std::vector<StaticPrimitive> primitives, TaskPool& pool);
    /// Adds primitives between steps (all triangles of a new static mesh, or one box); takes effect at commit().
    void insert(std::span<const StaticPrimitive> primitives);
    /// Removes every primitive of `body` (no effect if it has none); takes effect at once.
    void remove(std::uint32_t body);
    /// Rebuilds the secondary tree after inserts, and merges into the main tree when the edit policy asks for it.
    /// query() calls it; call it yourself before read-only use from several threads.
    void commit(TaskPool& pool);

    /// Every (moving body, static primitive) pair whose boxes overlap (closed intervals, as overlaps()), filtered.
    /// Whole bodies go to bodyPairs as {moving dense index, body id}; triangles are grouped into one MeshPair per
    /// (moving, body) with its triangles ascending in meshTriangles. All three outputs are overwritten, ordered by
    /// moving index, then body id, then triangle, and identical for any thread count.
    void query(const Bounds& moving, const StaticQueryFilter& filter, TaskPool& pool, std::vector<BodyPair>& bodyPairs,
               std::vector<MeshPair>& meshPairs, std::vector<std::uint32_t>& meshTriangles);

    /// Live primitives (main and secondary, without tombstones, including inserts not yet committed).
    std::uint32_t primitiveCount() const;
    bool empty() const { return primitiveCount() == 0; }
    StaticBvhStats stats() const;
    /// The main tree, for ray casts and tests; node 0 is the root (no nodes when empty). Call commit() first.
    const Tree& mainTree() const { return main_; }
    /// The tree of primitives inserted since the last merge (see commit()); queries must walk it too.
    const Tree& secondaryTree() const { return secondary_; }

private:
    /// A primitive that a grown query box overlaps, with the primitive's box.
    struct KeptHit {
        std::uint64_t key;  ///< (body << 32) | triangle
        float lo[3], hi[3];
    };
    /// One query chunk's output, merged in chunk order, and its kept hits; kept across steps so a step allocates
    /// nothing.
    struct ChunkOutput {
        std::vector<BodyPair> bodyPairs;
        std::vector<MeshPair> meshPairs;  ///< firstTriangle relative to this chunk's triangles
        std::vector<std::uint32_t> triangles;
        /// The tree content and chunk range the kept hits were found for; anything else makes them stale.
        std::uint64_t keptGeneration = 0;
        std::uint32_t keptBegin = 0, keptEnd = 0;
        std::vector<Aabb> grown;               ///< per body of the chunk: the box its hits were found for
        std::vector<std::uint32_t> keptStart;  ///< per body of the chunk + 1: its range of kept, by key
        std::vector<KeptHit> kept, keptNext;   ///< this step's list is built in keptNext, then swapped
    };
    struct WorkerScratch {
        std::vector<std::uint64_t> hits;  ///< (body << 32) | triangle of one moving box
        std::vector<std::uint32_t> stack;
    };

    void rebuildMain(TaskPool& pool);

    Tree main_;
    Tree secondary_;                        ///< built from pending_ at commit()
    std::vector<StaticPrimitive> pending_;  ///< inserted since the last merge, in insertion order
    /// (body << 32) | (node * 4 + lane) of every primitive lane of main_, sorted; built on the first remove() after
    /// a build, so that building pays nothing for it.
    std::vector<std::uint64_t> mainByBody_;
    bool mainByBodyValid_ = false;
    std::uint32_t tombstones_ = 0;
    bool secondaryDirty_ = false;
    std::uint64_t generation_ = 1;  ///< changes with every edit: kept query hits of another generation are stale
    std::vector<ChunkOutput> chunks_;
    std::vector<WorkerScratch> workers_;
};

/// Appends the primitives of a static body: one per triangle (world boxes of the posed vertices) for meshes and
/// heightfields, one world box (kWholeBody) for any other shape. `pose` takes the shape frame to the world.
void appendStaticPrimitives(const Shape& shape, const Transform& pose, std::uint32_t body,
                            std::vector<StaticPrimitive>& out);

}  // namespace rubble::detail
