// How the contact solver splits the step's manifolds into the segments it solves apart (blocks of small islands, the
// slabs of large islands and the manifolds that cross them: ContactSolver::partition and splitIntoSlabs), numbers
// their bodies' rows and colours each segment (assignRows, colourSegments, layOutColours, fillLanes). Kept apart
// from contact_solver.cpp, whose kernels GCC inlines within a growth budget for the whole file: there, the
// partition alone cost S5's solver 3% at one thread.
#include "solver/contact_solver.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>

#include "islands/islands.h"

namespace rubble::detail {
namespace {

/// Islands with more manifolds than this are solved colour by colour across the threads; smaller ones are packed
/// into blocks that one task solves whole. A block of this size takes a few hundred microseconds per solve on one
/// core, so one island never holds the other threads up for long.
constexpr std::size_t kLargeIslandManifolds = 1024;
/// A block is closed once it holds this many manifolds: enough per colour to fill the SIMD lanes (S6's walls: 95%
/// against 86% at 256), few enough that a block's constraint rows (about 400 bytes per manifold, 300 KB) stay in
/// the core's own 1 MB cache across the iterations.
constexpr std::size_t kBlockManifolds = 768;
/// The large islands are cut in two slabs (see splitIntoSlabs()) when they hold at least this many manifolds and
/// their colours held fewer than kSlabBatchesPerColor batches on average in the last step. Two, whatever the thread
/// count (the result must not depend on it): one per core of the machines Rubble is measured on.
constexpr std::size_t kSlabManifolds = 2048;
constexpr std::size_t kSlabCount = 2;
/// Below this many batches per colour, a colour's dispatch and wait cost more than the work the second thread takes
/// from it. S3's pile (55 a colour, eight of its 18 colours under 32) solves 20% faster in slabs at two threads;
/// S1's pyramid (80) and S5's wall (156) gain nothing at two threads and lose 3-5% at one (the crossing manifolds'
/// extra colours and the cut).
constexpr float kSlabBatchesPerColor = 64;

}  // namespace

void ContactSolver::partition(const Contacts& contacts, const Islands* islands, const MovingBodies& m) {
    const std::size_t manifoldCount = contacts.manifolds.size();
    segmentManifolds_.clear();
    segmentStart_.assign(1, 0);
    segmentOfIsland_.clear();
    slabSegments_ = 0;
    const bool useIslands = islands && islands->count() > 0 && islands->manifolds.size() <= manifoldCount;
    segmentsFromIslands_ = useIslands;
    if (!useIslands) {
        segmentManifolds_.resize(manifoldCount);
        for (std::size_t k = 0; k < manifoldCount; ++k) segmentManifolds_[k] = static_cast<std::uint32_t>(k);
        segmentStart_.push_back(static_cast<std::uint32_t>(manifoldCount));
        return;
    }
    placed_.assign(manifoldCount, 0);
    segmentOfIsland_.assign(islands->count(), kLargeSegment);
    const auto blockSize = [&] { return segmentManifolds_.size() - segmentStart_.back(); };
    for (std::uint32_t k = 0; k < islands->count(); ++k) {
        const std::uint32_t first = islands->manifoldStart[k], last = islands->manifoldStart[k + 1];
        if (last == first || last - first > kLargeIslandManifolds) continue;
        // The block being filled; blocks that end up with no constraint are dropped after colouring (see prepare).
        segmentOfIsland_[k] = static_cast<std::uint32_t>(segmentStart_.size() - 1);
        for (std::uint32_t i = first; i < last; ++i) {
            segmentManifolds_.push_back(islands->manifolds[i]);
            placed_[islands->manifolds[i]] = 1;
        }
        if (blockSize() >= kBlockManifolds)
            segmentStart_.push_back(static_cast<std::uint32_t>(segmentManifolds_.size()));
    }
    if (blockSize() > 0) segmentStart_.push_back(static_cast<std::uint32_t>(segmentManifolds_.size()));
    // The large part: every manifold not in a block (large islands, and any in no island), in manifold order.
    largePart_.clear();
    for (std::size_t k = 0; k < manifoldCount; ++k)
        if (!placed_[k]) largePart_.push_back(static_cast<std::uint32_t>(k));
    splitIntoSlabs(contacts, m);
}

void ContactSolver::splitIntoSlabs(const Contacts& contacts, const MovingBodies& m) {
    // Colour by colour, every colour of a large island costs each thread a wait, and the bodies' rows move between
    // the cores' caches with every colour. Cut in slabs across its longest axis, most of the island's manifolds have
    // both bodies in one slab: each slab is solved whole by one task, every colour of it with no wait and its rows in
    // that core's cache, and only the manifolds that cross the cut are solved colour by colour across the threads
    // (see forEachColor). The cut depends on the bodies' positions only, never on the thread count. S3's pile at two
    // threads: velocity iterations 1.66 -> 1.33 ms, for 0.1 ms more in prepare.
    const auto appendLarge = [&](const std::uint32_t* first, std::size_t count) {
        segmentManifolds_.insert(segmentManifolds_.end(), first, first + count);
        segmentStart_.push_back(static_cast<std::uint32_t>(segmentManifolds_.size()));
    };
    if (largePart_.size() < kSlabManifolds || !(largeBatchesPerColor_ < kSlabBatchesPerColor)) {
        appendLarge(largePart_.data(), largePart_.size());
        return;
    }
    // A manifold's place: its first dynamic body's. The cut runs across the longest axis of the box around the
    // places, at their median, so that the slabs hold about as many manifolds each. Every 8th manifold stands for
    // the rest: the slabs need not be equal to a manifold.
    const auto dynamicSide = [&](std::uint32_t k) {
        return (traits_[k] & kTraitDynamicA) != 0 ? contacts.pairs[k].a : contacts.pairs[k].b;
    };
    constexpr std::size_t kSampleStride = 8;
    Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    slabPlaces_.clear();
    for (std::size_t i = 0; i < largePart_.size(); i += kSampleStride) {
        const std::uint32_t d = dynamicSide(largePart_[i]);
        const Vec3 p{m.px[d], m.py[d], m.pz[d]};
        slabPlaces_.push_back(p);
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    const Vec3 extent = hi - lo;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    const float* coordinate = axis == 0 ? m.px.data() : (axis == 1 ? m.py.data() : m.pz.data());
    slabKeys_.resize(slabPlaces_.size());
    for (std::size_t i = 0; i < slabPlaces_.size(); ++i) slabKeys_[i] = slabPlaces_[i][axis];
    const auto middle = slabKeys_.begin() + static_cast<std::ptrdiff_t>(slabKeys_.size() / 2);
    std::nth_element(slabKeys_.begin(), middle, slabKeys_.end());
    const float cut = *middle;
    if (!(cut > lo[axis] && cut <= hi[axis])) {  // every place the same (or not finite): nothing to cut
        appendLarge(largePart_.data(), largePart_.size());
        return;
    }
    slabAxis_ = axis;
    slabCut_ = cut;
    // A manifold stays in a slab when all its dynamic bodies lie on that side of the cut; else it crosses.
    // Written without branches: which side of the cut a manifold lies is a coin toss to the branch predictor.
    const auto slabOf = [&](std::uint32_t dense) { return coordinate[dense] < cut ? 0u : 1u; };
    // Each list is kept as long as the large part (only `counts` of it used): growing it back every step would
    // clear it every step.
    std::uint32_t* lists[kSlabCount + 1];
    std::size_t counts[kSlabCount + 1] = {};
    for (std::size_t part = 0; part <= kSlabCount; ++part) {
        if (slabParts_[part].size() < largePart_.size()) slabParts_[part].resize(largePart_.size());
        lists[part] = slabParts_[part].data();
    }
    for (const std::uint32_t k : largePart_) {
        const ContactPair& p = contacts.pairs[k];
        const bool dynA = (traits_[k] & kTraitDynamicA) != 0, dynB = (traits_[k] & kTraitDynamicB) != 0;
        const std::uint32_t slabA = dynA ? slabOf(p.a) : kSlabCount, slabB = dynB ? slabOf(p.b) : kSlabCount;
        const std::uint32_t slab = slabA == kSlabCount ? slabB : slabA;
        // No dynamic body (left out when coloured), or a cut between them: the crossing part (index kSlabCount).
        const std::uint32_t part = slabB != kSlabCount && slabB != slab ? kSlabCount : slab;
        lists[part][counts[part]++] = k;
    }
    for (std::size_t part = 0; part <= kSlabCount; ++part) appendLarge(lists[part], counts[part]);
    slabSegments_ = kSlabCount;
}

void ContactSolver::assignRows(const Contacts& contacts, const Islands* islands, const MovingBodies& m, bool anyHeld) {
    // Only the last prepare's bodies hold a row: clear theirs rather than one entry per moving body (a million sparse
    // bodies with a few thousand in contact). Bodies may have moved or gone since; the entries are cleared whoever
    // holds them now.
    for (const std::uint32_t dense : bodies_.moving)
        if (dense < solverIndex_.size()) solverIndex_[dense] = -1;
    solverIndex_.resize(m.size(), -1);
    bodies_.moving.clear();
    const std::size_t segmentCount = segmentStart_.size() - 1;
    segmentRows_.assign(segmentCount, {});
    const auto rowCount = [&] { return static_cast<std::uint32_t>(bodies_.moving.size()); };
    // The moving sides the solve touches, in segment order: the sides it holds still, and the dynamic ones too
    // unless the islands number those.
    const auto touchSides = [&](bool dynamicToo) {
        const std::uint8_t sideA = kTraitHeldA | (dynamicToo ? kTraitDynamicA : 0);
        const std::uint8_t sideB = kTraitHeldB | (dynamicToo ? kTraitDynamicB : 0);
        for (const std::uint32_t k : segmentManifolds_) {
            const std::uint8_t traits = traits_[k];
            if ((traits & kTraitLeftOut) != 0) continue;
            const ContactPair& p = contacts.pairs[k];
            if ((traits & sideA) != 0) touchRow(p.a);
            if ((traits & sideB) != 0) touchRow(p.b);
        }
    };
    if (!segmentsFromIslands_) {
        touchSides(true);  // in order of first appearance
        for (RowRange& range : segmentRows_) range = {0, rowCount()};
        return;
    }
    // Every dynamic body lies in one island, and the islands' bodies are listed: a block's bodies take rows island by
    // island, the large islands' bodies slab by slab, each in ascending index order. Every segment's dynamic bodies
    // then lie in rows of its own (a block's neighbouring ones), numbered without reading a manifold, and the
    // segments can be coloured apart (colourSegments). The bodies the solve holds still come after, in order of
    // first appearance.
    const auto islandManifolds = [&](std::uint32_t k) {
        return islands->manifoldStart[k + 1] - islands->manifoldStart[k];
    };
    const auto touchIsland = [&](std::uint32_t k, int slab) {
        const float* coordinate = slabAxis_ == 0 ? m.px.data() : (slabAxis_ == 1 ? m.py.data() : m.pz.data());
        for (std::uint32_t i = islands->bodyStart[k]; i < islands->bodyStart[k + 1]; ++i) {
            const std::uint32_t body = islands->bodies[i];
            if (!isDynamicBody(m, body)) continue;
            if (slab >= 0 && (coordinate[body] < slabCut_ ? 0 : 1) != slab) continue;
            touchRow(body);
        }
    };
    // Blocks are runs of consecutive islands, so each block's rows come out in one range.
    const std::uint32_t islandCount = islands->count();
    for (std::uint32_t k = 0; k < islandCount; ++k) {
        const std::uint32_t segment = segmentOfIsland_[k];
        if (segment == kLargeSegment) continue;
        if (segmentRows_[segment].end == 0) segmentRows_[segment].begin = rowCount();
        touchIsland(k, -1);
        segmentRows_[segment].end = rowCount();
    }
    const std::size_t firstLarge = segmentCount - 1 - slabSegments_;
    const std::uint32_t largeBegin = rowCount();
    for (int slab = slabSegments_ > 0 ? 0 : -1; slab < static_cast<int>(slabSegments_); ++slab) {
        const std::uint32_t slabBegin = rowCount();
        for (std::uint32_t k = 0; k < islandCount; ++k)
            if (segmentOfIsland_[k] == kLargeSegment && islandManifolds(k) > kLargeIslandManifolds)
                touchIsland(k, slab);
        if (slab >= 0) segmentRows_[firstLarge + static_cast<std::size_t>(slab)] = {slabBegin, rowCount()};
    }
    // The large part's manifolds (those that cross the slabs, when there are slabs) may touch any of its rows.
    segmentRows_[segmentCount - 1] = {largeBegin, rowCount()};
    if (anyHeld) touchSides(false);
}

bool ContactSolver::colourSegment(const Contacts& contacts, std::size_t segment) {
    SegmentColours& out = segmentColours_[segment];
    std::fill(std::begin(out.manifolds), std::end(out.manifolds), 0u);
    for (auto& counts : out.byPoints) std::fill(std::begin(counts), std::end(counts), 0u);
    std::uint32_t constraints = 0;
    bool rowsFound = true;
    const RowRange rows = segmentRows_[segment];
    const auto outside = [&](std::int32_t row) {
        return static_cast<std::uint32_t>(row) < rows.begin || static_cast<std::uint32_t>(row) >= rows.end;
    };
    for (std::uint32_t at = segmentStart_[segment]; at < segmentStart_[segment + 1]; ++at) {
        const std::uint32_t k = segmentManifolds_[at];
        const std::uint8_t traits = traits_[k];
        if ((traits & kTraitLeftOut) != 0) {
            segmentColor_[at] = kNoColor;
            continue;
        }
        const ContactPair& p = contacts.pairs[k];
        const bool dynA = (traits & kTraitDynamicA) != 0, dynB = (traits & kTraitDynamicB) != 0;
        const std::int32_t ia = dynA ? solverIndex_[p.a] : 0, ib = dynB ? solverIndex_[p.b] : 0;
        if ((dynA && outside(ia)) || (dynB && outside(ib))) {  // the islands did not list it here (colourSegments)
            rowsFound = false;
            segmentColor_[at] = kNoColor;
            continue;
        }
        std::uint64_t used = 0;
        if (dynA) used |= bodyColors_[static_cast<std::size_t>(ia)];
        if (dynB) used |= bodyColors_[static_cast<std::size_t>(ib)];
        std::uint32_t color = static_cast<std::uint32_t>(std::countr_one(used));
        if (color >= kMaxColors) {
            color = kOverflowColor;
        } else {
            if (dynA) bodyColors_[static_cast<std::size_t>(ia)] |= std::uint64_t{1} << color;
            if (dynB) bodyColors_[static_cast<std::size_t>(ib)] |= std::uint64_t{1} << color;
        }
        segmentColor_[at] = static_cast<std::uint8_t>(color);
        out.manifolds[color] += 1;
        out.byPoints[color][traits & kTraitPoints] += 1;
        constraints += 1;
    }
    out.constraints = constraints;
    return rowsFound;
}

void ContactSolver::colourSegments(const Contacts& contacts, const MovingBodies& m, TaskPool& pool) {
    const std::size_t segmentCount = segmentStart_.size() - 1;
    segmentColours_.resize(segmentCount);
    segmentColor_.resize(segmentManifolds_.size());
    // The blocks and slabs share no dynamic body, and each has rows of its own: they are coloured at once, each by
    // one task. The manifolds that cross the slabs share bodies with both: they are coloured after them, afresh.
    const std::size_t apart = slabSegments_ > 0 ? segmentCount - 1 : segmentCount;
    const auto colourAll = [&](TaskPool* parallel) {
        bodyColors_.assign(bodies_.moving.size(), 0);
        std::atomic<bool> rowsFound{true};
        const auto colour = [&](std::size_t, std::size_t begin, std::size_t end, int) {
            for (std::size_t segment = begin; segment < end; ++segment)
                if (!colourSegment(contacts, segment)) rowsFound.store(false, std::memory_order_relaxed);
        };
        if (parallel)
            parallel->forChunks(apart, 1, colour);
        else
            colour(0, 0, apart, 0);
        if (apart < segmentCount) {
            const std::size_t crossing = segmentCount - 1;
            for (std::uint32_t at = segmentStart_[crossing]; at < segmentStart_[crossing + 1]; ++at) {
                const ContactPair& p = contacts.pairs[segmentManifolds_[at]];
                if (!p.aStatic && solverIndex_[p.a] >= 0) bodyColors_[static_cast<std::size_t>(solverIndex_[p.a])] = 0;
                if (!p.bStatic && solverIndex_[p.b] >= 0) bodyColors_[static_cast<std::size_t>(solverIndex_[p.b])] = 0;
            }
            if (!colourSegment(contacts, crossing)) rowsFound = false;
        }
        return rowsFound.load();
    };
    if (colourAll(&pool)) return;
    // Islands built over other manifolds than these left a dynamic body without a row, or with a row in another
    // segment than one of its manifolds (two tasks would then solve it at once): every manifold in one segment
    // instead, its bodies in order of first appearance.
    partition(contacts, nullptr, m);
    assignRows(contacts, nullptr, m, false);
    colourAll(nullptr);
}

std::uint32_t ContactSolver::layOutColours() {
    colors_.clear();
    blocks_.clear();
    slabs_.clear();
    stats_ = {};
    const std::size_t segmentCount = segmentStart_.size() - 1;
    blockOfSegment_.assign(segmentCount, kLargeSegment);
    const std::size_t firstSlab = segmentCount - 1 - slabSegments_;
    std::uint32_t batchCount = 0;
    for (std::size_t segment = 0; segment < segmentCount; ++segment) {
        const bool largePart = segment + 1 == segmentCount;
        const bool slab = segment >= firstSlab && !largePart;
        SegmentColours& sc = segmentColours_[segment];
        // Every colour starts a fresh batch; the overflow colour comes last.
        const auto firstColor = static_cast<std::uint32_t>(colors_.size());
        for (std::uint32_t c = 0; c <= kMaxColors; ++c) {
            sc.firstBatch[c] = batchCount;
            if (sc.manifolds[c] == 0) continue;
            const auto n = static_cast<std::uint32_t>((sc.manifolds[c] + kBatchLanes - 1) / kBatchLanes);
            colors_.push_back({batchCount, n, c == kOverflowColor});
            batchCount += n;
        }
        const ColorSpan span{firstColor, static_cast<std::uint32_t>(colors_.size()) - firstColor};
        if (largePart) {
            large_ = span;
        } else if (slab) {
            if (span.colorCount > 0) slabs_.push_back(span);
        } else if (span.colorCount > 0) {
            blockOfSegment_[segment] = static_cast<std::uint32_t>(blocks_.size());
            blocks_.push_back(span);
        }
        stats_.constraints += sc.constraints;
        stats_.colors = std::max(stats_.colors, span.colorCount);
        if (largePart || slab) stats_.largeIslandConstraints += sc.constraints;
    }
    manifoldOfLane_.assign(std::size_t{batchCount} * kBatchLanes, ~0u);
    batchPoints_.assign(batchCount, 0);
    return batchCount;
}

void ContactSolver::fillLanes(TaskPool& pool) {
    pool.forChunks(segmentStart_.size() - 1, 1, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t segment = begin; segment < end; ++segment) {
            const SegmentColours& sc = segmentColours_[segment];
            // Per colour, manifolds by point count: a colour's lanes are filled with the manifolds of most points
            // first, so that batches of few-point manifolds stop early. Lanes of one colour share no dynamic body,
            // so their order within the colour does not change the result. The overflow colour is solved lane by
            // lane over shared bodies, so it keeps manifold order. `filled`: the next free lane per colour and
            // point count, counted from the colour's first lane.
            std::uint32_t filled[kMaxColors + 1][kMaxManifoldPoints + 1];
            for (std::uint32_t c = 0; c <= kMaxColors; ++c) {
                std::uint32_t at = 0;
                for (int points = kMaxManifoldPoints; points >= 0; --points) {
                    filled[c][points] = at;
                    if (c != kOverflowColor) at += sc.byPoints[c][points];
                }
            }
            for (std::uint32_t at = segmentStart_[segment]; at < segmentStart_[segment + 1]; ++at) {
                const std::uint8_t c = segmentColor_[at];
                if (c == kNoColor) continue;
                const std::uint32_t k = segmentManifolds_[at];
                const int points = traits_[k] & kTraitPoints;
                const std::size_t slot =
                    std::size_t{sc.firstBatch[c]} * kBatchLanes + filled[c][c == kOverflowColor ? 0 : points]++;
                manifoldOfLane_[slot] = k;
                laneOfManifold_[k] = static_cast<std::uint32_t>(slot);
                std::uint8_t& most = batchPoints_[slot / kBatchLanes];
                most = std::max(most, static_cast<std::uint8_t>(points));
            }
        }
    });
}

}  // namespace rubble::detail
