#pragma once
// Sleeping per island, the second half of the islands stage (only in scenes that declare Effect::Sleeping).
//
// Each dynamic body has a sleep timer: how long it has rested (rubble::SleepSettings). After the step, an island
// whose bodies have all rested for timeToSleep falls asleep whole: its bodies get the asleep flag and zero
// velocity, and its manifolds leave the step for a "sleeping island" kept here, with their final impulses. While
// asleep its bodies are not integrated, the broad phase skips pairs of two sleeping bodies (or a sleeping and a
// static one), so the narrow phase, the contact cache and the solver never see its contacts.
//
// Waking is per island too. In the step, the union-find joins every body of a sleeping island that a manifold or a
// joint of the step touches (its members are linked by extra edges), so an awake body that touches one of them
// lands in the same island, and the islands no one touches cost nothing; an island that holds
// an awake body, or touches a moving kinematic body, wakes whole, and its kept manifolds come back into the step's
// contacts with their impulses, so that a woken stack is solved as it was left. Between steps the API wakes a body's
// island (forces, impulses, velocities, transforms, removal of a body it rests on); its kept manifolds then go to
// the contact cache, so that the next step's manifolds warm-start from them.
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "bounds/bounds.h"
#include "contacts/contact_cache.h"
#include "integrate/integrate.h"
#include "islands/islands.h"
#include "rubble/settings.h"
#include "storage/slot_map.h"

namespace rubble::detail {

class TaskPool;

class SleepingIslands {
public:
    /// Appends to `edges` the edges that hold together each sleeping island this step may wake (dense indices):
    /// those with a body that is a side of one of this step's manifolds or of an extra edge already in `edges` whose
    /// other side is awake. The others stay out of the union-find, so a world that sleeps costs the islands stage
    /// nothing for its sleepers (a sleeping island wakes only through a body that touches it).
    void linkSleepingIslands(const BodyStorage& storage, const Contacts& contacts, TaskPool& pool,
                             std::vector<IslandEdge>& edges);
    /// In the step, after the islands are built: an island that holds a sleeping body wakes whole when it also holds
    /// an awake body or touches a moving kinematic body. The kept manifolds of woken islands are appended to this
    /// step's contacts and impulses. Returns whether any were, in which case the islands' manifold rows are stale.
    bool wakeTouched(const Islands& islands, BodyStorage& storage, IntegrationScratch& integration, Contacts& contacts,
                     std::vector<PointImpulse>& impulses, ContactCache& cache, TaskPool& pool);
    /// After the step: sleep timers, and islands that have rested for timeToSleep fall asleep, their manifolds kept.
    void fallAsleep(const Islands& islands, const Contacts& contacts, const std::vector<PointImpulse>& impulses,
                    const ContactCache& cache, BodyStorage& storage, const ShapeBoundsTable& shapes,
                    const SleepSettings& settings, float dt, TaskPool& pool);

    /// Between steps: wakes the sleeping island of moving body `dense` (nothing if it is awake).
    void wake(std::uint32_t dense, BodyStorage& storage);
    /// Between steps: wakes the sleeping islands that touch body `slot` (about to be removed or moved), found among
    /// the kept manifolds and last step's contacts.
    void wakeTouching(std::uint32_t slot, BodyStorage& storage, const ContactCache& cache);
    /// Wakes every sleeping island (the Sleeping effect was turned off).
    void wakeAll(BodyStorage& storage);
    /// At the start of a step: the kept manifolds of islands woken between steps go to the contact cache.
    void flushWarmStarts(ContactCache& cache);

    std::uint32_t sleepingBodies() const { return sleepingBodies_; }
    /// The bodies that fell asleep or woke since the last clearSleepChanges(), for the broad phase's tree of sleepers
    /// and the sleepers' kept boxes.
    SleepChanges sleepChanges() const { return {changedSlots_, changesOverflowed_}; }
    void clearSleepChanges() {
        changedSlots_.clear();
        changesOverflowed_ = false;
    }
    /// The kept manifolds of moving body `dense`'s sleeping island (bodies named by slot); empty when it is awake.
    std::span<const KeptManifold> keptManifolds(std::uint32_t dense, const BodyStorage& storage) const {
        if (!(storage.moving.flags[dense] & kFlagAsleep)) return {};
        return groups_[storage.moving.sleepGroup[dense]].manifolds;
    }
    /// Calls fn(const KeptManifold&) for the kept manifolds of every sleeping island.
    template <class Fn>
    void forEachKeptManifold(Fn&& fn) const {
        for (std::uint32_t g = 0; g < groups_.size(); ++g)
            if (groupIds_.alive(g))
                for (const KeptManifold& k : groups_[g].manifolds) fn(k);
    }

private:
    struct Group {
        std::vector<std::uint32_t> slots;  ///< its bodies
        std::vector<KeptManifold> manifolds;
    };
    using GroupId = Handle<Group>;
    /// Wakes group g and appends its kept manifolds to `out`.
    void wakeGroup(std::uint32_t g, BodyStorage& storage, std::vector<KeptManifold>& out);
    /// Fills sleepingPartners_ from the kept manifolds and last step's contacts.
    void indexSleepingPartners(const BodyStorage& storage, const ContactCache& cache);
    /// Lists a body that fell asleep or woke (its slot), up to a bound that keeps an undrained list from growing.
    void noteChange(std::uint32_t slot);

    SlotMap<GroupId> groupIds_;
    std::vector<Group> groups_;  ///< by group slot
    std::vector<KeptManifold> pendingWarmStarts_;
    std::vector<std::uint8_t> touchedByKinematic_;  ///< per island of the step: touches a moving kinematic body
    std::vector<std::vector<std::uint32_t>> chunkIslands_;
    std::vector<std::vector<std::uint32_t>> chunkLone_;      ///< per chunk of bodies: those that fall asleep alone
    std::vector<std::vector<std::uint32_t>> chunkTouching_;  ///< per chunk of manifolds: their sleeping sides
    std::vector<KeptManifold> restored_;
    /// Between steps, (slot, slot of a sleeping body it touches) sorted by the first: a game that removes a thousand
    /// bodies a step looks each one's sleeping partners up here instead of scanning every contact a thousand times.
    /// Built by the first wakeTouching after a step; bodies only fall asleep in a step, so until the next one it
    /// lists every sleeping partner (and some that have woken since, which waking again leaves as they are).
    std::vector<std::pair<std::uint32_t, std::uint32_t>> sleepingPartners_;
    bool sleepingPartnersIndexed_ = false;
    std::uint32_t sleepingBodies_ = 0;
    std::vector<std::uint32_t> changedSlots_;
    bool changesOverflowed_ = false;
    /// linkSleepingIslands: per group, the last call that linked it (so each is linked once), and that call's number.
    std::vector<std::uint64_t> groupLinkedAt_;
    std::uint64_t linkCalls_ = 0;
};

}  // namespace rubble::detail
