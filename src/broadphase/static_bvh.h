#pragma once
// Static BVH: the moving-vs-static half of the broad phase. Static bodies and every triangle of static meshes and
// heightfields are primitives of bounding volume hierarchies built with a binned surface area heuristic;
// each step the fattened boxes of the moving bodies are queried against it in parallel. Static-static pairs are
// never formed. The same tree will serve ray casts, so its nodes are four-wide with their children's boxes stored
// as SoA lanes: one node visit tests four boxes, for a query box and for a ray slab test alike.
//
// The tree is a forest of parts, so that no step ever pays for a large build (a million statics added at load, or
// thousands edited between steps, would otherwise stall the step that first needs them):
//  - insert() gathers primitives and builds them into a new part as soon as kBatchPrimitives are waiting: a world
//    that adds a million statics pays for their tree while it adds them (about one build per primitive), and the
//    next step builds at most the last batch, with the quick build (Morton order) when it is small.
//  - remove() tombstones the body's primitives in place: their boxes become empty (min = +inf, max = -inf), so
//    queries skip them without a check of their own; node bounds stay conservative.
//  - Parts are merged off the step, on background threads under the idle scheduling policy (and only between steps
//    when a step takes every core: StepGate): parts of similar size (a tier: sizes within a factor kMergeFanIn) are
//    merged kMergeFanIn at a time into one of the next tier, widest first (a batch of edits scattered over the world
//    is walked by every query), and a part with more than a quarter of its lanes tombstoned, or a quick part once
//    edits pause, is rebuilt alone. A merge reads only the parts' immutable primitive lists; the parts stay in use
//    until the next commit() after it finished swaps its result in (removals made meanwhile go to the merge's log: the
//    merge applies them to its result once its tree is built, the commit only those made after that). So the forest
//    holds O(kMergeFanIn log n) parts, every primitive is rebuilt O(log n) times in the background, and a step never
//    waits for a merge.
// Results never depend on which part holds a primitive (every query sorts its hits), so when a merge lands, which
// depends on the machine's timing, never changes a result; merges do not change the content, so they keep the
// queries' kept hits valid.
// Queries are coherent across steps: a moving box is looked up grown by an eighth of its size, and the hits of the
// grown box are kept with their boxes. While the body's box stays inside the grown one and no edit (a primitive
// inserted or removed) overlaps the grown box, its hits are those kept hits that overlap it: exactly the walk's
// answer (a primitive is reported when its own box overlaps, and every ancestor's box holds its box), found without
// the walk's cache misses. Resting piles walk the tree almost never, even while statics are edited elsewhere.
// A heightfield's primitives are its triangles, numbered as src/shapes/shape.h says (heightfieldTriangle).
#include <array>
#include <bit>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
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

/// Shape of the forest, for tests and the profiler.
struct StaticBvhStats {
    std::uint32_t parts = 0;
    std::uint32_t merging = 0;     ///< parts that a background merge is reading
    std::uint32_t nodes = 0;       ///< of all parts
    std::uint32_t depth = 0;       ///< node levels on the longest root-to-leaf path of any part
    std::uint32_t primitives = 0;  ///< of all parts, tombstones included
    std::uint32_t tombstones = 0;
    std::uint32_t pending = 0;  ///< inserted primitives not yet in a part
    /// Of the largest part: the expected cost of a random small query under the surface area heuristic: the root,
    /// plus the area of every other node and of every primitive (a primitive lane that passes costs a report, as a
    /// node costs a visit), each relative to the root's area.
    double sahCost = 0;
};

