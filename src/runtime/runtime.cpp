// The runtime: the physics thread's loop (fixed-step clock, inputs at step boundaries, snapshot publishing) and the
// control and render-side entry points around it.
#include "rubble/runtime.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "rubble/error.h"
#include "rubble/limits.h"
#include "rubble/world.h"
#include "runtime/input_queue.h"
#include "runtime/runtime_characters.h"
#include "runtime/snapshot.h"
#include "runtime/snapshot_buffer.h"
#include "runtime/step_clock.h"
#include "world/validation.h"

namespace rubble {

namespace {

using SteadyClock = std::chrono::steady_clock;
using detail::fail;

void validateSettings(const char* where, const RuntimeSettings& s) {
    // A step of 1 / rate must be one World::step accepts.
    const double lo = 1.0 / limits::kMaxTimeStep, hi = 1.0 / limits::kMinTimeStep;
    if (!(s.rate >= lo && s.rate <= hi))
        fail(where, "settings.rate must be in [" + detail::formatNumber(lo) + ", " + detail::formatNumber(hi) +
                        "] steps per second (got " + detail::formatNumber(s.rate) + "; docs/limits.md)");
    if (s.maxStepsPerWake < 1 || s.maxStepsPerWake > 1000)
        fail(where, "settings.maxStepsPerWake must be in [1, 1000] (got " + std::to_string(s.maxStepsPerWake) + ")");
}

/// Statistics are written by whichever thread steps and read from any: each field is its own atomic.
struct AtomicStats {
    std::atomic<std::uint64_t> steps{0}, wakeups{0}, droppedSteps{0};
    std::atomic<std::uint32_t> maxStepsPerWake{0};
    std::atomic<double> droppedSeconds{0}, slowdown{1}, physicsHz{0}, lastStepMs{0};
    std::atomic<bool> behind{false};

    RuntimeStats load() const {
        RuntimeStats s;
        s.steps = steps.load(std::memory_order_relaxed);
        s.wakeups = wakeups.load(std::memory_order_relaxed);
        s.droppedSteps = droppedSteps.load(std::memory_order_relaxed);
        s.maxStepsPerWake = maxStepsPerWake.load(std::memory_order_relaxed);
        s.droppedSeconds = droppedSeconds.load(std::memory_order_relaxed);
        s.slowdown = slowdown.load(std::memory_order_relaxed);
        s.physicsHz = physicsHz.load(std::memory_order_relaxed);
        s.lastStepMs = lastStepMs.load(std::memory_order_relaxed);
        s.behind = behind.load(std::memory_order_relaxed);
        return s;
    }
};

/// Rates are measured over windows of at least this much clock time.
constexpr double kStatsWindowSeconds = 0.5;

}  // namespace

struct Runtime::Impl {
    World world;
    RuntimeSettings settings;
    detail::StepClock clock;
    std::atomic<double> stepSeconds;

    // Physics side (whichever thread steps: the runtime's thread, or the caller of advance/replay/singleStep).
    detail::SnapshotBuffers snapshots;
    /// Snapshot buffers are rewritten in full when their layout version is behind the world's (bodies added or
    /// removed, static bodies moved, the world handed out), else only the moving bodies' poses.
    std::uint64_t bufferLayout[detail::SnapshotBuffers::kCount] = {};
    std::uint64_t layoutVersion = 1;
    std::vector<detail::PendingCommand> applying;
    detail::KinematicMoves kinematicMoves;
    detail::RuntimeCharacters characters;
    std::vector<RecordedInput> newlyRecorded;
    std::vector<std::string> newErrors;
    double simTime = 0;
    double windowClock = 0, windowSim = 0;
    std::uint64_t windowSteps = 0;
    AtomicStats stats;

    // Input and its by-products, shared with other threads.
    detail::InputQueue inputs;
    std::mutex outputMutex;
    std::vector<RecordedInput> recording;
    std::vector<std::string> errors;
    std::vector<StepEvents> events;

