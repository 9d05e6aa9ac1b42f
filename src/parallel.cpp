#include "parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

#include <thread>

namespace rubble::detail {

struct TaskPool::Arena {
    tbb::task_arena arena;
    explicit Arena(int threads) : arena(threads) {}
};

TaskPool::TaskPool(int threads)
    : threads_(threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()))),
      arena_(std::make_unique<Arena>(threads_)) {}

TaskPool::~TaskPool() = default;

void TaskPool::forChunks(std::size_t count, std::size_t chunkSize,
                         FunctionRef<void(std::size_t, std::size_t, std::size_t, int)> fn) {
    const std::size_t chunks = chunkCount(count, chunkSize);
    if (chunks == 0) return;
    if (chunks == 1 || threads_ == 1) {
        for (std::size_t c = 0; c < chunks; ++c) fn(c, c * chunkSize, std::min(count, (c + 1) * chunkSize), 0);
        return;
    }
    arena_->arena.execute([&] {
        tbb::parallel_for(
            tbb::blocked_range<std::size_t>(0, chunks, 1),
            [&](const tbb::blocked_range<std::size_t>& r) {
                const int worker = tbb::this_task_arena::current_thread_index();
                for (std::size_t c = r.begin(); c != r.end(); ++c)
                    fn(c, c * chunkSize, std::min(count, (c + 1) * chunkSize), worker);
            },
            tbb::simple_partitioner());
    });
}

}  // namespace rubble::detail
