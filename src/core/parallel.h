#pragma once
// The one thin threading API of the engine: deterministic chunked loops over a task arena.
// TBB appears only in parallel.cpp. Chunk boundaries depend only on (count, chunkSize), never on the thread
// count, so per-chunk outputs merged in chunk order give the same result on any number of threads.
#include <cstddef>
#include <memory>
#include <type_traits>

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

    static std::size_t chunkCount(std::size_t count, std::size_t chunkSize) {
        return chunkSize == 0 ? 0 : (count + chunkSize - 1) / chunkSize;
    }

private:
    struct Arena;
    int threads_;
    std::unique_ptr<Arena> arena_;
};

}  // namespace rubble::detail
