#pragma once
// Snapshots from the physics thread to the render thread, lock-free. The render thread interpolates between the two
// newest snapshots, so it holds a pair; the published pair must stay intact for the reader to take it; the physics
// thread writes the next one beside them: five buffers, so that the writer always finds a free one and never waits.
// (With four, a reader that missed two publishes holds a pair disjoint from the published one and the writer would
// have to withdraw the published older snapshot, handing the reader a pair of one snapshot twice.)
//
// One atomic word names the published pair (older, newer), a sequence number and a "claimed" bit that the reader
// sets by compare-and-swap when it takes the pair. The writer writes only into a buffer that is neither in the
// published pair nor in the pair the reader last claimed, which it learns from the claimed bit on its load before
// writing and on the exchange that publishes. A reader can only ever claim the currently published pair, which the
// writer never touches, so the reader never sees a torn snapshot.
#include <atomic>
#include <cstdint>

#include "rubble/runtime.h"

namespace rubble::detail {

class SnapshotBuffers {
public:
    static constexpr int kCount = 5;

    // ---- Writer (one thread) ----

    /// Index of a buffer the reader cannot be reading; write the next snapshot into buffer(index), then publish it.
    int beginWrite();
    /// Makes the buffer from beginWrite the newest, paired with the previous newest.
    void publish(int index);
    Snapshot& buffer(int index) { return buffers_[index]; }

    // ---- Reader (one thread) ----

    /// The newest published pair: two consecutive snapshots (older equals newer only for the very first). They stay
    /// intact until the next acquire. False before the first publish.
    bool acquire(const Snapshot*& older, const Snapshot*& newer);

private:
    static constexpr std::uint64_t kNone = 7;  // indices take 3 bits
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
