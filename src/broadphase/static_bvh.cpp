// Static BVH: binned-SAH build of a four-wide tree, stack-based box queries in parallel chunks, and the forest of
// parts with its background merges described in static_bvh.h.
#include "broadphase/static_bvh.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <functional>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <thread>

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#endif

#include "bounds/bounds.h"
#include "core/parallel.h"
#include "simd/simd.h"

namespace rubble::detail {

void StaticBvh::Node::setBox(int k, const Aabb& b) {
    lo[k] = b.min.x, lo[4 + k] = b.min.y, lo[8 + k] = b.min.z;
    hi[k] = b.max.x, hi[4 + k] = b.max.y, hi[8 + k] = b.max.z;
}

namespace {

using Node = StaticBvh::Node;
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr std::uint32_t kNoParent = ~0u;
constexpr std::uint32_t kPrimitiveBit = StaticBvh::kPrimitiveBit;
constexpr std::uint32_t kUnusedLane = StaticBvh::kUnusedLane;
/// Binned SAH with 32 bins per axis is within a few percent of a full sweep on meshes, at a fraction of the cost.
constexpr int kBins = 32;
/// Inputs above this size build their lower subtrees in parallel.
constexpr std::uint32_t kParallelBuildMin = 1u << 16;

/// A box with indexable axes, for the build's per-axis loops.
struct Box {
    float lo[3] = {kInf, kInf, kInf};
    float hi[3] = {-kInf, -kInf, -kInf};

    void grow(const Box& b) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], b.lo[a]);
            hi[a] = std::max(hi[a], b.hi[a]);
        }
    }
    /// Half the surface area; 0 for empty boxes (so empty bins cost nothing).
    float halfArea() const {
        const float dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
        if (!(dx >= 0 && dy >= 0 && dz >= 0)) return 0;
        return dx * dy + dy * dz + dz * dx;
    }
    Aabb aabb() const { return {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}}; }
};

Box toBox(const Aabb& b) { return {{b.min.x, b.min.y, b.min.z}, {b.max.x, b.max.y, b.max.z}}; }

/// What the build partitions: one record per primitive with its box, doubled centroid (lo + hi; the factor 2 changes
/// no split) and input index. Moving the records themselves keeps every pass a sequential stream.
struct BuildPrimitive {
    Box box;
    float centroid[3];
    std::uint32_t index;
};

struct Range {
    std::uint32_t begin = 0, end = 0;
    Box box;
    std::uint32_t size() const { return end - begin; }
};

/// Bin of a centroid among `bins`; NaN-safe (lands in bin 0) so that bad input cannot make an out-of-range index.
inline int binOf(float c, float lo, float scale, int bins) {
    const float f = (c - lo) * scale;
    return f > 0 ? (f < float(bins - 1) ? int(f) : bins - 1) : 0;
}

Box rangeBox(const std::vector<BuildPrimitive>& prims, std::uint32_t begin, std::uint32_t end) {
    Box b;
    for (std::uint32_t i = begin; i < end; ++i) b.grow(prims[i].box);
    return b;
}

/// Splits `r` in two by the binned SAH over all three axes (cost: area(left) n(left) + area(right) n(right)); when
/// every centroid coincides (duplicate triangles) it splits at the middle of the range. Both halves are non-empty.
void split(std::vector<BuildPrimitive>& prims, const Range& r, Range& left, Range& right) {
    float clo[3] = {kInf, kInf, kInf}, chi[3] = {-kInf, -kInf, -kInf};
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        for (int a = 0; a < 3; ++a) {
            clo[a] = std::min(clo[a], prims[i].centroid[a]);
            chi[a] = std::max(chi[a], prims[i].centroid[a]);
        }
    }
    // Small ranges (most splits of a tree) use as many bins as primitives: as good a choice, at a fraction of the
    // cost of clearing and sweeping 32 bins.
    const int binCount = int(std::min<std::uint32_t>(kBins, r.size()));
    float scale[3];
    for (int a = 0; a < 3; ++a) {
        const float extent = chi[a] - clo[a];
        scale[a] = extent > 0 ? float(binCount) / extent : 0;
    }

    Box bins[3][kBins];
    std::uint32_t counts[3][kBins] = {};
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        for (int a = 0; a < 3; ++a) {
            const int b = binOf(prims[i].centroid[a], clo[a], scale[a], binCount);
            bins[a][b].grow(prims[i].box);
            ++counts[a][b];
        }
    }

    // Sweep from the right for suffix costs, then from the left; split s puts bins [0, s) left. An axis whose
    // centroids coincide has everything in bin 0 and offers no split.
    float bestCost = kInf;
    int bestAxis = -1, bestSplit = 0;
    for (int a = 0; a < 3; ++a) {
        float rightCost[kBins];
        Box acc;
        std::uint32_t n = 0;
        for (int s = binCount - 1; s > 0; --s) {
            acc.grow(bins[a][s]);
            n += counts[a][s];
            rightCost[s] = acc.halfArea() * float(n);
        }
        acc = Box{};
        n = 0;
        for (int s = 1; s < binCount; ++s) {
            acc.grow(bins[a][s - 1]);
            n += counts[a][s - 1];
            if (n == 0 || n == r.size()) continue;
            const float cost = acc.halfArea() * float(n) + rightCost[s];
            if (cost < bestCost) bestCost = cost, bestAxis = a, bestSplit = s;
        }
    }
    if (bestAxis < 0) {  // all centroids coincide: any split is as good, the middle keeps the tree balanced
        const std::uint32_t mid = r.begin + r.size() / 2;
        left = {r.begin, mid, rangeBox(prims, r.begin, mid)};
        right = {mid, r.end, rangeBox(prims, mid, r.end)};
        return;
    }
    const int a = bestAxis;
    const float lo = clo[a], sc = scale[a];
    // std::partition is sequential and deterministic; the predicate recomputes the very bins counted above.
    const auto mid = std::partition(prims.begin() + r.begin, prims.begin() + r.end, [&](const BuildPrimitive& p) {
        return binOf(p.centroid[a], lo, sc, binCount) < bestSplit;
    });
    left = {r.begin, std::uint32_t(mid - prims.begin()), {}};
    right = {left.end, r.end, {}};
    for (int s = 0; s < binCount; ++s) (s < bestSplit ? left.box : right.box).grow(bins[a][s]);
}

/// Splits `r` at its middle: the quick build's split, over records in Morton order, where each half of a range is
/// a compact region of space. Both halves are non-empty.
void splitAtMiddle(const std::vector<BuildPrimitive>& prims, const Range& r, Range& left, Range& right) {
    const std::uint32_t mid = r.begin + r.size() / 2;
    left = {r.begin, mid, rangeBox(prims, r.begin, mid)};
    right = {mid, r.end, rangeBox(prims, mid, r.end)};
}