class StaticBvh {
public:
    static constexpr std::uint32_t kQueryChunk = 256;  ///< moving bodies per parallel task (fixed: determinism)
    /// Inserted primitives wait until there are this many, then become a part. The step builds the rest: at most
    /// this many, some 0.3 ms.
    static constexpr std::uint32_t kBatchPrimitives = 1024;
    /// Parts merged at a time, and the size ratio between tiers.
    static constexpr std::uint32_t kMergeFanIn = 8;
    /// A commit builds at most this many waiting primitives with the quick build (Morton order, no SAH): a step
    /// that builds the statics added since the last one pays a tenth of the SAH's time. Merges rebuild them with the
    /// SAH, and a quick part left alone is rebuilt once kQuietCommits commits in a row had nothing to build. The
    /// full batches insert() builds are the caller's time, and are built with the SAH.
    static constexpr std::uint32_t kQuickBuildMax = 4 * kBatchPrimitives;
    static constexpr std::uint32_t kQuietCommits = kMergeFanIn;
    /// Edits between two queries tracked one by one (see query()); more make every moving body walk the forest.
    static constexpr std::uint32_t kEditsTracked = 1u << 13;
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
    /// One part of the forest: a tree and what its edits and merges need, and a merge in flight (both defined in
    /// static_bvh.cpp).
    struct Part;
    struct Merge;
    /// What a primitive lane refers to.
    struct PrimitiveRef {
        std::uint32_t body, triangle;
    };
    struct Tree {
        AlignedVector<Node> nodes;
        std::vector<PrimitiveRef> primitives;  ///< in leaf order
        std::uint32_t depth = 0;               ///< node levels on the longest root-to-leaf path
    };

    StaticBvh();
    ~StaticBvh();  ///< cancels the merges in flight and joins their workers
    StaticBvh(const StaticBvh&) = delete;
    StaticBvh& operator=(const StaticBvh&) = delete;

    /// How a tree is built. Sah: the binned surface area heuristic, for trees that live long. Quick: halves of the
    /// Morton order of the centroids, some ten times faster (0.04 against 0.4 ms for a thousand scattered boxes) and
    /// visited more by queries, for a step's own batch of new statics that a background merge soon rebuilds.
    enum class BuildQuality : std::uint8_t { Sah, Quick };

    /// Builds `tree` over `primitives` (four-wide). Deterministic: the tree depends only on the input order and
    /// values, never on the thread count; large inputs build independent subtrees in parallel on `pool`, and a null
    /// pool builds on the calling thread.
    static void buildTree(Tree& tree, std::span<const StaticPrimitive> primitives, TaskPool* pool,
                          BuildQuality quality = BuildQuality::Sah);

    /// Replaces the whole content with `primitives`, as one part built now (merges in flight are dropped).
    void build(std::vector<StaticPrimitive> primitives, TaskPool& pool);
    /// Adds primitives (all triangles of a new static mesh, or one box). Queries see them after the next commit();
    /// each full batch is built into a part at once, on `pool` when it is large, by `quality` (Quick for a caller
    /// that inserts inside a step: the merges rebuild it with the SAH later).
    void insert(std::span<const StaticPrimitive> primitives, TaskPool& pool, BuildQuality quality = BuildQuality::Sah);
    /// Removes every primitive of `body` (no effect if it has none); takes effect at once.
    void remove(std::uint32_t body);
    /// Builds the waiting primitives into a part, swaps in the merges that finished and starts the merges due.
    /// query() calls it; call it yourself before read-only use from several threads.
    void commit(TaskPool& pool);
    /// Builds the waiting primitives and does every merge due (and the merges they make due) on this thread: the
    /// forest a quiet world would settle into. For tests and benchmarks; the engine never waits for a merge.
    void settle(TaskPool& pool);

    /// Every (moving body, static primitive) pair whose boxes overlap (closed intervals, as overlaps()), filtered.
    /// Whole bodies go to bodyPairs as {moving dense index, body id}; triangles are grouped into one MeshPair per
    /// (moving, body) with its triangles ascending in meshTriangles. All three outputs are overwritten, ordered by
    /// moving index, then body id, then triangle, and identical for any thread count.
    void query(const Bounds& moving, const StaticQueryFilter& filter, TaskPool& pool, std::vector<BodyPair>& bodyPairs,
               std::vector<MeshPair>& meshPairs, std::vector<std::uint32_t>& meshTriangles);

    /// Background merges wait while a step runs (see MergeControl in static_bvh.cpp); the world holds the gate
    /// shut for the length of each step that takes every core.
    struct StepGate {
        mutable std::mutex mutex;
        mutable std::condition_variable open;
        bool stepping = false;
        void set(bool steppingNow);
    };
    void stepBegins() { gate_->set(true); }
    void stepEnds() { gate_->set(false); }

