#pragma once
// One slot map for every kind of object a world owns (bodies, shapes, joints, sleeping groups): which slots are
// taken, the generation of each slot's occupant, the free list. What a slot holds lives with its owner, indexed by
// the slot (a body's row, a shape, a joint). A freed slot is the next one taken (last in, first out) and its
// generation moves on, so every handle to the old occupant goes stale.
#include <cstdint>
#include <vector>

#include "rubble/id.h"

namespace rubble::detail {

template <class Id>
class SlotMap {
public:
    /// Takes a slot for a new occupant: the most recently freed one, else a new one at index size().
    Id acquire() {
        std::uint32_t index;
        if (!free_.empty()) {
            index = free_.back();
            free_.pop_back();
        } else {
            index = static_cast<std::uint32_t>(slots_.size());
            slots_.push_back({});
        }
        Slot& s = slots_[index];
        s.generation += 1;
        if (s.generation == 0) s.generation = 1;  // 0 is the null handle; wrapping after 4 billion reuses is fine
        s.alive = true;
        return Id{index, s.generation};
    }

    void release(std::uint32_t index) {
        slots_[index].alive = false;
        free_.push_back(index);
    }

    /// False for a null handle, one out of range, or one whose occupant has left.
    bool contains(Id id) const {
        return !id.isNull() && id.index < slots_.size() && slots_[id.index].alive &&
               slots_[id.index].generation == id.generation;
    }
    bool alive(std::uint32_t index) const { return slots_[index].alive; }
    /// The handle of the slot's current (or last) occupant.
    Id idAt(std::uint32_t index) const { return Id{index, slots_[index].generation}; }
    /// Slots ever taken, live or free.
    std::uint32_t size() const { return static_cast<std::uint32_t>(slots_.size()); }

private:
    struct Slot {
        std::uint32_t generation = 0;
        bool alive = false;
    };
    std::vector<Slot> slots_;
    std::vector<std::uint32_t> free_;
};

}  // namespace rubble::detail
