#pragma once
// Broad phase: from the fattened AABBs of the moving bodies and the static set to a duplicate-free list of
// candidate pairs. Moving-moving pairs come from sweep-and-prune or the multi-resolution grid; moving-static pairs
// (static bodies and the triangles of static meshes and heightfields) from the static BVH. Static-static pairs
// never exist. The final lists are in a canonical order that does not depend on the algorithm or thread count.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "rubble/limits.h"
#include "storage/aligned_vector.h"

namespace rubble::detail {

/// Axis-aligned boxes in SoA form, indexed by dense body index.
struct Bounds {
    AlignedVector<float> minX, minY, minZ, maxX, maxY, maxZ;

    std::uint32_t size() const { return static_cast<std::uint32_t>(minX.size()); }
    void resize(std::size_t n) {
        for (auto* a : {&minX, &minY, &minZ, &maxX, &maxY, &maxZ}) a->resize(n);
    }
};

/// The one overlap predicate of the broad phase: closed intervals, so touching boxes overlap.
inline bool overlaps(const Bounds& a, std::uint32_t i, const Bounds& b, std::uint32_t j) {
    return a.minX[i] <= b.maxX[j] && b.minX[j] <= a.maxX[i] && a.minY[i] <= b.maxY[j] && b.minY[j] <= a.maxY[i] &&
           a.minZ[i] <= b.maxZ[j] && b.minZ[j] <= a.maxZ[i];
}

/// A candidate pair. Moving-moving: dense indices of two moving bodies with a < b. Moving-static: a is a moving
/// body's dense index, b a static body's dense index.
struct BodyPair {
    std::uint32_t a = 0;
    std::uint32_t b = 0;
    friend bool operator==(BodyPair x, BodyPair y) { return x.a == y.a && x.b == y.b; }
    friend bool operator<(BodyPair x, BodyPair y) { return x.a != y.a ? x.a < y.a : x.b < y.b; }
};

/// A moving body against a static mesh or heightfield: the triangles whose boxes its box overlaps are
/// meshTriangles[firstTriangle .. firstTriangle + triangleCount), ascending.
struct MeshPair {
    std::uint32_t moving = 0;
    std::uint32_t staticBody = 0;  ///< dense index in StaticBodies
    std::uint32_t firstTriangle = 0;
    std::uint32_t triangleCount = 0;
};

/// Whether two bodies may touch: each one's category in the other's mask.
inline bool filtersAccept(std::uint32_t categoryA, std::uint32_t maskA, std::uint32_t categoryB, std::uint32_t maskB) {
    return (categoryA & maskB) != 0 && (categoryB & maskA) != 0;
}

/// Which pairs may become contacts: each body's category must be in the other's mask, and a pair of two sleeping
/// bodies is skipped (a static body counts as sleeping). Null arrays mean "everything collides, nobody sleeps".
struct PairFilter {
    const std::uint32_t* category = nullptr;  ///< of moving bodies, dense order
    const std::uint32_t* mask = nullptr;
    const std::uint8_t* flags = nullptr;  ///< of moving bodies; `asleepBit` set means asleep
    std::uint8_t asleepBit = 0;

    bool asleep(std::uint32_t i) const { return flags != nullptr && (flags[i] & asleepBit) != 0; }
    bool accepts(std::uint32_t a, std::uint32_t b) const {
        if (category != nullptr && !filtersAccept(category[a], mask[a], category[b], mask[b])) return false;
        return !(asleep(a) && asleep(b));
    }
};

/// The pair budget (docs/limits.md): a search splits its work into chunks that depend on the body count only, and
/// each chunk keeps at most its cap of pairs; pairs past it are counted, not kept. So memory stays bounded (about
/// 2 x kPairsPerBody pairs a body) when bodies pile onto one point, and what is kept does not depend on the threads.
/// Time stays bounded too: once its chunk's cap is full, a body's search stops after meeting overlapsPerBody
/// overlapping boxes and counts the candidates it leaves untested as dropped, so a pile of n bodies at one point
/// costs time linear in n rather than n^2 / 2 tests. Until the cap is full every search is exact, however many
/// boxes one body overlaps (a platform under a thousand crates). A chunk that overflowed searches again with its
/// cap shared evenly among its bodies (ChunkPairs::keepPerBody).
struct PairBudget {
    std::size_t perBody = limits::kPairsPerBody;
    std::size_t minPerChunk = limits::kMinChunkPairs;
    std::size_t overlapsPerBody = limits::kSearchOverlapsPerBody;

    /// For tests that check a search against brute force on piles no world would hold.
    static PairBudget unlimited() {
        constexpr std::size_t kHuge = SIZE_MAX / (std::size_t{1} << 32);
        return {kHuge, kHuge, kHuge};
    }
    std::size_t chunkCap(std::size_t bodies, std::size_t chunks) const {
        const std::size_t share = chunks > 0 ? bodies * perBody / chunks : 0;
        return std::max(share, minPerChunk);
    }
};

/// One chunk's pairs under the budget, and the search of the body it is at. A chunk first searches exactly; if it
/// overflows its cap, it searches again with the cap shared evenly among its bodies (`keepPerBody`), so that the pairs
/// of a pile spread over its bodies instead of tying the first few to all the others.
struct ChunkPairs {
    std::vector<BodyPair>& pairs;
    std::size_t cap;
    std::size_t overlapsPerBody;
    /// The pairs one body's search keeps once the chunk has overflowed (else no limit).
    std::size_t keepPerBody = SIZE_MAX;
    /// Pairs past the chunk's cap or a body's share of it, and candidates left untested past them.
    std::uint64_t dropped = 0;
    std::size_t bodyOverlaps = 0;  ///< overlapping boxes the current body's search met
    std::size_t bodyKept = 0;      ///< pairs it kept

    void startBody() { bodyOverlaps = bodyKept = 0; }
    /// The current body has met its share of overlaps and can keep no more pairs: the caller skips the rest.
    bool bodyDone() const {
        return bodyOverlaps >= overlapsPerBody && (pairs.size() >= cap || bodyKept >= keepPerBody);
    }
    void skip(std::uint64_t candidates) { dropped += candidates; }
    /// An overlapping box the current body met; `accepted`: the filter lets the pair become a contact.
    void add(BodyPair p, bool accepted) {
        ++bodyOverlaps;
        if (!accepted) return;
        if (pairs.size() < cap && bodyKept < keepPerBody) {
            pairs.push_back(p);
            ++bodyKept;
        } else {
            ++dropped;
        }
    }
};

/// The broad phase's output.
struct CandidatePairs {
    std::vector<BodyPair> moving;  ///< sorted by (a, b)
    /// Moving vs static bodies whose shape is not a mesh or heightfield, ordered by (a, static body slot).
    std::vector<BodyPair> statics;
    std::vector<MeshPair> meshes;  ///< ordered by (moving, static body slot)
    std::vector<std::uint32_t> meshTriangles;
    /// Moving pairs past the pair budget, not kept or not tested (docs/limits.md); 0 in any sane scene.
    std::uint64_t droppedMoving = 0;
    /// Static candidates past the static budget and not kept (docs/limits.md); 0 in any sane scene.
    std::uint64_t droppedStatic = 0;

    void clear() {
        droppedMoving = 0;
        droppedStatic = 0;
        moving.clear();
        statics.clear();
        meshes.clear();
        meshTriangles.clear();
    }
};

}  // namespace rubble::detail
