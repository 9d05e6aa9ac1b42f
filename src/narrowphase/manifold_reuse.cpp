#include "narrowphase/manifold_reuse.h"

#include <algorithm>

namespace rubble::detail {

ManifoldReuse::Finder::Found ManifoldReuse::Finder::find(std::uint64_t order) {
    const std::vector<ChunkCache>& chunks = reuse_->previous_;
    if (!started_) {
        // The first chunk whose entries (or its predecessors') reach the order, then the first entry there that does.
        const std::vector<std::uint64_t>& last = reuse_->previousLast_;
        chunk_ = static_cast<std::size_t>(std::lower_bound(last.begin(), last.end(), order) - last.begin());
        if (chunk_ < chunks.size()) {
            const std::vector<Entry>& entries = chunks[chunk_].entries;
            index_ =
                static_cast<std::size_t>(std::lower_bound(entries.begin(), entries.end(), order,
                                                          [](const Entry& e, std::uint64_t o) { return e.order < o; }) -
                                         entries.begin());
        }
        started_ = true;
    }
    for (; chunk_ < chunks.size(); ++chunk_, index_ = 0) {
        const std::vector<Entry>& entries = chunks[chunk_].entries;
        while (index_ < entries.size() && entries[index_].order < order) ++index_;
        if (index_ == entries.size()) continue;
        const Entry& e = entries[index_];
        if (e.order != order) return {};
        return {&e, chunks[chunk_].stored.data() + e.firstStored};
    }
    return {};
}

void ManifoldReuse::begin(std::size_t chunkCount, std::uint64_t layoutChanges) {
    sameBodies_ = havePrevious_ && layoutChanges == previousLayout_;
    currentLayout_ = layoutChanges;
    if (current_.size() < chunkCount) current_.resize(chunkCount);
    for (std::size_t c = 0; c < chunkCount; ++c) {
        current_[c].entries.clear();
        current_[c].stored.clear();
    }
    currentCount_ = chunkCount;
}

void ManifoldReuse::finish() {
    std::swap(previous_, current_);
    previousLayout_ = currentLayout_;
    havePrevious_ = true;
    // Chunks past this step's count hold older entries: they must not be found.
    for (std::size_t c = currentCount_; c < previous_.size(); ++c) {
        previous_[c].entries.clear();
        previous_[c].stored.clear();
    }
    previousLast_.resize(previous_.size());
    std::uint64_t last = 0;
    for (std::size_t c = 0; c < previous_.size(); ++c) {
        if (!previous_[c].entries.empty()) last = std::max(last, previous_[c].entries.back().order);
        previousLast_[c] = last;
    }
}

void ManifoldReuse::clear() {
    havePrevious_ = sameBodies_ = false;
    previous_.clear();
    current_.clear();
    previousLast_.clear();
    currentCount_ = 0;
}

}  // namespace rubble::detail
