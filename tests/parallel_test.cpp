// The thread API: chunk boundaries depend only on (count, chunk size), every index is visited once, and workers
// stay within the arena's size.
#include <gtest/gtest.h>

#include <atomic>
#include <vector>

#include "core/parallel.h"

using rubble::detail::TaskPool;

TEST(Parallel, EveryIndexOnceAndChunksIndependentOfThreads) {
    for (int threads : {1, 2, 4}) {
        TaskPool pool(threads);
        const std::size_t count = 100'003, chunk = 1024;
        std::vector<std::atomic<int>> visits(count);
        std::vector<std::pair<std::size_t, std::size_t>> bounds(TaskPool::chunkCount(count, chunk));
        std::atomic<int> badWorker{0};
        pool.forChunks(count, chunk, [&](std::size_t c, std::size_t begin, std::size_t end, int worker) {
            if (worker < 0 || worker >= threads) badWorker++;
            bounds[c] = {begin, end};
            for (std::size_t i = begin; i < end; ++i) visits[i]++;
        });
        EXPECT_EQ(badWorker.load(), 0);
        for (std::size_t i = 0; i < count; ++i) ASSERT_EQ(visits[i].load(), 1) << i;
        for (std::size_t c = 0; c < bounds.size(); ++c) {
            EXPECT_EQ(bounds[c].first, c * chunk);
            EXPECT_EQ(bounds[c].second, std::min(count, (c + 1) * chunk));
        }
    }
}

TEST(Parallel, EmptyAndSingleChunkRunInline) {
    TaskPool pool(2);
    int calls = 0;
    pool.forChunks(0, 64, [&](std::size_t, std::size_t, std::size_t, int) { ++calls; });
    EXPECT_EQ(calls, 0);
    pool.forChunks(10, 64, [&](std::size_t, std::size_t b, std::size_t e, int w) {
        ++calls;
        EXPECT_EQ(b, 0u);
        EXPECT_EQ(e, 10u);
        EXPECT_EQ(w, 0);
    });
    EXPECT_EQ(calls, 1);
}

// Every chunk, on a worker or inline, runs with subnormal results flushed to zero (simd/float_mode.h), and the
// caller's own mode is back when forChunks returns: half the smallest normal float is zero inside, not outside.
TEST(Parallel, ChunksFlushSubnormalsAndTheCallerKeepsItsMode) {
#if defined(__SSE__) || defined(__x86_64__)
    const auto halfOfSmallestNormal = [] {
        volatile float tiny = 1.17549435e-38f;  // volatile: computed at run time, under the current mode
        return tiny * 0.5f;
    };
    ASSERT_NE(halfOfSmallestNormal(), 0.0f) << "the test expects the default mode (subnormals kept)";
    for (int threads : {1, 2}) {
        TaskPool pool(threads);
        for (std::size_t chunks : {std::size_t{1}, std::size_t{64}}) {
            std::atomic<int> kept{0};
            pool.forChunks(chunks, 1, [&](std::size_t, std::size_t, std::size_t, int) {
                if (halfOfSmallestNormal() != 0.0f) kept++;
            });
            EXPECT_EQ(kept.load(), 0) << threads << " threads, " << chunks << " chunks";
            EXPECT_NE(halfOfSmallestNormal(), 0.0f) << "the caller's mode after forChunks";
        }
    }
#else
    GTEST_SKIP() << "x86 only";
#endif
}
