#include "core/parallel.h"

#include <algorithm>
#include <thread>

#if RUBBLE_STD_THREADS
#include <atomic>
#include <condition_variable>
#include <mutex>
#include <vector>
#else
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>
#endif

#include "simd/float_mode.h"

namespace rubble::detail {

#if !RUBBLE_STD_THREADS

struct TaskPool::Arena {
    tbb::task_arena arena;
    explicit Arena(int threads) : arena(threads) {
        // TBB starts its worker threads the first time a parallel loop asks for them: without this, a world's first
        // step pays for starting them (about 1 ms at two threads, in whichever stage first runs in parallel).
        if (threads > 1) run(std::size_t(threads) * 16, [](std::size_t, int) {});
    }

    void run(std::size_t chunks, FunctionRef<void(std::size_t, int)> chunk) {
        arena.execute([&] {
            tbb::parallel_for(
                tbb::blocked_range<std::size_t>(0, chunks, 1),
                [&](const tbb::blocked_range<std::size_t>& r) {
                    // The engine's float mode, on every thread (simd/float_mode.h).
                    const simd::FlushSubnormals flushSubnormals;
                    const int worker = tbb::this_task_arena::current_thread_index();
                    for (std::size_t c = r.begin(); c != r.end(); ++c) chunk(c, worker);
                },
                tbb::simple_partitioner());
        });
    }
};

#else

/// ThreadSanitizer cannot see the synchronisation inside Debian's uninstrumented libtbb and reports races in
/// its task ranges. Under TSan the pool is this plain std::thread one instead, with the same chunks, so that
/// what TSan checks is Rubble's own code.
struct TaskPool::Arena {
    explicit Arena(int threads) {
        for (int w = 1; w < threads; ++w) workers.emplace_back([this, w] { workerLoop(w); });
    }
    ~Arena() {
        {
            std::lock_guard lock(mutex);
            stopping = true;
        }
        wake.notify_all();
        for (std::thread& t : workers) t.join();
    }

    void run(std::size_t chunks, FunctionRef<void(std::size_t, int)> chunk) {
        std::unique_lock lock(mutex);
        job = &chunk;
        jobChunks = chunks;
        next.store(0);
        ++generation;
        lock.unlock();
        wake.notify_all();
        drain(chunk, 0);
        lock.lock();
        // Every chunk is taken. Closing the job keeps out the workers that have not joined it yet (they would find
        // nothing left), so the caller waits only for those still running a chunk, never for one still waking up:
        // on a shared machine a descheduled worker can take milliseconds to wake, which a step of 0.1 ms then paid.
        job = nullptr;
        done.wait(lock, [&] { return busy == 0; });
    }

    void drain(FunctionRef<void(std::size_t, int)> chunk, int worker) {
        const simd::FlushSubnormals flushSubnormals;  // the engine's mode, on every thread (simd/float_mode.h)
        for (std::size_t c = next.fetch_add(1); c < jobChunks; c = next.fetch_add(1)) chunk(c, worker);
    }

    void workerLoop(int worker) {
        std::uint64_t seen = 0;
        std::unique_lock lock(mutex);
        for (;;) {
            wake.wait(lock, [&] { return stopping || generation != seen; });
            if (stopping) return;
            seen = generation;
            if (job == nullptr) continue;  // closed before this worker woke: its chunks were run by others
            ++busy;
            FunctionRef<void(std::size_t, int)> chunk = *job;
            lock.unlock();
            drain(chunk, worker);
            lock.lock();
            if (--busy == 0) done.notify_one();
        }
    }

    std::vector<std::thread> workers;
    std::mutex mutex;
    std::condition_variable wake, done;
    const FunctionRef<void(std::size_t, int)>* job = nullptr;
    std::size_t jobChunks = 0;
    std::atomic<std::size_t> next{0};
    std::uint64_t generation = 0;
    int busy = 0;
    bool stopping = false;
};

#endif

void TaskPool::forEachWorker(FunctionRef<void(int)> fn) {
    if (threads_ == 1) {
        const simd::FlushSubnormals flushSubnormals;
        fn(0);
        return;
    }
    arena_->run(static_cast<std::size_t>(threads_), [&](std::size_t, int worker) { fn(worker); });
}

void WorkPhases::reset(std::size_t phases, int workers) {
    workers_ = workers;
    const std::size_t counters = phases * static_cast<std::size_t>(workers);
    if (capacity_ < std::max(counters, phases)) {
        capacity_ = std::max(counters, phases) * 2;
        cursors_ = std::make_unique<Counter[]>(capacity_);
        done_ = std::make_unique<Counter[]>(capacity_);
    }
    for (std::size_t i = 0; i < counters; ++i) cursors_[i].value.store(0, std::memory_order_relaxed);
    for (std::size_t i = 0; i < phases; ++i) done_[i].value.store(0, std::memory_order_relaxed);
    starts_.assign(phases * static_cast<std::size_t>(workers + 1), 0);
}

void WorkPhases::setEven(std::size_t p, std::uint32_t count) {
    for (int w = 0; w <= workers_; ++w)
        starts_[p * static_cast<std::size_t>(workers_ + 1) + static_cast<std::size_t>(w)] = static_cast<std::uint32_t>(
            std::uint64_t{count} * static_cast<std::uint64_t>(w) / static_cast<std::uint64_t>(workers_));
}

void WorkPhases::setShares(std::size_t p, const std::uint32_t* starts) {
    std::copy(starts, starts + workers_ + 1, starts_.begin() + static_cast<std::ptrdiff_t>(p * (workers_ + 1)));
}

void WorkPhases::wait(std::size_t p) const {
    // A phase's units take microseconds: spin first, but give the core away if the other worker was descheduled
    // (these machines are shared).
    const std::uint32_t units = count(p);
    for (int spin = 0; done_[p].value.load(std::memory_order_acquire) < units; ++spin) {
        if (spin < 256) {
#if defined(__x86_64__) || defined(__i386__)
            __builtin_ia32_pause();
#endif
        } else {
            std::this_thread::yield();
        }
    }
}

TaskPool::TaskPool(int threads)
    : threads_(threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()))),
      arena_(std::make_unique<Arena>(threads_)) {}

TaskPool::~TaskPool() = default;

void TaskPool::forChunks(std::size_t count, std::size_t chunkSize,
                         FunctionRef<void(std::size_t, std::size_t, std::size_t, int)> fn) {
    const std::size_t chunks = chunkCount(count, chunkSize);
    if (chunks == 0) return;
    if (chunks == 1 || threads_ == 1) {
        const simd::FlushSubnormals flushSubnormals;  // as every worker does, whoever calls
        for (std::size_t c = 0; c < chunks; ++c) fn(c, c * chunkSize, std::min(count, (c + 1) * chunkSize), 0);
        return;
    }
    auto chunk = [&](std::size_t c, int worker) { fn(c, c * chunkSize, std::min(count, (c + 1) * chunkSize), worker); };
    arena_->run(chunks, chunk);
}

}  // namespace rubble::detail