/// The bits of a 10-bit value spread to every third bit, for a Morton code.
std::uint32_t spreadToEveryThirdBit(std::uint32_t v) {
    v &= 0x3FFu;
    v = (v | v << 16) & 0x030000FFu;
    v = (v | v << 8) & 0x0300F00Fu;
    v = (v | v << 4) & 0x030C30C3u;
    v = (v | v << 2) & 0x09249249u;
    return v;
}

/// Reorders the records along the Morton curve of their centroids (10 bits per axis over the centroids' bounds);
/// ties keep their input order, so the order depends on the input alone.
void sortAlongMortonCurve(std::vector<BuildPrimitive>& prims) {
    constexpr int kCells = 1 << 10;
    float clo[3] = {kInf, kInf, kInf}, chi[3] = {-kInf, -kInf, -kInf};
    for (const BuildPrimitive& p : prims)
        for (int a = 0; a < 3; ++a) {
            clo[a] = std::min(clo[a], p.centroid[a]);
            chi[a] = std::max(chi[a], p.centroid[a]);
        }
    float scale[3];
    for (int a = 0; a < 3; ++a) {
        const float extent = chi[a] - clo[a];
        scale[a] = extent > 0 ? float(kCells) / extent : 0;
    }
    std::vector<std::uint64_t> keys(prims.size());
    for (std::size_t i = 0; i < prims.size(); ++i) {
        std::uint32_t code = 0;
        for (int a = 0; a < 3; ++a)
            code |= spreadToEveryThirdBit(std::uint32_t(binOf(prims[i].centroid[a], clo[a], scale[a], kCells))) << a;
        keys[i] = std::uint64_t(code) << 32 | i;
    }
    std::sort(keys.begin(), keys.end());
    std::vector<BuildPrimitive> sorted(prims.size());
    for (std::size_t i = 0; i < keys.size(); ++i) sorted[i] = prims[std::uint32_t(keys[i])];
    prims.swap(sorted);
}

using BuildQuality = StaticBvh::BuildQuality;

/// Primitives a merge's loops handle between two looks at its MergeControl (some 0.1-0.5 ms).
constexpr std::size_t kPrimitivesBetweenChecks = std::size_t(1) << 16;

/// What a background merge answers to: the tree's cancellation, and the steps. While a step that takes every core
/// runs, a merge waits at its next check point: its page faults and unmaps take the process's memory map lock, and a
/// step's thread that needs it waits in turn, however low the merge's priority (a million statics with 1,000 edited a
/// step, at two threads: 3.8-5.2 ms at the 99th percentile of steps with merges running through them, 1.1-1.5 ms with
/// merges held at their check points).
struct MergeControl {
    const std::atomic<bool>& cancel;
    const StaticBvh::StepGate& gate;
    /// Waits while a step runs; false once cancelled.
    bool proceed() const;
};

struct BuildTask {
    Range range;
    std::uint32_t parent = kNoParent;  ///< node whose lane points here
    std::uint32_t lane = 0;
    std::uint32_t depth = 1;
};

Node emptyNode() {
    Node n;
    for (int k = 0; k < 4; ++k) {
        n.setBox(k, Box{}.aabb());
        n.setChild(k, kUnusedLane);
        n.hi[12 + k] = 0;
    }
    return n;
}

/// Builds the subtree of `root` depth-first (pre-order, children in lane order) into `nodes`, iteratively so that
/// skewed inputs cannot overflow the call stack. A node of more than four primitives splits its range twice (binary
/// SAH, then SAH on each half) into up to four children; a node of at most four holds them as primitive lanes.
/// With `deferred`, child ranges of at most `deferAtMost` primitives are recorded for a parallel pass instead of
/// being expanded. Returns the deepest node level reached.
std::uint32_t buildNodes(std::vector<BuildPrimitive>& prims, const BuildTask& root, AlignedVector<Node>& nodes,
                         std::vector<BuildTask>* deferred, std::uint32_t deferAtMost, BuildQuality quality,
                         const MergeControl* control = nullptr) {
    const auto halve = [&](const Range& r, Range& left, Range& right) {
        if (quality == BuildQuality::Quick)
            splitAtMiddle(prims, r, left, right);
        else
            split(prims, r, left, right);
    };
    std::uint32_t depth = 0;
    std::vector<BuildTask> stack{root};
    while (!stack.empty()) {
        if (control != nullptr && nodes.size() % 64 == 0 && !control->proceed()) return depth;
        const BuildTask task = stack.back();
        stack.pop_back();
        const auto index = std::uint32_t(nodes.size());
        if (task.parent != kNoParent) nodes[task.parent].setChild(int(task.lane), index);
        nodes.push_back(emptyNode());
        depth = std::max(depth, task.depth);

        Range children[4];
        int count = 0;
        const Range& r = task.range;
        if (r.size() <= 4) {
            for (std::uint32_t i = r.begin; i < r.end; ++i) children[count++] = {i, i + 1, prims[i].box};
        } else {
            Range halves[2];
            halve(r, halves[0], halves[1]);
            for (const Range& h : halves) {
                if (h.size() > 4) {  // a range of up to four fills one leaf node; splitting it would waste lanes
                    halve(h, children[count], children[count + 1]);
                    count += 2;
                } else {
                    children[count++] = h;
                }
            }
        }

        for (int k = count - 1; k >= 0; --k) {  // reversed so that the stack pops lane 0 first
            const Range& c = children[k];
            nodes[index].setBox(k, c.box.aabb());
            if (c.size() == 1) {
                nodes[index].setChild(k, kPrimitiveBit | c.begin);
            } else if (deferred != nullptr && c.size() <= deferAtMost) {
                deferred->push_back({c, index, std::uint32_t(k), task.depth + 1});
            } else {
                stack.push_back({c, index, std::uint32_t(k), task.depth + 1});
            }
        }
    }
    return depth;
}

bool isPrimitive(std::uint32_t child) { return (child & kPrimitiveBit) != 0 && child != kUnusedLane; }

void buildTreeUnlessCancelled(StaticBvh::Tree& tree, std::span<const StaticPrimitive> primitives, TaskPool* pool,
                              BuildQuality quality, const MergeControl* control);

}  // namespace

void StaticBvh::buildTree(Tree& tree, std::span<const StaticPrimitive> primitives, TaskPool* pool,
                          BuildQuality quality) {
    buildTreeUnlessCancelled(tree, primitives, pool, quality, nullptr);
}

