#include "events/sensor_events.h"

#include <algorithm>

namespace rubble::detail {

namespace {

BodyId idOf(const BodyStorage& storage, std::uint32_t dense, bool isStatic) {
    return storage.idAt(isStatic ? storage.statics.slot[dense] : storage.moving.slot[dense]);
}

bool overlaps(const Manifold& manifold) {
    for (int i = 0; i < manifold.pointCount; ++i)
        if (manifold.points[i].depth > 0) return true;
    return false;
}

}  // namespace

std::uint32_t SensorEventStage::separate(Contacts& contacts, const BodyStorage& storage) {
    const std::size_t n = contacts.manifolds.size();
    std::size_t kept = 0;
    std::uint32_t points = 0;
    for (std::size_t k = 0; k < n; ++k) {
        const ContactPair& pair = contacts.pairs[k];
        const std::uint8_t flagsA = bodyFlags(storage, pair.a, pair.aStatic);
        const std::uint8_t flagsB = bodyFlags(storage, pair.b, pair.bStatic);
        if (!((flagsA | flagsB) & (kFlagSensor | kFlagNoResponse))) {
            if (kept != k) {
                contacts.pairs[kept] = pair;
                contacts.manifolds[kept] = contacts.manifolds[k];
            }
            points += static_cast<std::uint32_t>(contacts.manifolds[kept].pointCount);
            ++kept;
            continue;
        }
        // Sensors do not see each other; a pair with a body without response and no sensor is simply not solved.
        const bool sensorA = (flagsA & kFlagSensor) != 0, sensorB = (flagsB & kFlagSensor) != 0;
        if (sensorA == sensorB) continue;
        if (!overlaps(contacts.manifolds[k])) continue;
        const BodyId a = idOf(storage, pair.a, pair.aStatic), b = idOf(storage, pair.b, pair.bStatic);
        now_.push_back(sensorA ? eventPair(a, b) : eventPair(b, a));
    }
    contacts.pairs.resize(kept);
    contacts.manifolds.resize(kept);
    contacts.pointCount = points;
    return static_cast<std::uint32_t>(n - kept);
}

void SensorEventStage::report(const BodyStorage& storage, SensorEvents& out) {
    // A sensor overlaps a mesh in several triangles, a compound in several children: one pair each.
    std::sort(now_.begin(), now_.end());
    now_.erase(std::unique(now_.begin(), now_.end()), now_.end());
    overlaps_.update(storage, now_, out.begins, out.ends);
    now_.clear();
}

}  // namespace rubble::detail
