#pragma once
// Sensors (BodyDef::sensor): bodies that report what overlaps them and push nothing. Their pairs come through the
// broad and narrow phases like any other (so a sensor costs what a body costs there, and its collision filter
// applies); right after the narrow phase their manifolds leave the step's contacts, before the contact cache, the
// islands and the solver see them, and the pairs with a point of positive depth are the sensor's overlaps.
#include <cstdint>
#include <vector>

#include "contacts/contacts.h"
#include "events/event_pairs.h"
#include "rubble/events.h"
#include "storage/body_storage.h"

namespace rubble::detail {

class SensorEventStage {
public:
    /// False when there is no sensor or body without contact response and no overlap is held: then neither call
    /// needs to run.
    bool active(std::uint32_t separatedBodies) const { return separatedBodies > 0 || !overlaps_.empty(); }

    /// First substep, after the narrow phase: takes every manifold with a sensor side, or a side without contact
    /// response, out of `contacts` (the others keep their order) and keeps the pairs of a sensor and a body that is
    /// not one which overlap. Returns how many manifolds it took out.
    std::uint32_t separate(Contacts& contacts, const BodyStorage& storage);
    /// After the step: the overlaps that began and ended since the last report, appended to `out`.
    void report(const BodyStorage& storage, SensorEvents& out);

private:
    std::vector<EventPair> now_;  ///< (sensor, visitor) pairs found this step
    HeldPairs overlaps_;
};

}  // namespace rubble::detail
