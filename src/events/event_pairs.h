#pragma once
// Pairs of bodies as the events name them (by slot and generation, so that a body reusing a slot is another body),
// and the set of such pairs that holds from one step to the next, whose difference is the begin and end events.
#include <algorithm>
#include <compare>
#include <cstdint>
#include <vector>

#include "storage/body_storage.h"

namespace rubble::detail {

struct EventPair {
    std::uint64_t slots = 0;        ///< first slot << 32 | second slot
    std::uint64_t generations = 0;  ///< in the same order
    friend auto operator<=>(const EventPair&, const EventPair&) = default;

    BodyId first() const { return {static_cast<unsigned>(slots >> 32), static_cast<unsigned>(generations >> 32)}; }
    BodyId second() const { return {static_cast<unsigned>(slots), static_cast<unsigned>(generations)}; }
};

inline EventPair eventPair(BodyId first, BodyId second) {
    return {std::uint64_t{first.index} << 32 | second.index, std::uint64_t{first.generation} << 32 | second.generation};
}

/// The pair with the lower slot first (contacts have no sides).
inline EventPair unorderedEventPair(BodyId x, BodyId y) {
    return x.index < y.index ? eventPair(x, y) : eventPair(y, x);
}

/// The flags of the body at `dense` in its set (kFlagContactEvents, kFlagSensor, kFlagNoResponse for either set).
inline std::uint8_t bodyFlags(const BodyStorage& storage, std::uint32_t dense, bool isStatic) {
    return isStatic ? storage.statics.flags[dense] : storage.moving.flags[dense];
}

/// A body of a pair is still there and stays where it is without being stepped: static, or asleep. A pair the step
/// did not find again but whose bodies are all such still touches: the broad phase skips pairs of sleeping bodies.
inline bool restsUnstepped(const BodyStorage& storage, BodyId id) {
    const BodySlot* slot = storage.find(id);
    if (slot == nullptr) return false;
    return slot->set == BodySet::Static || (storage.moving.flags[slot->dense] & kFlagAsleep) != 0;
}

/// The pairs that held after the last report. update() takes this step's pairs and tells what began and ended.
class HeldPairs {
public:
    /// `now` is this step's pairs, sorted and unique. Calls begin(pair) for each pair of `now` that did not hold, in
    /// order, then end(pair) for each that held and is not in `now`, in order, unless both its bodies rest unstepped
    /// (then it still holds). `now` is left holding what holds after the step.
    template <class Begin, class End>
    void update(const BodyStorage& storage, std::vector<EventPair>& now, Begin&& begin, End&& end) {
        std::size_t i = 0;
        for (const EventPair& p : now) {
            while (i < held_.size() && held_[i] < p) ++i;
            if (i == held_.size() || held_[i] != p) begin(p);
        }
        const std::size_t found = now.size();
        std::size_t j = 0;
        for (const EventPair& p : held_) {
            while (j < found && now[j] < p) ++j;
            if (j < found && now[j] == p) continue;
            if (restsUnstepped(storage, p.first()) && restsUnstepped(storage, p.second()))
                now.push_back(p);
            else
                end(p);
        }
        if (now.size() > found)
            std::inplace_merge(now.begin(), now.begin() + static_cast<std::ptrdiff_t>(found), now.end());
        held_.swap(now);
    }
    /// update() with the begins and ends appended to `begins` and `ends` as {first, second} events.
    template <class BeginEvent, class EndEvent>
    void update(const BodyStorage& storage, std::vector<EventPair>& now, std::vector<BeginEvent>& begins,
                std::vector<EndEvent>& ends) {
        update(
            storage, now,
            [&](const EventPair& p) {
                begins.push_back({p.first(), p.second()});
            },
            [&](const EventPair& p) {
                ends.push_back({p.first(), p.second()});
            });
    }
    bool empty() const { return held_.empty(); }

private:
    std::vector<EventPair> held_;
};

}  // namespace rubble::detail
