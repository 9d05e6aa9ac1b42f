// How the contact solver splits the step's manifolds into the segments it solves apart: blocks of small islands, the
// slabs of large islands and the manifolds that cross them (ContactSolver::partition and splitIntoSlabs). Kept apart
// from contact_solver.cpp, whose kernels GCC inlines within a growth budget for the whole file: there, this code
// cost S5's solver 3% at one thread.
#include "solver/contact_solver.h"

#include <algorithm>
#include <cmath>

#include "islands.h"

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
    for (std::size_t i = 0; i < slabPlaces_.size(); ++i) slabKeys_[i] = (&slabPlaces_[i].x)[axis];
    const auto middle = slabKeys_.begin() + static_cast<std::ptrdiff_t>(slabKeys_.size() / 2);
    std::nth_element(slabKeys_.begin(), middle, slabKeys_.end());
    const float cut = *middle;
    if (!(cut > (&lo.x)[axis] && cut <= (&hi.x)[axis])) {  // every place the same (or not finite): nothing to cut
        appendLarge(largePart_.data(), largePart_.size());
        return;
    }
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

}  // namespace rubble::detail
