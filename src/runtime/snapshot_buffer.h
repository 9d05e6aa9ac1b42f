#pragma once
// Snapshots from the physics thread to the render thread, lock-free. The render thread interpolates between the two
// newest snapshots, so it holds a pair, and the physics thread keeps its newest one (the older half of the next
// pair) while it writes the next: four buffers.
//
// One atomic word names the published pair (older, newer), a sequence number and a "claimed" bit that the reader
// sets by compare-and-swap when it takes the pair. The writer writes only into a buffer that is neither in the
// published pair nor in the pair the reader last claimed (which it learns from the claimed bit, on its loads and on
// the exchange that publishes). If the reader has not claimed the last two pairs, those four indices are all taken;
// then the writer withdraws the unclaimed older buffer by a compare-and-swap that publishes (newer, newer) instead.
// If the reader claims first, that CAS fails and the reader's old pair is free. The writer never waits.
#include <atomic>
#include <cstdint>

#include "rubble/runtime.h"

namespace rubble::detail {

class SnapshotBuffers {
public:
    static constexpr int kCount = 4;

    // ---- Writer (one thread) ----

    /// Index of a buffer the reader cannot be reading; write the next snapshot into buffer(index), then publish it.
    int beginWrite();
    /// Makes the buffer from beginWrite the newest, paired with the previous newest.
    void publish(int index);
    Snapshot& buffer(int index) { return buffers_[index]; }

    // ---- Reader (one thread) ----

    /// The newest published pair (older may equal newer: the first snapshot, or a pair the writer narrowed). The
    /// snapshots stay intact until the next acquire. False before the first publish.
    bool acquire(const Snapshot*& older, const Snapshot*& newer);

private:
    static constexpr std::uint64_t kNone = 7;
    static constexpr std::uint64_t claimedBit = 1;
    static std::uint64_t older(std::uint64_t word) { return (word >> 1) & 7; }
    static std::uint64_t newer(std::uint64_t word) { return (word >> 4) & 7; }
    static std::uint64_t sequence(std::uint64_t word) { return word >> 8; }
    static std::uint64_t make(std::uint64_t seq, std::uint64_t olderIndex, std::uint64_t newerIndex) {
        return (seq << 8) | (newerIndex << 4) | (olderIndex << 1);
    }

    Snapshot buffers_[kCount];
    std::atomic<std::uint64_t> word_{make(0, kNone, kNone)};
    // Writer-only state: the pair the reader held when last seen.
    std::uint64_t readerOlder_ = kNone, readerNewer_ = kNone;
};

}  // namespace rubble::detail
