#include "storage/body_storage.h"

#include <cassert>
#include <type_traits>
#include <utility>

#include "core/parallel.h"

namespace rubble::detail {
namespace {

// Applies `op` to every per-body array of a set, so push and swap-remove cannot forget a field.
template <class Bodies, class Op>
requires std::is_same_v<std::remove_const_t<Bodies>, MovingBodies>
void forEachArray(Bodies& b, Op&& op) {
    for (auto* a : {&b.px,
                    &b.py,
                    &b.pz,
                    &b.qx,
                    &b.qy,
                    &b.qz,
                    &b.qw,
                    &b.vx,
                    &b.vy,
                    &b.vz,
                    &b.wx,
                    &b.wy,
                    &b.wz,
                    &b.fx,
                    &b.fy,
                    &b.fz,
                    &b.tx,
                    &b.ty,
                    &b.tz,
                    &b.invMass,
                    &b.invIx,
                    &b.invIy,
                    &b.invIz,
                    &b.irx,
                    &b.iry,
                    &b.irz,
                    &b.irw,
                    &b.iwXX,
                    &b.iwYY,
                    &b.iwZZ,
                    &b.iwXY,
                    &b.iwXZ,
                    &b.iwYZ,
                    &b.linearDamping,
                    &b.angularDamping,
                    &b.gravityScale,
                    &b.lcx,
                    &b.lcy,
                    &b.lcz,
                    &b.friction,
                    &b.restitution,
                    &b.density,
                    &b.sleepTimer})
        op(*a);
    op(b.sleepGroup);
    op(b.shape);
    op(b.filterCategory);
    op(b.filterMask);
    op(b.userData);
    op(b.flags);
    op(b.slot);
}

template <class Bodies, class Op>
requires std::is_same_v<std::remove_const_t<Bodies>, StaticBodies>
void forEachArray(Bodies& b, Op&& op) {
    for (auto* a : {&b.px, &b.py, &b.pz, &b.qx, &b.qy, &b.qz, &b.qw, &b.friction, &b.restitution, &b.density}) op(*a);
    op(b.shape);
    op(b.filterCategory);
    op(b.filterMask);
    op(b.userData);
    op(b.flags);
    op(b.slot);
}

template <class Set>
std::uint32_t pushBackImpl(Set& set) {
    const std::uint32_t dense = set.size();
    forEachArray(set, [](auto& a) { a.emplace_back(); });
    return dense;
}

template <class Set>
std::uint32_t swapRemoveImpl(Set& set, std::uint32_t dense) {
    const std::uint32_t last = set.size() - 1;
    assert(dense <= last);
    const std::uint32_t movedSlot = dense == last ? ~0u : set.slot[last];
    forEachArray(set, [&](auto& a) {
        if (dense != last) a[dense] = a[last];
        a.pop_back();
    });
    return movedSlot;
}

}  // namespace

std::uint32_t MovingBodies::pushBack() { return pushBackImpl(*this); }
std::uint32_t MovingBodies::swapRemove(std::uint32_t dense) { return swapRemoveImpl(*this, dense); }
std::uint32_t StaticBodies::pushBack() { return pushBackImpl(*this); }
std::uint32_t StaticBodies::swapRemove(std::uint32_t dense) { return swapRemoveImpl(*this, dense); }

BodyId BodyStorage::allocate(BodySet set, std::uint32_t& denseOut) {
    const BodyId id = ids_.acquire();
    const std::uint32_t slotIndex = id.index;
    if (slotIndex == slots_.size()) slots_.push_back({});
    ++layoutChanges_;
    BodySlot& slot = slots_[slotIndex];
    slot.set = set;
    slot.dense = set == BodySet::Moving ? moving.pushBack() : statics.pushBack();
    if (set == BodySet::Moving)
        moving.slot[slot.dense] = slotIndex;
    else
        statics.slot[slot.dense] = slotIndex;
    denseOut = slot.dense;
    return id;
}

void BodyStorage::release(BodyId id) {
    ++layoutChanges_;
    BodySlot& slot = slots_[id.index];
    if (slot.set == BodySet::Moving) ++movingRowMoves_;
    const std::uint32_t moved =
        slot.set == BodySet::Moving ? moving.swapRemove(slot.dense) : statics.swapRemove(slot.dense);
    if (moved != ~0u) slots_[moved].dense = slot.dense;
    ids_.release(id.index);
}

void BodyStorage::reorderMoving(const std::uint32_t* order, TaskPool& pool) {
    const std::size_t n = moving.size();
    // Sized so that each worker's share of one array is a few pages: the reads follow `order`, the writes stream.
    constexpr std::size_t kChunk = 16384;
    ReorderScratch& scratch = reorderScratch_;
    const auto spareFor = [&](auto& array) -> auto& {
        using Array = std::remove_reference_t<decltype(array)>;
        if constexpr (std::is_same_v<Array, AlignedVector<float>>)
            return scratch.floats;
        else if constexpr (std::is_same_v<Array, std::vector<std::uint32_t>>)
            return scratch.words;
        else if constexpr (std::is_same_v<Array, std::vector<std::uint64_t>>)
            return scratch.longs;
        else
            return scratch.bytes;
    };
    forEachArray(moving, [&](auto& array) {
        auto& spare = spareFor(array);
        static_assert(
            std::is_same_v<std::remove_reference_t<decltype(spare)>, std::remove_reference_t<decltype(array)>>);
        spare.resize(n);
        pool.forChunks(n, kChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
            for (std::size_t k = begin; k < end; ++k) spare[k] = array[order[k]];
        });
        // The old array becomes the spare for the next array of its type.
        std::swap(array, spare);
    });
    for (std::uint32_t k = 0; k < n; ++k) slots_[moving.slot[k]].dense = k;
    ++layoutChanges_;
    ++movingRowMoves_;
}

const BodySlot* BodyStorage::find(BodyId id) const { return ids_.contains(id) ? &slots_[id.index] : nullptr; }

std::string BodyStorage::checkInvariants() const {
    std::string problem;
    auto checkLengths = [&](auto& set, const char* name) {
        forEachArray(set, [&](const auto& a) {
            if (a.size() != set.slot.size() && problem.empty())
                problem = std::string(name) + ": an array has " + std::to_string(a.size()) + " rows, not " +
                          std::to_string(set.slot.size());
        });
    };
    checkLengths(moving, "moving bodies");
    checkLengths(statics, "static bodies");
    std::uint32_t alive = 0;
    for (std::uint32_t s = 0; s < slots_.size() && problem.empty(); ++s) {
        if (!ids_.alive(s)) continue;
        const BodySlot& slot = slots_[s];
        ++alive;
        const auto& back = slot.set == BodySet::Moving ? moving.slot : statics.slot;
        if (slot.dense >= back.size() || back[slot.dense] != s)
            problem = "slot " + std::to_string(s) + " points at row " + std::to_string(slot.dense) +
                      ", which does not point back";
    }
    if (problem.empty() && alive != count())
        problem = std::to_string(alive) + " live slots for " + std::to_string(count()) + " rows";
    return problem;
}

}  // namespace rubble::detail
