#include "runtime/snapshot_buffer.h"

namespace rubble::detail {

int SnapshotBuffers::beginWrite() {
    const std::uint64_t word = word_.load(std::memory_order_acquire);
    if (word & claimedBit) readerOlder_ = older(word), readerNewer_ = newer(word);
    // At most four of the five are taken: the published pair and the reader's. A claim the writer has not seen yet
    // can only be of the published pair, which is excluded anyway.
    for (std::uint64_t i = 0; i < kCount; ++i)
        if (i != older(word) && i != newer(word) && i != readerOlder_ && i != readerNewer_) return static_cast<int>(i);
    return -1;  // unreachable: five buffers, four excluded at most
}

void SnapshotBuffers::publish(int index) {
    const std::uint64_t current = word_.load(std::memory_order_relaxed);  // only this thread changes the pair
    const std::uint64_t previousNewer = newer(current) == kNone ? static_cast<std::uint64_t>(index) : newer(current);
    const std::uint64_t next = make(sequence(current) + 1, previousNewer, static_cast<std::uint64_t>(index));
    const std::uint64_t old = word_.exchange(next, std::memory_order_acq_rel);
    if (old & claimedBit) readerOlder_ = older(old), readerNewer_ = newer(old);
}

bool SnapshotBuffers::acquire(const Snapshot*& olderOut, const Snapshot*& newerOut) {
    std::uint64_t word = word_.load(std::memory_order_acquire);
    while (!(word & claimedBit)) {
        if (newer(word) == kNone) return false;
        if (word_.compare_exchange_weak(word, word | claimedBit, std::memory_order_acq_rel, std::memory_order_acquire))
            break;
    }
    olderOut = &buffers_[older(word)];
    newerOut = &buffers_[newer(word)];
    return true;
}

}  // namespace rubble::detail