    /// Static candidates the last query dropped past the budget (limits::kStaticHitsPerBody); 0 in any sane scene.
    std::uint64_t droppedHits() const { return droppedHits_; }

    /// Live primitives (tombstones left out, inserts not yet in a part counted).
    std::uint32_t primitiveCount() const;
    bool empty() const { return primitiveCount() == 0; }
    StaticBvhStats stats() const;
    /// The tree of every part, for ray casts, sweeps and tests; node 0 of each is its root. Call commit() first;
    /// valid until the next non-const call.
    std::span<const Tree* const> trees() const { return treeViews_; }
    /// The largest absolute coordinate of any primitive inserted since the last build(), for the queries' padding
    /// (src/query/tree_queries.h). It never shrinks, so it does not depend on when merges land.
    float scale() const { return scale_; }

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
        std::uint64_t keptDropped = 0;         ///< hits the kept lists lack for the budget
    };
    struct WorkerScratch {
        std::vector<std::uint64_t> hits;  ///< (body << 32) | triangle of one moving box
        std::vector<std::uint32_t> stack;
        std::vector<Aabb> edits;  ///< the edits near one chunk
    };

    class BackgroundWorker;

    BackgroundWorker& workerFor(std::uint32_t tier);
    /// Marks the bodies of newly waiting primitives as pending and grows the scale.
    void notePending(std::span<const StaticPrimitive> primitives);
    void noteEdit(const Aabb& box);
    void flushPending(TaskPool* pool, BuildQuality quality);
    /// commit() with the waiting primitives built by `quality`.
    void commitBuilding(TaskPool& pool, BuildQuality quality);
    void addPart(std::unique_ptr<Part> part);
    Part* findPart(std::uint32_t id);
    void landFinishedMerges();
    /// Starts the merges due (one per tier at a time), on the background workers or, for settle(), here. When the
    /// edits have paused (`quiet`), a quick part is due for a rebuild of its own.
    std::size_t startDueMerges(bool background, bool quiet);
    void startMerge(std::vector<Part*> sources, std::uint32_t tier, bool background);
    void dropMerges();
    void refreshTreeViews();

    std::vector<std::unique_ptr<Part>> parts_;
    std::vector<std::unique_ptr<Merge>> merges_;
    std::shared_ptr<StepGate> gate_;                               ///< shared with the jobs in flight
    std::vector<std::unique_ptr<BackgroundWorker>> mergeWorkers_;  ///< by tier: one merge per tier runs at a time
    std::vector<const Tree*> treeViews_;
    /// Each part's box as it was when the part came in (tombstones only shrink a part, so it stays conservative).
    std::vector<Aabb> partBoxes_;
    std::vector<StaticPrimitive> pending_;  ///< inserted, not yet in a part, in insertion order
    /// By body: the id of the part that holds its primitives, kPendingPart or kNoPart.
    std::vector<std::uint32_t> partOfBody_;
    /// By part id: the part that absorbed it (itself while it lives).
    std::vector<std::uint32_t> mergedInto_;
    float scale_ = 0;
    std::uint64_t generation_ = 1;  ///< kept query hits of another generation are stale
    /// Boxes of the primitives inserted and removed since the last query, which spoil the kept hits of the bodies
    /// whose grown boxes they overlap; past kEditsTracked every body looks again.
    std::vector<Aabb> editBoxes_;
    bool editsOverflowed_ = false;
    std::vector<Aabb> queryEdits_;  ///< editBoxes_ as the running query sees them
    std::vector<Aabb> removedBoxes_;
    std::uint32_t commitsSinceFlush_ = 0;
    std::vector<ChunkOutput> chunks_;
    std::vector<std::uint8_t> chunkHasOutput_;  ///< per chunk of the last query: it left pairs or drops to merge
    std::vector<WorkerScratch> workers_;
    std::uint64_t droppedHits_ = 0;
};

/// Appends the primitives of a static body: one per triangle (world boxes of the posed vertices) for meshes and
/// heightfields, one world box (kWholeBody) for any other shape. `pose` takes the shape frame to the world.
void appendStaticPrimitives(const Shape& shape, const Transform& pose, std::uint32_t body,
                            std::vector<StaticPrimitive>& out);

}  // namespace rubble::detail