namespace {

/// Large inputs build the top of the tree first, then the subtrees below it in parallel, each into its own array,
/// appended in a fixed order: the result depends on the input alone. A serial build stops early, leaving a tree
/// to throw away, once `control` says it is cancelled.
void buildTreeUnlessCancelled(StaticBvh::Tree& tree, std::span<const StaticPrimitive> primitives, TaskPool* pool,
                              BuildQuality quality, const MergeControl* control) {
    tree.nodes.clear();
    tree.primitives.clear();
    tree.depth = 0;
    if (primitives.empty()) return;
    if (primitives.size() >= kPrimitiveBit) throw std::length_error("StaticBvh: too many primitives");
    const auto n = std::uint32_t(primitives.size());

    std::vector<BuildPrimitive> prims(n);
    Box all;
    for (std::uint32_t i = 0; i < n; ++i) {
        if (control != nullptr && i % kPrimitivesBetweenChecks == 0 && !control->proceed()) return;
        BuildPrimitive& p = prims[i];
        p.box = toBox(primitives[i].box);
        for (int a = 0; a < 3; ++a) p.centroid[a] = p.box.lo[a] + p.box.hi[a];
        p.index = i;
        all.grow(p.box);
    }

    if (quality == BuildQuality::Quick) sortAlongMortonCurve(prims);
    const BuildTask root{{0, n, all}, kNoParent, 0, 1};
    if (n < kParallelBuildMin || pool == nullptr) {
        tree.depth = buildNodes(prims, root, tree.nodes, nullptr, 0, quality, control);
    } else {
        // Subtree size cut: a function of n only (never of the thread count), giving some 64-128 tasks.
        const std::uint32_t cut = std::max<std::uint32_t>(4096, n / 64);
        std::vector<BuildTask> jobs;
        tree.depth = buildNodes(prims, root, tree.nodes, &jobs, cut, quality);
        std::vector<AlignedVector<Node>> jobNodes(jobs.size());
        std::vector<std::uint32_t> jobDepth(jobs.size());
        pool->forChunks(jobs.size(), 1, [&](std::size_t j, std::size_t, std::size_t, int) {
            BuildTask local = jobs[j];
            local.parent = kNoParent;
            // Jobs partition disjoint ranges of prims, so they never touch the same data.
            jobDepth[j] = buildNodes(prims, local, jobNodes[j], nullptr, 0, quality);
        });
        for (std::size_t j = 0; j < jobs.size(); ++j) {
            const auto offset = std::uint32_t(tree.nodes.size());
            tree.nodes[jobs[j].parent].setChild(int(jobs[j].lane), offset);
            for (Node node : jobNodes[j]) {
                for (int k = 0; k < 4; ++k)
                    if ((node.child(k) & kPrimitiveBit) == 0) node.setChild(k, node.child(k) + offset);
                tree.nodes.push_back(node);
            }
            tree.depth = std::max(tree.depth, jobDepth[j]);  // jobs count levels from the global root
        }
    }

    tree.primitives.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        const StaticPrimitive& p = primitives[prims[i].index];
        tree.primitives[i] = {p.body, p.triangle};
    }
}

/// A query box broadcast to the node row layout, in registers: lo = (minX x4, minY x4, minZ x4, minZ x4) and hi
/// likewise, split into 16 / kLanes native vectors, so that lane k of (lo <= node.hi) & (node.lo <= hi) tests child
/// k on one axis per quarter.
struct QueryRows {
    static_assert(16 % simd::kLanes == 0, "a node row must split into whole native vectors");
    static constexpr std::size_t kParts = 16 / simd::kLanes;
    simd::FloatW lo[kParts], hi[kParts];

    QueryRows(const float (&boxLo)[3], const float (&boxHi)[3]) {
        using simd::FloatW;
        for (std::size_t part = 0; part < kParts; ++part) {
            const FloatW lane = simd::laneIndices<FloatW>() + simd::broadcast<FloatW>(float(part * simd::kLanes));
            const simd::MaskW x = lane < simd::broadcast<FloatW>(4), y = lane < simd::broadcast<FloatW>(8);
            lo[part] = simd::select(x, FloatW(boxLo[0]), simd::select(y, FloatW(boxLo[1]), FloatW(boxLo[2])));
            hi[part] = simd::select(x, FloatW(boxHi[0]), simd::select(y, FloatW(boxHi[1]), FloatW(boxHi[2])));
        }
    }
};

/// Bit k set when child k of `n` overlaps the query box (closed intervals). Written over the native lane type: one
/// compare pair with AVX-512, two with AVX, four with SSE; the fourth quarter (child indices) is ignored.
inline unsigned overlapMask(const Node& n, const QueryRows& q) {
    using simd::FloatW;
    std::uint32_t bits = 0;
    for (std::size_t part = 0; part < QueryRows::kParts; ++part) {
        const std::size_t off = part * simd::kLanes;
        const simd::MaskW m =
            (q.lo[part] <= simd::load<FloatW>(n.hi + off)) & (simd::load<FloatW>(n.lo + off) <= q.hi[part]);
        bits |= simd::laneBits(m) << off;
    }
    // Bits 0-3 say x overlaps for children 0-3, bits 4-7 y, bits 8-11 z.
    return bits & bits >> 4 & bits >> 8 & 0xFu;
}

/// Calls found(node, lane) for every primitive lane of `tree` whose box overlaps `q`. `stack` holds at least
/// 3 * depth + 1 entries: each level pops one node and pushes at most four.
template <class Found>
void walk(const StaticBvh::Tree& tree, const QueryRows& q, std::uint32_t* stack, Found&& found) {
    if (tree.nodes.empty()) return;
    const Node* nodes = tree.nodes.data();
    std::uint32_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& n = nodes[stack[--top]];
        for (unsigned mask = overlapMask(n, q); mask != 0; mask &= mask - 1) {
            const int k = std::countr_zero(mask);
            const std::uint32_t c = n.child(k);
            if ((c & kPrimitiveBit) == 0)
                stack[top++] = c;
            else
                found(n, k, tree.primitives[c & ~kPrimitiveBit]);
        }
    }
}

/// How much a query box is grown on every side, as a share of its largest extent, for its hits to be kept: a
/// body resting or sliding slowly stays inside for many steps, and the grown box holds few more primitives.
constexpr float kQueryGrowth = 0.125f;

/// Contains no box: a body without kept hits.
constexpr Aabb kNoBox{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};

/// Closed intervals, as the node test.
bool boxesOverlap(const Aabb& a, const Aabb& b) {
    return a.min.x <= b.max.x && b.min.x <= a.max.x && a.min.y <= b.max.y && b.min.y <= a.max.y && a.min.z <= b.max.z &&
           b.min.z <= a.max.z;
}

bool contains(const Aabb& outer, const Aabb& inner) {
    return outer.min.x <= inner.min.x && outer.min.y <= inner.min.y && outer.min.z <= inner.min.z &&
           inner.max.x <= outer.max.x && inner.max.y <= outer.max.y && inner.max.z <= outer.max.z;
}

}  // namespace

// ---- The forest of parts ----