    // Thread control.
    std::thread thread;
    std::mutex control;
    std::condition_variable wake;     ///< to the physics thread: stop, pause, resume, single step
    std::condition_variable changed;  ///< to the controller: idle, single step done
    bool stopRequested = false, pauseRequested = false, idle = false;
    int singleSteps = 0;
    std::atomic<bool> threadRunning{false};

    // Runtime clock: advance() moves `manualClock`; while the thread runs it is clockBase + steady time since start.
    std::atomic<double> clockBase{0};
    std::atomic<SteadyClock::rep> threadStart{0};
    std::atomic<double> manualClock{0};

    // Debug drawing: the stepping thread only ever try-locks debugMutex, so it never waits for the render side.
    std::atomic<bool> debugWanted{false};
    std::mutex debugMutex;  ///< guards debugOptions, debugReady and debugFresh
    DebugDrawOptions debugOptions;
    DebugLines debugReady;
    bool debugFresh = false;
    DebugLineBatch debugBatch;  ///< stepping side only

    // Render side.
    std::mutex readerMutex;  ///< between render-side callers only; the physics thread never takes it
    RenderFrame frame;

    Impl(World&& w, const RuntimeSettings& s)
        : world(std::move(w)), settings(s), clock(1.0 / s.rate, s.maxStepsPerWake), stepSeconds(1.0 / s.rate) {}

    double steadyClockTime() const {
        const SteadyClock::duration since(SteadyClock::now().time_since_epoch().count() - threadStart.load());
        return clockBase.load() + std::chrono::duration<double>(since).count();
    }

    double now() const { return threadRunning.load() ? steadyClockTime() : manualClock.load(); }

    void publish(double dueClock) {
        const int b = snapshots.beginWrite();
        Snapshot& s = snapshots.buffer(b);
        detail::writeSnapshot(world, bufferLayout[b] != layoutVersion, s);
        bufferLayout[b] = layoutVersion;
        s.step = world.stepCount();
        s.time = simTime;
        s.clockTime = dueClock;
        s.profile = world.lastProfile();
        s.stats = stats.load();
        snapshots.publish(b);
        if (debugWanted.load(std::memory_order_relaxed)) drawDebug();
    }

    void drawDebug() {
        DebugDrawOptions options;
        {
            std::unique_lock lock(debugMutex, std::try_to_lock);
            if (!lock.owns_lock()) return;
            options = debugOptions;
        }
        debugBatch.lines.clear();
        world.debugDraw(debugBatch, options);
        debugBatch.lines.step = world.stepCount();
        std::unique_lock lock(debugMutex, std::try_to_lock);
        if (!lock.owns_lock()) return;
        std::swap(debugReady, debugBatch.lines);
        debugFresh = true;
    }

    /// Applies `commands` (recording them) and runs one step that was due at `dueClock`.
    void stepOnce(double dueClock, std::vector<detail::PendingCommand>& commands) {
        const std::uint64_t step = world.stepCount();
        for (detail::PendingCommand& c : commands) {
            if (settings.recordInputs) newlyRecorded.push_back({step, c.command});
            detail::applyCommand(world, c.command,
                                 {static_cast<float>(clock.stepSeconds()), kinematicMoves, characters}, &c.reply,
                                 newErrors);
            if (detail::changesLayout(c.command)) ++layoutVersion;
        }
        commands.clear();
        kinematicMoves.beforeStep(world, static_cast<float>(clock.stepSeconds()), newErrors);
        characters.update(static_cast<float>(clock.stepSeconds()));
        if (!newlyRecorded.empty() || !newErrors.empty()) {
            std::lock_guard lock(outputMutex);
            recording.insert(recording.end(), newlyRecorded.begin(), newlyRecorded.end());
            errors.insert(errors.end(), newErrors.begin(), newErrors.end());
            newlyRecorded.clear();
            newErrors.clear();
        }
        const double dt = clock.stepSeconds();
        world.step(static_cast<float>(dt));
        kinematicMoves.afterStep(world);
        characters.publish();
        keepEvents();
        simTime += dt;
        stats.steps.fetch_add(1, std::memory_order_relaxed);
        stats.lastStepMs.store(world.lastProfile().stepMs, std::memory_order_relaxed);
        publish(dueClock);
    }

