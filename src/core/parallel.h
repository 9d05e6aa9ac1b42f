#pragma once
// The one thin threading API of the engine: deterministic chunked loops over a task arena, and parallel regions
// whose workers pass through phases of independent units. TBB appears only in parallel.cpp. Chunk boundaries depend
// only on (count, chunkSize), never on the thread count, so per-chunk outputs merged in chunk order give the same
// result on any number of threads; a region's units are independent within their phase, so which worker runs one
// changes nothing.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <type_traits>
#include <vector>

namespace rubble::detail {

/// Non-owning reference to a callable, cheaper than std::function for hot dispatch.
template <class Signature>
class FunctionRef;

template <class R, class... Args>
class FunctionRef<R(Args...)> {
public:
    template <class F>
    FunctionRef(F&& f) noexcept  // NOLINT(google-explicit-constructor): used like a function parameter
        : object_(const_cast<void*>(static_cast<const void*>(&f))),
          call_([](void* o, Args... args) -> R { return (*static_cast<std::remove_reference_t<F>*>(o))(args...); }) {}
    R operator()(Args... args) const { return call_(object_, args...); }

private:
    void* object_;
    R (*call_)(void*, Args...);
};

class TaskPool {
public:
    /// threads <= 0 means every hardware thread.
    explicit TaskPool(int threads);
    ~TaskPool();
    TaskPool(const TaskPool&) = delete;
    TaskPool& operator=(const TaskPool&) = delete;

    int threadCount() const { return threads_; }

    /// Calls fn(chunk, begin, end, worker) for chunks [k*chunkSize, min(count, (k+1)*chunkSize)).
    /// worker is in [0, threadCount()) and indexes per-worker scratch. Runs inline when there is one chunk.
    void forChunks(std::size_t count, std::size_t chunkSize,
                   FunctionRef<void(std::size_t chunk, std::size_t begin, std::size_t end, int worker)> fn);

    /// Calls fn(worker) threadCount() times, as many at once as there are free threads: one parallel region for
    /// work that passes through phases without a fork and join per phase. Calls may also run one after another on
    /// one thread, so fn must claim its work from shared counters and may wait only for work another call has
    /// already claimed (WorkPhases), never for a call to arrive.
    void forEachWorker(FunctionRef<void(int worker)> fn);

    static std::size_t chunkCount(std::size_t count, std::size_t chunkSize) {
        return chunkSize == 0 ? 0 : (count + chunkSize - 1) / chunkSize;
    }

private:
    struct Arena;
    int threads_;
    std::unique_ptr<Arena> arena_;
};

/// The phases of a parallel region (TaskPool::forEachWorker). A phase is `count` units in one contiguous share per
/// worker: a worker runs its own share first, so that the same units fall to the same worker on every call and their
/// data stays in its core's cache, then what is left of the others' shares, and passes the phase's barrier once every
/// unit is done. Deadlock-free whichever workers arrive: a worker waits only for units that running workers have
/// claimed, and a worker alone runs every share.
class WorkPhases {
public:
    /// `phases` empty phases for `workers` workers.
    void reset(std::size_t phases, int workers);
    /// Phase p: units [0, count) in even shares.
    void setEven(std::size_t p, std::uint32_t count);
    /// Phase p: worker w's share is [starts[w], starts[w + 1]); starts has workers + 1 entries, the last the count.
    void setShares(std::size_t p, const std::uint32_t* starts);
    std::uint32_t count(std::size_t p) const { return start(p, workers_); }

    /// Runs unit(u) for every unit of phase p this worker claims: its own share's, then the others'.
    template <class Unit>
    void run(std::size_t p, int worker, Unit&& unit) {
        std::uint32_t finished = 0;
        for (int k = 0; k < workers_; ++k) {
            const int owner = (worker + k) % workers_;
            std::atomic<std::uint32_t>& cursor = cursors_[p * static_cast<std::size_t>(workers_) + owner].value;
            const std::uint32_t first = start(p, owner), end = start(p, owner + 1);
            for (std::uint32_t u = first + cursor.fetch_add(1, std::memory_order_relaxed); u < end;
                 u = first + cursor.fetch_add(1, std::memory_order_relaxed)) {
                unit(u);
                ++finished;
            }
        }
        if (finished > 0) done_[p].value.fetch_add(finished, std::memory_order_release);
    }
    /// Waits until every unit of phase p is done (spinning briefly, then yielding the core); their writes are seen.
    void wait(std::size_t p) const;

private:
    struct alignas(64) Counter {
        std::atomic<std::uint32_t> value{0};
    };
    std::uint32_t start(std::size_t p, int w) const {
        return starts_[p * static_cast<std::size_t>(workers_ + 1) + static_cast<std::size_t>(w)];
    }
    int workers_ = 1;
    std::size_t capacity_ = 0;
    std::vector<std::uint32_t> starts_;
    std::unique_ptr<Counter[]> cursors_, done_;
};

}  // namespace rubble::detail