/// Bodies removed from the parts a merge reads while it runs: remove() appends them (the step's thread), the merge
/// applies those it finds to its result once its tree is built (its own thread), and the landing only the few
/// removed after that. So a large merge that ran for seconds while a game removed statics lands without a pause.
struct MergeRemovalLog {
    std::mutex mutex;
    std::vector<std::uint32_t> bodies;
    std::size_t applied = 0;  ///< entries the merge applied to its result
};

/// One built tree of the forest, with what its edits and merges need.
struct StaticBvh::Part {
    std::uint32_t id = 0;
    Tree tree;
    /// (body << 32) | (node * 4 + lane) of every primitive lane, sorted: where remove() finds a body's lanes.
    std::vector<std::uint64_t> byBody;
    /// The primitives it was built from, never changed: merges read them on their own threads.
    std::shared_ptr<const std::vector<StaticPrimitive>> source;
    std::vector<std::uint32_t> removed;         ///< bodies tombstoned in it; merges leave their primitives out
    std::uint32_t tombstones = 0;               ///< lanes
    bool merging = false;                       ///< a merge in flight reads it
    bool quick = false;                         ///< built by the quick build: rebuilt with the SAH once edits pause
    int areaClass = 0;                          ///< of its root box as built (see areaClassOf)
    std::shared_ptr<MergeRemovalLog> mergeLog;  ///< while merging: where its removals go for the merge's result

    std::uint32_t size() const { return std::uint32_t(tree.primitives.size()); }
    std::uint32_t live() const { return size() - tombstones; }
};

/// A merge in flight: its job reads `sources` and writes `result`, and touches nothing else.
struct StaticBvh::Merge {
    struct Work {
        std::vector<std::shared_ptr<const std::vector<StaticPrimitive>>> sources;
        std::vector<std::vector<std::uint32_t>> removed;  ///< per source, sorted by the merge
        std::shared_ptr<MergeRemovalLog> log;             ///< removed since it started
        std::unique_ptr<Part> result;
        std::atomic<bool> done{false};
    };
    std::shared_ptr<Work> work;
    std::uint32_t tier = 0;
    std::vector<std::uint32_t> sourceIds;
};

/// A thread that runs jobs in order under the idle scheduling policy: it runs only on a core nothing else wants,
/// and a step's thread that wakes takes its core at once (a low nice value was not enough: a worker woken for a
/// parallel loop waited out the merge's time slice, 4 ms). It lives as long as the tree: starting a thread per
/// merge would map a new stack inside the step. Its destructor drops the jobs not begun, cancels the running one
/// and joins.
class StaticBvh::BackgroundWorker {
public:
    using Job = std::function<void(const std::atomic<bool>& cancel)>;

    BackgroundWorker() : thread_([this] { run(); }) {}
    ~BackgroundWorker() {
        std::deque<Job> dropped;
        {
            const std::lock_guard<std::mutex> lock(mutex_);
            stop_ = true;
            dropped.swap(jobs_);
        }
        cancel_.store(true, std::memory_order_relaxed);
        wake_.notify_one();
        thread_.join();
    }
    BackgroundWorker(const BackgroundWorker&) = delete;
    BackgroundWorker& operator=(const BackgroundWorker&) = delete;

    void post(Job job) {
        {
            const std::lock_guard<std::mutex> lock(mutex_);
            jobs_.push_back(std::move(job));
        }
        wake_.notify_one();
    }

private:
    void run();

    std::mutex mutex_;
    std::condition_variable wake_;
    std::deque<Job> jobs_;
    bool stop_ = false;
    std::atomic<bool> cancel_{false};
    std::thread thread_;  ///< last: it starts once the members above exist
};

namespace {

constexpr std::uint32_t kNoPart = ~0u;
constexpr std::uint32_t kPendingPart = ~0u - 1;

/// Half the surface area of a tree's root box, as a power of four (areas below 1 m^2 count as 1 m^2).
int areaClassOf(const StaticBvh::Tree& tree) {
    if (tree.nodes.empty()) return 0;
    Box box;
    for (int k = 0; k < 4; ++k) box.grow(toBox(tree.nodes[0].box(k)));
    const float area = box.halfArea();
    return area > 1 ? std::ilogb(area) / 2 : 0;  // a NaN area counts as small, an infinite one as the widest
}

/// Builds a part over `source` (its id is set by the caller).
std::unique_ptr<StaticBvh::Part> makePart(std::shared_ptr<const std::vector<StaticPrimitive>> source, TaskPool* pool,
                                          BuildQuality quality, const MergeControl* control = nullptr) {
    auto part = std::make_unique<StaticBvh::Part>();
    part->quick = quality == BuildQuality::Quick;
    buildTreeUnlessCancelled(part->tree, *source, pool, quality, control);
    if (control != nullptr && !control->proceed()) return part;
    const StaticBvh::Tree& t = part->tree;
    part->areaClass = areaClassOf(t);
    part->byBody.reserve(t.primitives.size());
    for (std::size_t i = 0; i < t.nodes.size(); ++i)
        for (int k = 0; k < 4; ++k)
            if (const std::uint32_t c = t.nodes[i].child(k); isPrimitive(c))
                part->byBody.push_back(std::uint64_t(t.primitives[c & ~kPrimitiveBit].body) << 32 |
                                       (i * 4 + std::uint32_t(k)));
    std::sort(part->byBody.begin(), part->byBody.end());
    part->source = std::move(source);
    return part;
}

/// Empties the lanes of `body` in `part`, appending their boxes to `removedBoxes` if given; returns whether it had
/// any.
bool tombstone(StaticBvh::Part& part, std::uint32_t body, std::vector<Aabb>* removedBoxes = nullptr) {
    const std::uint64_t first = std::uint64_t(body) << 32;
    bool found = false;
    for (auto it = std::lower_bound(part.byBody.begin(), part.byBody.end(), first);
         it != part.byBody.end() && (*it >> 32) == body; ++it) {
        StaticBvh::Node& node = part.tree.nodes[std::uint32_t(*it) / 4];
        const int lane = int(std::uint32_t(*it) % 4);
        if (!(node.lo[lane] <= node.hi[lane])) continue;  // tombstoned already
        if (removedBoxes != nullptr) removedBoxes->push_back(node.box(lane));
        node.setBox(lane, Box{}.aabb());
        ++part.tombstones;
        found = true;
    }
    if (found) {
        part.removed.push_back(body);
        if (part.mergeLog) {
            const std::lock_guard lock(part.mergeLog->mutex);
            part.mergeLog->bodies.push_back(body);
        }
    }
    return found;
}

/// Tier of a part of `size` live primitives: sizes within a factor kMergeFanIn share a tier.
std::uint32_t tierOf(std::uint32_t size) {
    std::uint32_t tier = 0;
    for (std::uint64_t bound = std::uint64_t(StaticBvh::kBatchPrimitives) * StaticBvh::kMergeFanIn; size >= bound;
         bound *= StaticBvh::kMergeFanIn)
        ++tier;
    return tier;
}

void runAtIdlePriority() {
#if defined(__linux__)
    sched_param param{};
    param.sched_priority = 0;
    (void)pthread_setschedparam(pthread_self(), SCHED_IDLE, &param);
#endif
}

/// The merge itself: the sources' primitives without their removed bodies, built into one part.
void runMerge(StaticBvh::Merge::Work& work, const MergeControl& control) {
    std::size_t total = 0;
    for (const auto& s : work.sources) total += s->size();
    auto merged = std::make_shared<std::vector<StaticPrimitive>>();
    merged->reserve(total);
    for (std::size_t s = 0; s < work.sources.size(); ++s) {
        std::vector<std::uint32_t>& removed = work.removed[s];
        std::sort(removed.begin(), removed.end());
        const std::vector<StaticPrimitive>& source = *work.sources[s];
        for (std::size_t i = 0; i < source.size(); ++i) {
            if (i % kPrimitivesBetweenChecks == 0 && !control.proceed()) return;
            if (!std::binary_search(removed.begin(), removed.end(), source[i].body)) merged->push_back(source[i]);
        }
    }
    if (!control.proceed()) return;
    std::unique_ptr<StaticBvh::Part> part = makePart(std::move(merged), nullptr, BuildQuality::Sah, &control);
    if (!control.proceed()) return;
    {
        // What was removed while the tree was built; the landing applies what comes after.
        const std::lock_guard lock(work.log->mutex);
        for (; work.log->applied < work.log->bodies.size(); ++work.log->applied)
            tombstone(*part, work.log->bodies[work.log->applied]);
    }
    work.result = std::move(part);
    work.done.store(true, std::memory_order_release);
}

float largestCoordinate(const StaticPrimitive& p) {
    float m = 0;
    for (const float c : {p.box.min.x, p.box.min.y, p.box.min.z, p.box.max.x, p.box.max.y, p.box.max.z})
        if (std::isfinite(c)) m = std::max(m, std::fabs(c));
    return m;
}

}  // namespace

