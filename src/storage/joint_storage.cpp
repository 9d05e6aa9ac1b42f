#include "storage/joint_storage.h"

#include <algorithm>
#include <atomic>

namespace rubble::detail {

std::uint64_t JointStore::nextPairsVersion() {
    static std::atomic<std::uint64_t> last{0};
    return last.fetch_add(1, std::memory_order_relaxed) + 1;
}

JointId JointStore::add(const Joint& joint) {
    pairsVersion_ = nextPairsVersion();
    const JointId id = ids_.acquire();
    const std::uint32_t slot = id.index;
    if (slot == denseOfSlot_.size()) denseOfSlot_.push_back(0);
    denseOfSlot_[slot] = static_cast<std::uint32_t>(joints_.size());
    joints_.push_back(joint);
    joints_.back().slot = slot;
    if (joint.broken) brokenCount_ += 1;
    for (BodyId body : {joint.bodyA, joint.bodyB}) {
        if (body.index >= jointsOfBody_.size()) jointsOfBody_.resize(body.index + 1);
        jointsOfBody_[body.index].push_back(slot);
    }
    return id;
}

void JointStore::unlink(std::uint32_t bodySlot, std::uint32_t jointSlot) {
    std::vector<std::uint32_t>& list = jointsOfBody_[bodySlot];
    const auto it = std::find(list.begin(), list.end(), jointSlot);
    if (it != list.end()) list.erase(it);
}

void JointStore::remove(JointId id) {
    const Joint* joint = find(id);
    if (!joint) return;
    pairsVersion_ = nextPairsVersion();
    const std::uint32_t dense = denseOfSlot_[id.index];
    unlink(joint->bodyA.index, id.index);
    unlink(joint->bodyB.index, id.index);
    if (joint->broken) brokenCount_ -= 1;
    const std::uint32_t last = size() - 1;
    if (dense != last) {
        joints_[dense] = joints_[last];
        denseOfSlot_[joints_[dense].slot] = dense;
    }
    joints_.pop_back();
    ids_.release(id.index);
}

Joint* JointStore::find(JointId id) { return const_cast<Joint*>(static_cast<const JointStore*>(this)->find(id)); }

const Joint* JointStore::find(JointId id) const {
    return ids_.contains(id) ? &joints_[denseOfSlot_[id.index]] : nullptr;
}

std::uint32_t JointStore::removeAttachedTo(BodyId body) {
    if (body.index >= jointsOfBody_.size()) return 0;
    // Copied: remove() edits the list.
    const std::vector<std::uint32_t> attached = jointsOfBody_[body.index];
    for (std::uint32_t slot : attached) remove(ids_.idAt(slot));
    return static_cast<std::uint32_t>(attached.size());
}

void JointStore::markBroken(std::uint32_t dense) {
    Joint& j = joints_[dense];
    if (j.broken) return;
    pairsVersion_ = nextPairsVersion();
    j.broken = true;
    brokenCount_ += 1;
    brokenReports_.push_back(idOf(dense));
}

}  // namespace rubble::detail
