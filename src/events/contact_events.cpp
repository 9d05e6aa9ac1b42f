#include "events/contact_events.h"

#include <algorithm>

#include "core/parallel.h"

namespace rubble::detail {

namespace {

constexpr std::size_t kManifoldChunk = 4096;

std::uint8_t flagsOf(const BodyStorage& storage, std::uint32_t dense, bool isStatic) {
    return isStatic ? storage.statics.flags[dense] : storage.moving.flags[dense];
}

bool listens(const BodyStorage& storage, const ContactPair& pair) {
    return ((flagsOf(storage, pair.a, pair.aStatic) | flagsOf(storage, pair.b, pair.bStatic)) & kFlagContactEvents) !=
           0;
}

Vec3 velocityAt(const MovingBodies& m, std::uint32_t i, Vec3 point) {
    const Vec3 arm = point - Vec3{m.px[i], m.py[i], m.pz[i]};
    return Vec3{m.vx[i], m.vy[i], m.vz[i]} + cross(Vec3{m.wx[i], m.wy[i], m.wz[i]}, arm);
}

/// The pair of a manifold as the contact cache keyed it (slots and generations survive removals between steps,
/// which dense indices do not), lower slot first; `flipped` when the kernel's A is the second body.
EventPair pairOf(const ContactKey& key, bool& flipped) {
    const BodyId a{static_cast<unsigned>(key.slots >> 32), static_cast<unsigned>(key.generations >> 32)};
    const BodyId b{static_cast<unsigned>(key.slots), static_cast<unsigned>(key.generations)};
    flipped = b.index < a.index;
    return unorderedEventPair(a, b);
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

void ContactEventStage::listen(const Contacts& contacts, const BodyStorage& storage, TaskPool& pool) {
    selectManifolds(contacts.manifolds.size(), pool, chunkLists_, listened_,
                    [&](std::size_t k) { return listens(storage, contacts.pairs[k]); });
    const MovingBodies& m = storage.moving;
    approach_.assign(listened_.size() * kMaxManifoldPoints, 0.0f);
    impulses_.assign(listened_.size() * kMaxManifoldPoints, 0.0f);
    lanes_.assign(listened_.size(), ~0u);
    for (std::size_t j = 0; j < listened_.size(); ++j) {
        const ContactPair& pair = contacts.pairs[listened_[j]];
        const Manifold& manifold = contacts.manifolds[listened_[j]];
        for (int i = 0; i < manifold.pointCount; ++i) {
            const Vec3 p = manifold.points[i].position;
            const Vec3 va = pair.aStatic ? Vec3{} : velocityAt(m, pair.a, p);
            const Vec3 vb = pair.bStatic ? Vec3{} : velocityAt(m, pair.b, p);
            approach_[j * kMaxManifoldPoints + static_cast<std::size_t>(i)] = -dot(vb - va, manifold.normal);
        }
    }
}

void ContactEventStage::findLanes(const ContactSolver* solver) {
    if (solver == nullptr || listened_.empty()) return;
    solver->lanesOf(listened_, lanes_);
}

void ContactEventStage::addSubstepImpulses(const ContactSolver& solver, const Contacts& contacts) {
    for (std::size_t j = 0; j < listened_.size(); ++j) {
        if (lanes_[j] == ~0u) continue;
        const int points = contacts.manifolds[listened_[j]].pointCount;
        for (int i = 0; i < points; ++i)
            impulses_[j * kMaxManifoldPoints + static_cast<std::size_t>(i)] += solver.normalImpulse(lanes_[j], i);
    }
}

void ContactEventStage::report(const Contacts* contacts, const ContactCache& cache, const BodyStorage& storage,
                               float touchSlop, float hitSpeed, TaskPool& pool, ContactEvents& out) {
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
        bool flipped = false;
        for (const std::uint32_t k : touchingManifolds_) now_.push_back(pairOf(cache.currentKey(k), flipped));
        // A speculative contact that pushed met within the step: a ball that falls onto a floor and bounces off it
        // between two steps' contacts touched it.
        for (std::size_t j = 0; j < listened_.size(); ++j)
            if (pushed(j)) now_.push_back(pairOf(cache.currentKey(listened_[j]), flipped));
        std::sort(now_.begin(), now_.end());
        now_.erase(std::unique(now_.begin(), now_.end()), now_.end());
    }
    touching_.update(
        storage, now_,
        [&](const EventPair& p) {
            out.begins.push_back({p.first(), p.second()});
        },
        [&](const EventPair& p) {
            out.ends.push_back({p.first(), p.second()});
        });

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
}

}  // namespace rubble::detail