void StaticBvh::BackgroundWorker::run() {
    runAtIdlePriority();
    for (;;) {
        Job job;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            wake_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
            if (jobs_.empty()) return;  // stopping, with nothing left to run
            job = std::move(jobs_.front());
            jobs_.pop_front();
        }
        job(cancel_);
    }
}

bool MergeControl::proceed() const {
    std::unique_lock lock(gate.mutex);
    // Timed: cancellation does not signal the gate.
    while (gate.stepping && !cancel.load(std::memory_order_relaxed))
        gate.open.wait_for(lock, std::chrono::milliseconds(1));
    return !cancel.load(std::memory_order_relaxed);
}

void StaticBvh::StepGate::set(bool steppingNow) {
    {
        const std::lock_guard lock(mutex);
        stepping = steppingNow;
    }
    if (!steppingNow) open.notify_all();
}

StaticBvh::StaticBvh() : gate_(std::make_shared<StepGate>()) {}

StaticBvh::~StaticBvh() { dropMerges(); }

void StaticBvh::dropMerges() {
    mergeWorkers_.clear();  // each drops the jobs not begun, cancels the running one and joins
    merges_.clear();
    for (const std::unique_ptr<Part>& p : parts_) p->merging = false, p->mergeLog.reset();
}

StaticBvh::BackgroundWorker& StaticBvh::workerFor(std::uint32_t tier) {
    if (tier >= mergeWorkers_.size()) mergeWorkers_.resize(tier + 1);
    if (!mergeWorkers_[tier]) mergeWorkers_[tier] = std::make_unique<BackgroundWorker>();
    return *mergeWorkers_[tier];
}

void StaticBvh::build(std::vector<StaticPrimitive> primitives, TaskPool& pool) {
    ++generation_;
    dropMerges();
    parts_.clear();
    partOfBody_.clear();
    mergedInto_.clear();
    scale_ = 0;
    pending_ = std::move(primitives);
    notePending(pending_);
    flushPending(&pool, BuildQuality::Sah);
}

void StaticBvh::notePending(std::span<const StaticPrimitive> primitives) {
    for (const StaticPrimitive& p : primitives) {
        if (p.body >= partOfBody_.size())
            partOfBody_.resize(std::max(std::size_t(p.body) + 1, 2 * partOfBody_.size()), kNoPart);
        partOfBody_[p.body] = kPendingPart;
        scale_ = std::max(scale_, largestCoordinate(p));
    }
}

void StaticBvh::insert(std::span<const StaticPrimitive> primitives, TaskPool& pool, BuildQuality quality) {
    if (primitives.empty()) return;
    for (const StaticPrimitive& p : primitives) noteEdit(p.box);
    pending_.insert(pending_.end(), primitives.begin(), primitives.end());
    notePending(primitives);
    if (pending_.size() >= kBatchPrimitives) commitBuilding(pool, quality);  // the caller's time
}

void StaticBvh::remove(std::uint32_t body) {
    if (body >= partOfBody_.size()) return;
    const std::uint32_t id = partOfBody_[body];
    partOfBody_[body] = kNoPart;
    if (id == kNoPart) return;
    if (id == kPendingPart) {  // its boxes are among the edits already, as inserted
        std::erase_if(pending_, [body](const StaticPrimitive& p) { return p.body == body; });
        return;
    }
    if (Part* part = findPart(id)) {
        removedBoxes_.clear();
        tombstone(*part, body, &removedBoxes_);
        for (const Aabb& box : removedBoxes_) noteEdit(box);
    }
}

void StaticBvh::noteEdit(const Aabb& box) {
    if (editBoxes_.size() < kEditsTracked)
        editBoxes_.push_back(box);
    else
        editsOverflowed_ = true;
}

void StaticBvh::commit(TaskPool& pool) {
    commitBuilding(pool, pending_.size() <= kQuickBuildMax ? BuildQuality::Quick : BuildQuality::Sah);
}

void StaticBvh::commitBuilding(TaskPool& pool, BuildQuality quality) {
    ++commitsSinceFlush_;
    flushPending(&pool, quality);
    landFinishedMerges();
    startDueMerges(true, commitsSinceFlush_ > kQuietCommits);
}

void StaticBvh::settle(TaskPool& pool) {
    flushPending(&pool, BuildQuality::Sah);
    landFinishedMerges();
    // Merges in flight are dropped and done again here: a test waiting on an idle-priority thread could wait for as
    // long as other programs keep the cores busy.
    dropMerges();
    while (startDueMerges(false, true) > 0) landFinishedMerges();
}

void StaticBvh::flushPending(TaskPool* pool, BuildQuality quality) {
    if (pending_.empty()) return;
    auto source = std::make_shared<const std::vector<StaticPrimitive>>(std::move(pending_));
    pending_ = {};
    std::unique_ptr<Part> part = makePart(std::move(source), pool, quality);
    commitsSinceFlush_ = 0;
    part->id = std::uint32_t(mergedInto_.size());
    mergedInto_.push_back(part->id);
    for (const StaticPrimitive& p : *part->source) partOfBody_[p.body] = part->id;
    addPart(std::move(part));
}