    /// The step's events, for takeEvents; the oldest go once a second of steps is waiting.
    void keepEvents() {
        const ContactEvents& c = world.contactEvents();
        const SensorEvents& s = world.sensorEvents();
        if (c.begins.empty() && c.ends.empty() && c.hits.empty() && s.begins.empty() && s.ends.empty()) return;
        std::lock_guard lock(outputMutex);
        events.push_back({world.stepCount(), c, s});
        const auto kept = static_cast<std::size_t>(std::max(1.0, settings.rate));
        if (events.size() > kept) events.erase(events.begin(), events.end() - static_cast<std::ptrdiff_t>(kept));
    }

    void stepFromQueue(double dueClock) {
        inputs.takeAll(applying);
        stepOnce(dueClock, applying);
    }

    /// One wake-up of the fixed-step clock at runtime-clock time `t`, `elapsed` after the previous one.
    void wakeUp(double elapsed, double t) {
        const int n = clock.advance(elapsed);
        const double dt = clock.stepSeconds();
        for (int k = 0; k < n; ++k) stepFromQueue(t - clock.remainder() - (n - 1 - k) * dt);
        if (n > 0) stats.wakeups.fetch_add(1, std::memory_order_relaxed);
        if (static_cast<std::uint32_t>(n) > stats.maxStepsPerWake.load(std::memory_order_relaxed))
            stats.maxStepsPerWake.store(static_cast<std::uint32_t>(n), std::memory_order_relaxed);
        stats.behind.store(clock.behind(), std::memory_order_relaxed);
        stats.droppedSteps.store(clock.droppedSteps(), std::memory_order_relaxed);
        stats.droppedSeconds.store(clock.droppedSeconds(), std::memory_order_relaxed);
        const double window = t - windowClock;
        if (window >= kStatsWindowSeconds) {
            const std::uint64_t steps = stats.steps.load(std::memory_order_relaxed);
            stats.physicsHz.store(static_cast<double>(steps - windowSteps) / window, std::memory_order_relaxed);
            stats.slowdown.store((simTime - windowSim) / window, std::memory_order_relaxed);
            startWindow(t);
        }
    }

    void startWindow(double t) {
        windowClock = t;
        windowSim = simTime;
        windowSteps = stats.steps.load(std::memory_order_relaxed);
    }

    void threadMain() {
        double last = steadyClockTime();
        std::unique_lock lock(control);
        for (;;) {
            if (stopRequested) break;
            if (singleSteps > 0) {
                lock.unlock();
                stepFromQueue(steadyClockTime());
                lock.lock();
                --singleSteps;
                changed.notify_all();
                continue;
            }
            if (pauseRequested) {
                idle = true;
                changed.notify_all();
                wake.wait(lock, [&] { return stopRequested || !pauseRequested || singleSteps > 0; });
                idle = false;
                if (!pauseRequested) {
                    // Paused time is not simulated.
                    last = steadyClockTime();
                    clock.reset();
                    startWindow(last);
                }
                continue;
            }
            lock.unlock();
            const double t = steadyClockTime();
            wakeUp(t - last, t);
            last = t;
            const auto sleep = std::chrono::duration<double>(clock.untilNextStep());
            lock.lock();
            wake.wait_for(lock, sleep, [&] { return stopRequested || pauseRequested || singleSteps > 0; });
        }
        idle = true;
        changed.notify_all();
    }

    /// The world may be touched from outside only while no thread steps it.
    bool worldIsFree() {
        if (!threadRunning.load()) return true;
        std::lock_guard lock(control);
        return pauseRequested && idle && singleSteps == 0;
    }

