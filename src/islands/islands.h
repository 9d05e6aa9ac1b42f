#pragma once
// The islands stage: union-find over the constraint graph of one step. Moving dynamic bodies are the nodes; every
// manifold between two of them and every extra edge (joints) is an edge. Static, kinematic and frozen bodies do not
// join islands (as in Box2D and Jolt): a floor or a moving platform would otherwise glue everything it carries into
// one island. An island is the unit that falls asleep and wakes (islands_sleep.h), and the unit the solver can
// schedule as one task.
//
// Only the bodies the step constrains are listed: those with a manifold or an extra edge. A body that touches
// nothing is an island of its own that nothing reads (sleep handles such bodies by themselves), so a world of a
// million sparse bodies pays for its contacts, not its bodies.
//
// The partition is unique; islands are labelled canonically so that nothing downstream depends on the thread count:
// an island is named by its smallest dense body index, islands are numbered in the order of those names, and each
// island's bodies and manifolds are listed in ascending index order.
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "broadphase/radix_sort.h"
#include "contacts/contacts.h"
#include "storage/aligned_vector.h"
#include "storage/body_storage.h"

namespace rubble::detail {

class TaskPool;

inline constexpr std::uint32_t kNoIsland = ~0u;

/// An edge given by the dense indices of two moving bodies (joints).
using IslandEdge = std::pair<std::uint32_t, std::uint32_t>;

/// Dynamic bodies join islands, awake or asleep; kinematic and frozen ones do not.
inline bool joinsIslands(std::uint8_t flags) { return (flags & (kFlagKinematic | kFlagFrozen)) == 0; }

/// The islands of one step, in canonical order (see above), as compressed rows.
struct Islands {
    /// Per moving body (dense index): its island, or kNoIsland (no manifold or edge, kinematic or frozen). Only the
    /// listed bodies hold an island, so the next build clears just those.
    std::vector<std::uint32_t> islandOf;
    std::vector<std::uint32_t> bodyStart;      ///< island k's bodies are bodies[bodyStart[k], bodyStart[k + 1])
    std::vector<std::uint32_t> bodies;         ///< dense indices, ascending within an island
    std::vector<std::uint32_t> manifoldStart;  ///< island k's manifolds are manifolds[manifoldStart[k], ...[k + 1])
    /// Manifold indices, ascending within an island. A manifold belongs to the island of its dynamic body; one with
    /// no dynamic body that joins islands (kinematic against static, say) belongs to none.
    std::vector<std::uint32_t> manifolds;
    std::uint32_t largest = 0;  ///< body count of the largest island

    std::uint32_t count() const { return bodyStart.empty() ? 0 : static_cast<std::uint32_t>(bodyStart.size() - 1); }
};

class IslandBuilder {
public:
    /// Islands of the moving bodies joined by `contacts` and `extraEdges`, in parallel: the constrained bodies are
    /// listed as the edges are read, a lock-free union-find links the larger root under the smaller by
    /// compare-and-swap (so every root is its island's smallest index, whatever order the links happen in), islands
    /// are numbered by parallel chunked prefix sums, then the rows come from a counting sort. Every pass runs over
    /// the edges or the constrained bodies, none over all bodies.
    void build(const Contacts& contacts, std::span<const IslandEdge> extraEdges, const MovingBodies& bodies,
               TaskPool& pool, Islands& out);
    /// The same result on one thread with a plain union-find: the reference the parallel build is tested and
    /// measured against.
    static void buildSerial(const Contacts& contacts, std::span<const IslandEdge> extraEdges,
                            const MovingBodies& bodies, Islands& out);
    /// Recomputes only the manifold rows (after manifolds were appended to `contacts`; the bodies' islands stand).
    static void assignManifolds(const Contacts& contacts, Islands& out);

private:
    /// Per moving body: its union-find parent. Every body is its own parent between builds (a build resets the
    /// bodies it listed), so a build never initialises all of them.
    std::vector<std::uint32_t> parent_;
    std::vector<std::uint32_t> rank_;  ///< at a root: its island's number
    std::vector<std::uint32_t> chunkCounts_;
    std::vector<std::vector<std::uint32_t>> chunkMembers_;  ///< per chunk of edges: the sides it listed
    std::vector<std::uint32_t> members_;                    ///< the last build's constrained bodies, ascending
    AlignedVector<std::uint64_t> sortItems_;
    RadixSortScratch sortScratch_;
};

}  // namespace rubble::detail