void StaticBvh::addPart(std::unique_ptr<Part> part) {
    if (part->live() > 0) parts_.push_back(std::move(part));
    refreshTreeViews();
}

StaticBvh::Part* StaticBvh::findPart(std::uint32_t id) {
    while (mergedInto_[id] != id) id = mergedInto_[id];
    for (const std::unique_ptr<Part>& p : parts_)
        if (p->id == id) return p.get();
    return nullptr;  // every primitive it had was removed, and it was dropped
}

void StaticBvh::landFinishedMerges() {
    for (std::size_t i = 0; i < merges_.size();) {
        Merge& m = *merges_[i];
        if (!m.work->done.load(std::memory_order_acquire)) {
            ++i;
            continue;
        }
        std::unique_ptr<Part> result = std::move(m.work->result);
        result->id = std::uint32_t(mergedInto_.size());
        mergedInto_.push_back(result->id);
        for (const std::uint32_t source : m.sourceIds) mergedInto_[source] = result->id;
        {
            // Removed after the merge caught up: the result still holds them.
            MergeRemovalLog& log = *m.work->log;
            const std::lock_guard lock(log.mutex);
            for (std::size_t r = log.applied; r < log.bodies.size(); ++r) tombstone(*result, log.bodies[r]);
        }
        std::vector<std::unique_ptr<Part>> replaced;
        std::size_t replacedSize = 0;
        for (std::unique_ptr<Part>& p : parts_) {
            if (std::find(m.sourceIds.begin(), m.sourceIds.end(), p->id) == m.sourceIds.end()) continue;
            p->mergeLog.reset();
            replacedSize += p->size();
            replaced.push_back(std::move(p));
        }
        std::erase(parts_, nullptr);
        addPart(std::move(result));
        std::shared_ptr<Merge::Work> work = std::move(m.work);
        const std::uint32_t tier = m.tier;
        merges_.erase(merges_.begin() + std::ptrdiff_t(i));  // m is gone from here on
        // Returning the memory of large parts to the system takes milliseconds (unmapping tens of megabytes), so
        // it is done off the step too.
        if (replacedSize >= kMergeFanIn * kBatchPrimitives * kMergeFanIn) {
            auto doomed = std::make_shared<std::vector<std::unique_ptr<Part>>>(std::move(replaced));
            workerFor(tier).post([doomed, w = std::move(work), gate = gate_](const std::atomic<bool>& cancel) mutable {
                if (MergeControl{cancel, *gate}.proceed()) doomed->clear();
                w.reset();
            });
        }
    }
}

std::size_t StaticBvh::startDueMerges(bool background, bool quiet) {
    // Parts of a tier wait until kMergeFanIn of them are idle; at most one merge per tier runs at a time, so a long
    // merge of large parts never holds up the quick merges of small ones.
    std::size_t started = 0;
    std::vector<std::vector<Part*>> idleByTier;
    std::vector<bool> tierBusy;
    auto grow = [&](std::uint32_t tier) {
        if (tier >= idleByTier.size()) idleByTier.resize(tier + 1), tierBusy.resize(tier + 1, false);
    };
    for (const std::unique_ptr<Part>& p : parts_) {
        const std::uint32_t tier = tierOf(p->live());
        grow(tier);
        if (p->merging)
            tierBusy[tier] = true;
        else
            idleByTier[tier].push_back(p.get());
    }
    for (std::uint32_t tier = 0; tier < idleByTier.size(); ++tier) {
        if (tierBusy[tier]) continue;
        std::vector<Part*>& idle = idleByTier[tier];
        if (idle.size() >= kMergeFanIn) {
            // The widest first: every query that overlaps a part walks it, and a batch of edits scattered over the
            // world overlaps every query. Areas within a factor of four count as equal and go oldest first, so a
            // level loaded in order merges neighbours into compact parts that few queries touch.
            std::stable_sort(idle.begin(), idle.end(),
                             [](const Part* a, const Part* b) { return a->areaClass > b->areaClass; });
            idle.resize(kMergeFanIn);
            startMerge(std::move(idle), tier, background);
            ++started;
            continue;
        }
        for (Part* p : idle)
            if (std::uint64_t(p->tombstones) * 4 > p->size() || (quiet && p->quick)) {
                startMerge({p}, tier, background);
                ++started;
                break;
            }
    }
    return started;
}

void StaticBvh::startMerge(std::vector<Part*> sources, std::uint32_t tier, bool background) {
    auto merge = std::make_unique<Merge>();
    merge->work = std::make_shared<Merge::Work>();
    merge->work->log = std::make_shared<MergeRemovalLog>();
    for (Part* p : sources) {
        p->merging = true;
        p->mergeLog = merge->work->log;
        merge->sourceIds.push_back(p->id);
        merge->work->sources.push_back(p->source);
        merge->work->removed.push_back(p->removed);  // sorted by the merge, off the step
    }
    merge->tier = tier;
    if (background) {
        workerFor(tier).post([work = merge->work, gate = gate_](const std::atomic<bool>& cancel) {
            runMerge(*work, MergeControl{cancel, *gate});
        });
    } else {
        const std::atomic<bool> never{false};
        const StepGate open;
        runMerge(*merge->work, MergeControl{never, open});
    }
    merges_.push_back(std::move(merge));
}

void StaticBvh::refreshTreeViews() {
    treeViews_.clear();
    partBoxes_.clear();
    for (const std::unique_ptr<Part>& p : parts_) {
        treeViews_.push_back(&p->tree);
        Box box;
        for (int k = 0; k < 4; ++k) box.grow(toBox(p->tree.nodes[0].box(k)));
        partBoxes_.push_back(box.aabb());
    }
}

