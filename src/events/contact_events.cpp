#include "events/contact_events.h"

#include <algorithm>

#include "core/parallel.h"

namespace rubble::detail {

namespace {

constexpr std::size_t kManifoldChunk = 4096;

bool listens(const BodyStorage& storage, const ContactPair& pair) {
    return ((bodyFlags(storage, pair.a, pair.aStatic) | bodyFlags(storage, pair.b, pair.bStatic)) &
            kFlagContactEvents) != 0;
}

/// A moving body's centre of mass and velocities (zero for a static body).
struct BodyMotion {
    Vec3 center, linear, angular;
    Vec3 velocityAt(Vec3 point) const { return linear + cross(angular, point - center); }
};

BodyMotion motionOf(const MovingBodies& m, std::uint32_t i) {
    return {{m.px[i], m.py[i], m.pz[i]}, {m.vx[i], m.vy[i], m.vz[i]}, {m.wx[i], m.wy[i], m.wz[i]}};
}

/// The pair of a manifold as the contact cache keyed it (slots and generations survive removals between steps,
/// which dense indices do not), lower slot first; `flipped` when the kernel's A is the second body.
EventPair pairOf(const ContactKey& key, bool& flipped) {
    flipped = key.bodyB().index < key.bodyA().index;
    return unorderedEventPair(key.bodyA(), key.bodyB());
}

/// Indices of the manifolds `keep` accepts, ascending, found in parallel chunks and joined in chunk order.
template <class Keep>
void selectManifolds(std::size_t count, TaskPool& pool, std::vector<std::vector<std::uint32_t>>& chunks,
                     std::vector<std::uint32_t>& out, Keep&& keep) {
    const std::size_t chunkCount = TaskPool::chunkCount(count, kManifoldChunk);
    if (chunks.size() < chunkCount) chunks.resize(chunkCount);
    pool.forChunks(count, kManifoldChunk, [&](std::size_t c, std::size_t begin, std::size_t end, int) {
        std::vector<std::uint32_t>& list = chunks[c];
        list.clear();
        for (std::size_t k = begin; k < end; ++k)
            if (keep(k)) list.push_back(static_cast<std::uint32_t>(k));
    });
    out.clear();
    for (std::size_t c = 0; c < chunkCount; ++c) out.insert(out.end(), chunks[c].begin(), chunks[c].end());
}

}  // namespace

void ContactEventStage::listen(const Contacts& contacts, const BodyStorage& storage, float touchSlop, float hitSpeed,
                               TaskPool& pool) {
    const MovingBodies& m = storage.moving;
    // The approach speed of each point of manifold k, before the solve; each body's motion is read once per
    // manifold (its rows are scattered, the points are not).
    const auto approaches = [&](std::size_t k, float* out) {
        const ContactPair& pair = contacts.pairs[k];
        const Manifold& manifold = contacts.manifolds[k];
        const BodyMotion a = pair.aStatic ? BodyMotion{} : motionOf(m, pair.a);
        const BodyMotion b = pair.bStatic ? BodyMotion{} : motionOf(m, pair.b);
        for (int i = 0; i < manifold.pointCount; ++i) {
            const Vec3 p = manifold.points[i].position;
            out[i] = -dot(b.velocityAt(p) - a.velocityAt(p), manifold.normal);
        }
    };
    // Only the manifolds whose push the report needs are followed through the substeps: those that may hit, and
    // those not touching yet (they touch if they push). A resting contact is neither: it touches by its depth.
    selectManifolds(contacts.manifolds.size(), pool, chunkLists_, listened_, [&](std::size_t k) {
        if (!listens(storage, contacts.pairs[k])) return false;
        const Manifold& manifold = contacts.manifolds[k];
        bool touching = false;
        for (int i = 0; i < manifold.pointCount; ++i) touching = touching || manifold.points[i].depth >= -touchSlop;
        if (!touching) return true;
        float speeds[kMaxManifoldPoints];
        approaches(k, speeds);
        return *std::max_element(speeds, speeds + manifold.pointCount) >= hitSpeed;
    });
    approach_.assign(listened_.size() * kMaxManifoldPoints, 0.0f);
    impulses_.assign(listened_.size() * kMaxManifoldPoints, 0.0f);
    lanes_.clear();
    pool.forChunks(listened_.size(), kManifoldChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t j = begin; j < end; ++j) approaches(listened_[j], &approach_[j * kMaxManifoldPoints]);
    });
}

void ContactEventStage::findLanes(const ContactSolver* solver, const Contacts& contacts) {
    lanes_.clear();
    if (solver == nullptr || listened_.empty()) return;
    listenedOf_.assign(contacts.manifolds.size(), ~0u);
    for (std::size_t j = 0; j < listened_.size(); ++j) listenedOf_[listened_[j]] = static_cast<std::uint32_t>(j);
    const std::span<const std::uint32_t> manifoldOfLane = solver->manifoldOfLane();
    for (std::uint32_t lane = 0; lane < manifoldOfLane.size(); ++lane) {
        const std::uint32_t k = manifoldOfLane[lane];
        if (k >= listenedOf_.size() || listenedOf_[k] == ~0u) continue;
        lanes_.push_back({lane, listenedOf_[k], contacts.manifolds[k].pointCount});
    }
    laneImpulses_.assign(lanes_.size() * kMaxManifoldPoints, 0.0f);
}