    const RenderFrame& blend(bool fromClock, double clockSeconds, float alpha) {
        const Snapshot* older = nullptr;
        const Snapshot* newer = nullptr;
        if (!snapshots.acquire(older, newer)) {
            frame = RenderFrame{};
            return frame;
        }
        if (fromClock) {
            const double dt = newer->time - older->time;
            alpha = dt > 0 ? static_cast<float>((clockSeconds - newer->clockTime) / dt) : 1.0f;
        }
        interpolateSnapshots(*older, *newer, alpha, frame);
        return frame;
    }
};

Runtime::Runtime(World world, const RuntimeSettings& settings) {
    validateSettings("Runtime", settings);
    impl_ = std::make_unique<Impl>(std::move(world), settings);
}

Runtime::~Runtime() { stop(); }

void Runtime::start() {
    Impl& r = *impl_;
    if (r.threadRunning.load()) fail("Runtime::start", "the physics thread is already running");
    r.stopRequested = r.pauseRequested = r.idle = false;
    r.singleSteps = 0;
    r.clockBase.store(r.manualClock.load());
    r.threadStart.store(SteadyClock::now().time_since_epoch().count());
    r.clock.reset();
    r.startWindow(r.manualClock.load());
    ++r.layoutVersion;
    r.threadRunning.store(true);
    r.thread = std::thread([&r] { r.threadMain(); });
}

void Runtime::stop() {
    Impl& r = *impl_;
    if (!r.threadRunning.load()) return;
    {
        std::lock_guard lock(r.control);
        r.stopRequested = true;
    }
    r.wake.notify_all();
    r.thread.join();
    r.manualClock.store(r.steadyClockTime());
    r.threadRunning.store(false);
    std::lock_guard lock(r.control);
    r.pauseRequested = false;
}

bool Runtime::running() const { return impl_->threadRunning.load(); }

void Runtime::pause() {
    Impl& r = *impl_;
    if (!r.threadRunning.load()) return;
    std::unique_lock lock(r.control);
    r.pauseRequested = true;
    r.wake.notify_all();
    r.changed.wait(lock, [&] { return r.idle; });
}

void Runtime::resume() {
    Impl& r = *impl_;
    {
        std::lock_guard lock(r.control);
        r.pauseRequested = false;
    }
    r.wake.notify_all();
}

bool Runtime::paused() const {
    std::lock_guard lock(impl_->control);
    return impl_->pauseRequested;
}

void Runtime::singleStep() {
    Impl& r = *impl_;
    if (!r.threadRunning.load()) {
        r.stepFromQueue(r.manualClock.load());
        return;
    }
    std::unique_lock lock(r.control);
    if (!r.pauseRequested) fail("Runtime::singleStep", "the runtime is running; pause it first");
    ++r.singleSteps;
    r.wake.notify_all();
    r.changed.wait(lock, [&] { return r.singleSteps == 0 && r.idle; });
}

void Runtime::advance(double seconds) {
    Impl& r = *impl_;
    if (r.threadRunning.load()) fail("Runtime::advance", "the physics thread is running; stop it first");
    // The clock counts nanoseconds in 64 bits: a million seconds per call is far from overflow and from any use.
    if (!std::isfinite(seconds) || seconds < 0 || seconds > 1e6)
        fail("Runtime::advance", "seconds must be in [0, 1e6] (got " + std::to_string(seconds) + ")");
    r.manualClock.store(r.manualClock.load() + seconds);
    r.wakeUp(seconds, r.manualClock.load());
}

void Runtime::replay(const std::vector<RecordedInput>& inputs, std::uint64_t untilStep) {
    static constexpr const char* kWhere = "Runtime::replay";
    Impl& r = *impl_;
    if (r.threadRunning.load()) fail(kWhere, "the physics thread is running; stop it first");
    std::size_t next = 0;
    std::vector<detail::PendingCommand> commands;
    while (r.world.stepCount() < untilStep) {
        const std::uint64_t step = r.world.stepCount();
        for (; next < inputs.size() && inputs[next].step <= step; ++next) {
            if (inputs[next].step < step)
                fail(kWhere, "input " + std::to_string(next) + " is for step " + std::to_string(inputs[next].step) +
                                 ", which the world has passed (it is at step " + std::to_string(step) +
                                 "; inputs must be in step order)");
            commands.push_back({inputs[next].command, {}});
        }
        r.stepOnce(r.manualClock.load(), commands);
    }
}

World& Runtime::world() {
    Impl& r = *impl_;
    if (!r.worldIsFree()) fail("Runtime::world", "the physics thread is stepping the world; pause or stop it first");
    ++r.layoutVersion;  // the caller may add, remove or move anything
    return r.world;
}

const RuntimeSettings& Runtime::settings() const { return impl_->settings; }

void Runtime::setSettings(const RuntimeSettings& settings) {
    Impl& r = *impl_;
    validateSettings("Runtime::setSettings", settings);
    if (!r.worldIsFree()) fail("Runtime::setSettings", "the physics thread is stepping; pause or stop it first");
    r.settings = settings;
    r.clock.configure(1.0 / settings.rate, settings.maxStepsPerWake);
    r.stepSeconds.store(1.0 / settings.rate);
}

float Runtime::stepSeconds() const { return static_cast<float>(impl_->stepSeconds.load()); }

RuntimeStats Runtime::stats() const { return impl_->stats.load(); }

double Runtime::clockTime() const { return impl_->now(); }

void Runtime::submit(const Command& command) {
    detail::validateCommand(command);
    impl_->inputs.push({command, {}});
}

std::future<BodyId> Runtime::spawn(const BodyDef& def) {
    std::promise<BodyId> promise;
    std::future<BodyId> future = promise.get_future();
    impl_->inputs.push({SpawnBodyCommand{def}, std::move(promise)});
    return future;
}

std::future<std::optional<RayHit>> Runtime::castRay(const CastRayCommand& ray) {
    detail::validateCommand(ray);
    std::promise<std::optional<RayHit>> promise;
    auto future = promise.get_future();
    impl_->inputs.push({ray, std::move(promise)});
    return future;
}

std::vector<std::string> Runtime::takeInputErrors() {
    std::lock_guard lock(impl_->outputMutex);
    std::vector<std::string> out;
    out.swap(impl_->errors);
    return out;
}

std::vector<RecordedInput> Runtime::takeRecording() {
    std::lock_guard lock(impl_->outputMutex);
    std::vector<RecordedInput> out;
    out.swap(impl_->recording);
    return out;
}

CharacterId Runtime::addCharacter(Vec3 feet, const CharacterSettings& settings) {
    Impl& r = *impl_;
    if (!r.worldIsFree())
        fail("Runtime::addCharacter", "the physics thread is stepping the world; pause or stop it first");
    ++r.layoutVersion;  // its body is new
    const CharacterId id = r.characters.add(r.world, feet, settings);
    r.characters.publish();
    return id;
}

void Runtime::removeCharacter(CharacterId id) {
    Impl& r = *impl_;
    if (!r.worldIsFree())
        fail("Runtime::removeCharacter", "the physics thread is stepping the world; pause or stop it first");
    ++r.layoutVersion;
    r.characters.remove(id);
}

std::optional<CharacterState> Runtime::character(CharacterId id) const { return impl_->characters.state(id); }

std::vector<StepEvents> Runtime::takeEvents() {
    std::lock_guard lock(impl_->outputMutex);
    std::vector<StepEvents> out;
    out.swap(impl_->events);
    return out;
}

void Runtime::setDebugDraw(const std::optional<DebugDrawOptions>& options) {
    Impl& r = *impl_;
    std::lock_guard lock(r.debugMutex);
    if (options) r.debugOptions = *options;
    r.debugWanted.store(options.has_value(), std::memory_order_relaxed);
}

bool Runtime::takeDebugLines(DebugLines& lines) {
    Impl& r = *impl_;
    std::lock_guard lock(r.debugMutex);
    if (!r.debugFresh) return false;
    std::swap(lines, r.debugReady);
    r.debugFresh = false;
    return true;
}

const RenderFrame& Runtime::latest(float alpha) {
    std::lock_guard lock(impl_->readerMutex);
    return impl_->blend(false, 0, alpha);
}

const RenderFrame& Runtime::interpolate(double clockSeconds) {
    std::lock_guard lock(impl_->readerMutex);
    return impl_->blend(true, clockSeconds, 0);
}

}  // namespace rubble