void StaticBvh::query(const Bounds& moving, const StaticQueryFilter& filter, TaskPool& pool,
                      std::vector<BodyPair>& bodyPairs, std::vector<MeshPair>& meshPairs,
                      std::vector<std::uint32_t>& meshTriangles) {
    commit(pool);
    bodyPairs.clear();
    meshPairs.clear();
    meshTriangles.clear();
    droppedHits_ = 0;
    const std::uint32_t n = moving.size();
    // Edits spoil only the kept hits of bodies whose grown boxes they overlap; past kEditsTracked, all of them.
    if (editsOverflowed_) ++generation_;
    if (n == 0 || treeViews_.empty()) {
        if (!editBoxes_.empty()) ++generation_;
        editBoxes_.clear();
        editsOverflowed_ = false;
        return;
    }
    queryEdits_.clear();
    if (!editsOverflowed_) queryEdits_.swap(editBoxes_);
    editBoxes_.clear();
    editsOverflowed_ = false;

    const std::size_t chunkCount = TaskPool::chunkCount(n, kQueryChunk);
    if (chunks_.size() < chunkCount) chunks_.resize(chunkCount);
    chunkHasOutput_.assign(chunkCount, 0);
    if (workers_.size() < std::size_t(pool.threadCount())) workers_.resize(std::size_t(pool.threadCount()));
    std::uint32_t depth = 0;
    for (const Tree* tree : treeViews_) depth = std::max(depth, tree->depth);
    const std::size_t stackSize = 3 * std::size_t(depth) + 1;
    for (WorkerScratch& w : workers_) w.stack.resize(std::max(w.stack.size(), stackSize));

    pool.forChunks(n, kQueryChunk, [&](std::size_t chunk, std::size_t begin, std::size_t end, int worker) {
        ChunkOutput& out = chunks_[chunk];
        out.bodyPairs.clear();
        out.meshPairs.clear();
        out.triangles.clear();
        const bool keptValid = out.keptGeneration == generation_ && out.keptBegin == begin && out.keptEnd == end;
        out.grown.resize(end - begin);
        out.keptStart.resize(end - begin + 1);
        WorkerScratch& scratch = workers_[std::size_t(worker)];
        if (!keptValid) {
            std::fill(out.grown.begin(), out.grown.end(), kNoBox);
            std::fill(out.keptStart.begin(), out.keptStart.end(), 0u);
            out.kept.clear();
        } else if (!queryEdits_.empty()) {
            // A body whose grown box an edit overlaps looks again (asleep, once it wakes). The edits near the
            // chunk's union of grown boxes first: most edits are far from most chunks.
            Box chunkBox;
            for (const Aabb& g : out.grown) chunkBox.grow(toBox(g));
            const Aabb reach = chunkBox.aabb();
            std::vector<Aabb>& near = scratch.edits;
            near.clear();
            for (const Aabb& e : queryEdits_)
                if (boxesOverlap(e, reach)) near.push_back(e);
            if (!near.empty())
                for (Aabb& g : out.grown)
                    if (std::any_of(near.begin(), near.end(), [&](const Aabb& e) { return boxesOverlap(e, g); }))
                        g = kNoBox;
        }
        std::vector<std::uint64_t>& hits = scratch.hits;
        const PairFilter& mf = filter.moving;
        const auto boxOf = [&](std::uint32_t i) {
            return Aabb{{moving.minX[i], moving.minY[i], moving.minZ[i]},
                        {moving.maxX[i], moving.maxY[i], moving.maxZ[i]}};
        };
        // The kept lists are rewritten only when some awake body left its grown box: a resting chunk copies nothing.
        bool rewrite = !keptValid;
        // The budget bounds the kept lists, and with them every output: static bodies piled onto one point would
        // otherwise hand each moving body near them the whole pile.
        const std::size_t cap = std::max((end - begin) * limits::kStaticHitsPerBody, limits::kMinChunkStaticHits);
        for (auto i = std::uint32_t(begin); i < end && !rewrite; ++i)
            rewrite = !mf.asleep(i) && !contains(out.grown[i - begin], boxOf(i));
        if (rewrite) out.keptDropped = 0;
        out.keptNext.clear();
        for (auto i = std::uint32_t(begin); i < end; ++i) {
            const std::size_t local = i - begin;
            const bool asleep = mf.asleep(i);  // asleep vs static (which counts as asleep) is never a pair
            const Aabb box = boxOf(i);
            const KeptHit* list = out.kept.data() + out.keptStart[local];
            std::size_t listSize = out.keptStart[local + 1] - out.keptStart[local];
            if (rewrite) {
                const std::size_t first = out.keptNext.size();
                if (asleep || contains(out.grown[local], box)) {
                    out.keptNext.insert(out.keptNext.end(), list, list + listSize);
                } else {
                    const float reach = std::max({box.max.x - box.min.x, box.max.y - box.min.y, box.max.z - box.min.z});
                    const Vec3 grow = Vec3{1, 1, 1} * (kQueryGrowth * reach);
                    const Aabb grown{box.min - grow, box.max + grow};
                    const QueryRows q({grown.min.x, grown.min.y, grown.min.z}, {grown.max.x, grown.max.y, grown.max.z});
                    const std::size_t walkFirst = out.keptNext.size();
                    const auto keep = [&](const Node& node, int lane, const PrimitiveRef& p) {
                        out.keptNext.push_back({std::uint64_t(p.body) << 32 | p.triangle,
                                                {node.lo[lane], node.lo[4 + lane], node.lo[8 + lane]},
                                                {node.hi[lane], node.hi[4 + lane], node.hi[8 + lane]}});
                    };
                    // A part's box first: while merges catch up with a large load there are hundreds of parts,
                    // and most lie far from the body.
                    for (std::size_t part = 0; part < treeViews_.size(); ++part)
                        if (boxesOverlap(partBoxes_[part], grown))
                            walk(*treeViews_[part], q, scratch.stack.data(), keep);
                    // Tree order to the canonical order, whichever part and leaf held them. Duplicates only arise
                    // from inserting the same primitive twice.
                    const auto found = out.keptNext.begin() + std::ptrdiff_t(walkFirst);
                    std::sort(found, out.keptNext.end(),
                              [](const KeptHit& x, const KeptHit& y) { return x.key < y.key; });
                    out.keptNext.erase(std::unique(found, out.keptNext.end(),
                                                   [](const KeptHit& x, const KeptHit& y) { return x.key == y.key; }),
                                       out.keptNext.end());
                    // A grown box with a NaN contains no box, so such a body walks the tree every step.
                    out.grown[local] = grown;
                }
                if (out.keptNext.size() > cap) {
                    // Past the budget the body keeps its lowest keys (a choice that depends on nothing but the
                    // world), and looks again at every rewrite, in case the room came back.
                    out.keptDropped += out.keptNext.size() - cap;
                    out.keptNext.resize(cap);
                    out.grown[local] = kNoBox;
                }
                // keptStart[local + 1] is still the old list's end, which the next body reads before rewriting it.
                out.keptStart[local] = std::uint32_t(first);
                list = out.keptNext.data() + first;
                listSize = out.keptNext.size() - first;
            }
            if (asleep) continue;
            // The exact hits: the kept ones whose boxes overlap the body's own (closed intervals, as the walk).
            hits.clear();
            for (std::size_t h = 0; h < listSize; ++h) {
                const KeptHit& k = list[h];
                if (box.min.x <= k.hi[0] && k.lo[0] <= box.max.x && box.min.y <= k.hi[1] && k.lo[1] <= box.max.y &&
                    box.min.z <= k.hi[2] && k.lo[2] <= box.max.z)
                    hits.push_back(k.key);
            }
            if (hits.empty()) continue;

            const std::uint32_t category = mf.category != nullptr ? mf.category[i] : ~0u;
            const std::uint32_t mask = mf.mask != nullptr ? mf.mask[i] : ~0u;
            for (std::size_t h = 0; h < hits.size();) {
                const auto body = std::uint32_t(hits[h] >> 32);
                std::size_t runEnd = h;
                while (runEnd < hits.size() && std::uint32_t(hits[runEnd] >> 32) == body) ++runEnd;
                const std::uint32_t staticCategory = filter.staticCategory ? filter.staticCategory[body] : ~0u;
                const std::uint32_t staticMask = filter.staticMask ? filter.staticMask[body] : ~0u;
                if (filtersAccept(category, mask, staticCategory, staticMask)) {
                    // kWholeBody (~0u) sorts after every triangle of the same body.
                    std::size_t triangleEnd = runEnd;
                    if (std::uint32_t(hits[runEnd - 1]) == kWholeBody) {
                        out.bodyPairs.push_back({i, body});
                        --triangleEnd;
                    }
                    if (triangleEnd > h) {
                        out.meshPairs.push_back(
                            {i, body, std::uint32_t(out.triangles.size()), std::uint32_t(triangleEnd - h)});
                        for (std::size_t t = h; t < triangleEnd; ++t) out.triangles.push_back(std::uint32_t(hits[t]));
                    }
                }
                h = runEnd;
            }
        }
        if (rewrite) {
            out.keptStart[end - begin] = std::uint32_t(out.keptNext.size());
            out.kept.swap(out.keptNext);
        }
        out.keptGeneration = generation_;
        out.keptBegin = std::uint32_t(begin);
        out.keptEnd = std::uint32_t(end);
        chunkHasOutput_[chunk] = !out.bodyPairs.empty() || !out.meshPairs.empty() || out.keptDropped > 0;
    });

    // Merge in chunk order: the output is the same for any thread count. Most chunks of a large world have none (it
    // rests, or sleeps): their outputs are not even looked at.
    std::size_t bodyTotal = 0, meshTotal = 0, triangleTotal = 0;
    for (std::size_t c = 0; c < chunkCount; ++c) {
        if (!chunkHasOutput_[c]) continue;
        droppedHits_ += chunks_[c].keptDropped;
        bodyTotal += chunks_[c].bodyPairs.size();
        meshTotal += chunks_[c].meshPairs.size();
        triangleTotal += chunks_[c].triangles.size();
    }
    bodyPairs.reserve(bodyTotal);
    meshPairs.reserve(meshTotal);
    meshTriangles.reserve(triangleTotal);
    for (std::size_t c = 0; c < chunkCount; ++c) {
        if (!chunkHasOutput_[c]) continue;
        const ChunkOutput& out = chunks_[c];
        const auto base = std::uint32_t(meshTriangles.size());
        bodyPairs.insert(bodyPairs.end(), out.bodyPairs.begin(), out.bodyPairs.end());
        for (MeshPair m : out.meshPairs) {
            m.firstTriangle += base;
            meshPairs.push_back(m);
        }
        meshTriangles.insert(meshTriangles.end(), out.triangles.begin(), out.triangles.end());
    }
}