void ContactEventStage::addSubstepImpulses(const ContactSolver& solver, TaskPool& pool) {
    // Read and written in lane order, both in memory order; report() hands the sums to their manifolds once.
    pool.forChunks(lanes_.size(), kManifoldChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t e = begin; e < end; ++e) {
            const Lane& l = lanes_[e];
            float* sum = &laneImpulses_[e * kMaxManifoldPoints];
            for (int i = 0; i < l.points; ++i) sum[i] += solver.normalImpulse(l.lane, i);
        }
    });
}

void ContactEventStage::report(const Contacts* contacts, const ContactCache& cache, const BodyStorage& storage,
                               float touchSlop, float hitSpeed, TaskPool& pool, ContactEvents& out) {
    for (std::size_t e = 0; e < lanes_.size(); ++e)
        for (std::size_t i = 0; i < kMaxManifoldPoints; ++i)
            impulses_[std::size_t{lanes_[e].listened} * kMaxManifoldPoints + i] =
                laneImpulses_[e * kMaxManifoldPoints + i];
    const auto pushed = [&](std::size_t j) {
        for (std::size_t i = 0; i < kMaxManifoldPoints; ++i)
            if (impulses_[j * kMaxManifoldPoints + i] > 0) return true;
        return false;
    };
    now_.clear();
    if (contacts != nullptr) {
        selectManifolds(contacts->manifolds.size(), pool, chunkLists_, touchingManifolds_, [&](std::size_t k) {
            if (!listens(storage, contacts->pairs[k])) return false;
            const Manifold& manifold = contacts->manifolds[k];
            for (int i = 0; i < manifold.pointCount; ++i)
                if (manifold.points[i].depth >= -touchSlop) return true;
            return false;
        });
        // Pairs by slots alone: within a step a slot holds one body, whose generation the storage still has.
        const auto slotsOf = [&](std::uint32_t k) {
            bool flipped = false;
            return pairOf(cache.currentKey(k), flipped).slots;
        };
        touchingSlots_.clear();
        for (const std::uint32_t k : touchingManifolds_) touchingSlots_.push_back(slotsOf(k));
        // A speculative contact that pushed met within the step: a ball that falls onto a floor and bounces off it
        // between two steps' contacts touched it.
        for (std::size_t j = 0; j < listened_.size(); ++j)
            if (pushed(j)) touchingSlots_.push_back(slotsOf(listened_[j]));
        radixSort(touchingSlots_.data(), touchingSlots_.size(), sortScratch_, pool);
        touchingSlots_.erase(std::unique(touchingSlots_.begin(), touchingSlots_.end()), touchingSlots_.end());
        for (const std::uint64_t slots : touchingSlots_) {
            const BodyId a = storage.idAt(static_cast<std::uint32_t>(slots >> 32));
            const BodyId b = storage.idAt(static_cast<std::uint32_t>(slots));
            now_.push_back(eventPair(a, b));
        }
    }
    touching_.update(storage, now_, out.begins, out.ends);

    hits_.clear();
    for (std::size_t j = 0; j < listened_.size() && contacts != nullptr; ++j) {
        const Manifold& manifold = contacts->manifolds[listened_[j]];
        float impulse = 0, fastest = 0;
        int at = -1;
        for (int i = 0; i < manifold.pointCount; ++i) {
            const std::size_t p = j * kMaxManifoldPoints + static_cast<std::size_t>(i);
            impulse += impulses_[p];
            if (approach_[p] > fastest) fastest = approach_[p], at = i;
        }
        if (impulse <= 0 || at < 0 || fastest < hitSpeed) continue;
        bool flipped = false;
        const EventPair pair = pairOf(cache.currentKey(listened_[j]), flipped);
        hits_.push_back({pair,
                         {pair.first(), pair.second(), manifold.points[at].position,
                          flipped ? -manifold.normal : manifold.normal, fastest, impulse}});
    }
    // One event per pair: the parts of a compound or the triangles of a mesh that one body struck add their
    // impulses; the point and normal are the fastest approach's.
    std::stable_sort(hits_.begin(), hits_.end(), [](const Hit& x, const Hit& y) { return x.pair < y.pair; });
    for (std::size_t j = 0; j < hits_.size();) {
        ContactHitEvent event = hits_[j].event;
        std::size_t k = j + 1;
        for (; k < hits_.size() && hits_[k].pair == hits_[j].pair; ++k) {
            const float impulse = event.impulse + hits_[k].event.impulse;
            if (hits_[k].event.approachSpeed > event.approachSpeed) event = hits_[k].event;
            event.impulse = impulse;
        }
        out.hits.push_back(event);
        j = k;
    }
    listened_.clear();
    lanes_.clear();
}

}  // namespace rubble::detail
