#include "runtime/snapshot_buffer.h"

namespace rubble::detail {

int SnapshotBuffers::beginWrite() {
    std::uint64_t word = word_.load(std::memory_order_acquire);
    for (;;) {
        if (word & claimedBit) readerOlder_ = older(word), readerNewer_ = newer(word);
        for (std::uint64_t i = 0; i < kCount; ++i)
            if (i != older(word) && i != newer(word) && i != readerOlder_ && i != readerNewer_)
                return static_cast<int>(i);
        // All four are taken: the reader still holds a pair older than the published one, which it has not claimed.
        // Withdraw the published older buffer so it cannot be claimed; if the reader claims first, retry (its old
        // pair is then free).
        const std::uint64_t narrowed = make(sequence(word) + 1, newer(word), newer(word));
        if (word_.compare_exchange_strong(word, narrowed, std::memory_order_acq_rel, std::memory_order_acquire))
            return static_cast<int>(older(word));
    }
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