std::uint32_t StaticBvh::primitiveCount() const {
    std::size_t count = pending_.size();
    for (const std::unique_ptr<Part>& p : parts_) count += p->live();
    return std::uint32_t(count);
}

StaticBvhStats StaticBvh::stats() const {
    StaticBvhStats s;
    s.parts = std::uint32_t(parts_.size());
    s.pending = std::uint32_t(pending_.size());
    const Part* largest = nullptr;
    for (const std::unique_ptr<Part>& p : parts_) {
        s.merging += p->merging ? 1 : 0;
        s.nodes += std::uint32_t(p->tree.nodes.size());
        s.depth = std::max(s.depth, p->tree.depth);
        s.primitives += p->size();
        s.tombstones += p->tombstones;
        if (largest == nullptr || p->size() > largest->size()) largest = p.get();
    }
    if (largest == nullptr || largest->tree.nodes.empty()) return s;
    const Tree& tree = largest->tree;
    Box root;
    for (int k = 0; k < 4; ++k) root.grow(toBox(tree.nodes[0].box(k)));
    double rootArea = root.halfArea();
    if (!(rootArea > 0)) rootArea = 1;  // a flat or single-point set: weights become plain areas
    double cost = 1;                    // the root is always visited
    for (const Node& n : tree.nodes)
        for (int k = 0; k < 4; ++k)
            if (n.child(k) != kUnusedLane) cost += toBox(n.box(k)).halfArea() / rootArea;
    s.sahCost = cost;
    return s;
}

// ---- Primitives of static bodies ----

namespace {

Aabb triangleBox(Vec3 a, Vec3 b, Vec3 c) {
    return {{std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})},
            {std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})}};
}

}  // namespace

void appendStaticPrimitives(const Shape& shape, const Transform& pose, std::uint32_t body,
                            std::vector<StaticPrimitive>& out) {
    if (shape.kind == ShapeKind::TriangleMesh) {
        const TriangleMesh& mesh = *shape.mesh;
        std::vector<Vec3> world(mesh.vertices.size());
        for (std::size_t v = 0; v < world.size(); ++v) world[v] = apply(pose, mesh.vertices[v]);
        out.reserve(out.size() + mesh.triangleCount());
        for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
            const std::uint32_t* idx = &mesh.indices[3 * std::size_t(t)];
            out.push_back({triangleBox(world[idx[0]], world[idx[1]], world[idx[2]]), body, t});
        }
    } else if (shape.kind == ShapeKind::Heightfield) {
        // From the grid directly: each sample is posed once per row pair, not once per triangle.
        const Heightfield& field = *shape.heightfield;
        if (heightfieldTriangleCount(field) == 0) return;
        out.reserve(out.size() + heightfieldTriangleCount(field));
        auto posedRow = [&](std::uint32_t row, std::vector<Vec3>& dst) {
            dst.resize(field.columns);
            for (std::uint32_t col = 0; col < field.columns; ++col)
                dst[col] = apply(pose, heightfieldSample(field, row, col));
        };
        std::vector<Vec3> row0, row1;
        posedRow(0, row0);
        for (std::uint32_t r = 0; r + 1 < field.rows; ++r) {
            posedRow(r + 1, row1);
            for (std::uint32_t c = 0; c + 1 < field.columns; ++c) {
                const Vec3 p00 = row0[c], p10 = row0[c + 1], p01 = row1[c], p11 = row1[c + 1];
                const std::uint32_t t = 2 * (r * (field.columns - 1) + c);
                out.push_back({triangleBox(p00, p01, p11), body, t});
                out.push_back({triangleBox(p00, p11, p10), body, t + 1});
            }
            std::swap(row0, row1);
        }
    } else {
        out.push_back({worldBounds(shape, pose), body, kWholeBody});
    }
}

}  // namespace rubble::detail
