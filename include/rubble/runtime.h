#pragma once
// The runtime: a world stepped at a fixed rate on its own physics thread, transforms published to the render side
// as lock-free snapshots that it interpolates, and game input applied through a queue at step boundaries.
#include <cstdint>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "rubble/body.h"
#include "rubble/character.h"
#include "rubble/debug_draw.h"
#include "rubble/events.h"
#include "rubble/id.h"
#include "rubble/math.h"
#include "rubble/profile.h"
#include "rubble/query.h"

namespace rubble {

class World;

/// How the runtime paces its world.
struct RuntimeSettings {
    /// Steps per second of simulated time; each step advances the world by 1 / rate.
    double rate = 120.0;
    /// Most steps one wake-up of the physics thread may run to catch up. When more are due (the machine cannot keep
    /// up, or the process was stalled), the excess time is dropped: simulated time slows down instead of spiralling.
    int maxStepsPerWake = 4;
    /// Keep every applied input (step index + command) for Runtime::takeRecording, to replay a run.
    bool recordInputs = false;
};

/// Pacing counters, read from any thread.
struct RuntimeStats {
    std::uint64_t steps = 0;            ///< steps the runtime has run
    std::uint64_t wakeups = 0;          ///< times the physics clock ran due steps (thread wake-ups or advance calls)
    std::uint32_t maxStepsPerWake = 0;  ///< most steps one wake-up ran; never above the cap
    std::uint64_t droppedSteps = 0;     ///< due steps given up because of the cap
    double droppedSeconds = 0;          ///< wall time those steps stood for
    bool behind = false;                ///< the last wake-up dropped time
    /// Simulated over wall seconds in the last measurement window (about half a second): 1 in real time, below 1
    /// when steps are dropped.
    double slowdown = 1.0;
    double physicsHz = 0;  ///< steps per wall-clock second over the same window
    double lastStepMs = 0;
};

/// Per-slot flags of a snapshot body.
enum SnapshotBodyFlags : std::uint8_t {
    kSnapshotStatic = 1u << 0,
    kSnapshotKinematic = 1u << 1,
    kSnapshotAsleep = 1u << 2,
    kSnapshotFrozen = 1u << 3,
};

/// Poses of every body after one step, in structure-of-arrays form indexed by body slot (BodyId::index), so that a
/// renderer matches a body across snapshots by its slot and generation: generation[slot] == 0 means no body.
/// Positions and orientations are of each shape's local origin (what World::transform returns).
struct Snapshot {
    std::uint64_t step = 0;  ///< World::stepCount() after the step
    double time = 0;         ///< simulated seconds since the runtime started (dropped time not counted)
    double clockTime = 0;    ///< runtime clock (seconds) at which this step was due
    std::vector<std::uint32_t> generation;
    std::vector<float> px, py, pz;
    std::vector<float> qx, qy, qz, qw;
    std::vector<std::uint32_t> shape;  ///< ShapeId::index of the body's shape
    std::vector<std::uint8_t> flags;   ///< SnapshotBodyFlags
    Profile profile;                   ///< of the step that made this snapshot
    RuntimeStats stats;                ///< when it was published

    std::uint32_t slotCount() const { return static_cast<std::uint32_t>(generation.size()); }
    BodyId body(std::uint32_t slot) const { return BodyId{slot, generation[slot]}; }
    Transform transform(std::uint32_t slot) const {
        return {{px[slot], py[slot], pz[slot]}, {qx[slot], qy[slot], qz[slot], qw[slot]}};
    }
};

/// What the render thread draws: the two newest snapshots blended by alpha. Bodies present in both (same slot and
/// generation) are interpolated (positions linearly, orientations by normalised lerp along the shortest arc); bodies
/// that just appeared take the newer pose; bodies gone from the newer snapshot are absent.
struct RenderFrame : Snapshot {
    float alpha = 1;              ///< 0: the older snapshot, 1: the newer one
    std::uint64_t olderStep = 0;  ///< step of the older snapshot
    std::uint32_t bodyCount = 0;  ///< live slots
};

// ---------------------------------------------------------------------------------------------------------------
// Input commands: applied by the physics thread at the next step boundary, in submission order.

struct AddForceCommand {
    BodyId body;
    Vec3 force;
};
struct AddForceAtPointCommand {
    BodyId body;
    Vec3 force;
    Vec3 point;  ///< world
};
struct AddTorqueCommand {
    BodyId body;
    Vec3 torque;
};
struct ApplyImpulseCommand {
    BodyId body;
    Vec3 impulse;
};
struct ApplyImpulseAtPointCommand {
    BodyId body;
    Vec3 impulse;
    Vec3 point;  ///< world
};
struct ApplyAngularImpulseCommand {
    BodyId body;
    Vec3 impulse;
};
struct SetVelocityCommand {
    BodyId body;
    Vec3 linear;
    Vec3 angular;
};
struct SetTransformCommand {
    BodyId body;
    Vec3 position;
    Quat orientation;
};
struct SpawnBodyCommand {
    BodyDef def;
};
struct RemoveBodyCommand {
    BodyId body;
};
struct CastRayCommand {
    Vec3 origin;
    Vec3 direction;
    float maxDistance = 1e30f;
    QueryFilter filter;
};

/// Moves a kinematic body to a pose over `duration` seconds (World::moveKinematic, steered again every step with the
/// time left), and stops it there. A game sends one per frame with the frame's time; a later move of the same body
/// replaces the one under way.
struct MoveKinematicCommand {
    BodyId body;
    Vec3 position;
    Quat orientation;
    float duration = 0;  ///< s, rounded to whole steps; less than one step: the next step
};
/// Makes a character of the runtime (Runtime::addCharacter) walk at `velocity` (m/s, horizontal) from the next step
/// until the next such command; jumpSpeed > 0 also makes it jump at that speed as soon as it stands on something.
struct WalkCharacterCommand {
    CharacterId character;
    Vec3 velocity;
    float jumpSpeed = 0;
};
/// World::setContactEvents.
struct SetContactEventsCommand {
    BodyId body;
    bool enabled = true;
};

using Command = std::variant<AddForceCommand, AddForceAtPointCommand, AddTorqueCommand, ApplyImpulseCommand,
                             ApplyImpulseAtPointCommand, ApplyAngularImpulseCommand, SetVelocityCommand,
                             SetTransformCommand, SpawnBodyCommand, RemoveBodyCommand, CastRayCommand,
                             MoveKinematicCommand, SetContactEventsCommand, WalkCharacterCommand>;

/// Where a character of the runtime is, after the last step (CharacterController's accessors).
struct CharacterState {
    Vec3 feet;
    Vec3 velocity;
    bool grounded = false;
    BodyId ground;
    Vec3 groundNormal;
    BodyId body;  ///< its kinematic capsule, for rendering from the snapshots
};

/// The events of one step (World::contactEvents, World::sensorEvents), as the runtime hands them to the game.
struct StepEvents {
    std::uint64_t step = 0;  ///< World::stepCount() after the step
    ContactEvents contacts;
    SensorEvents sensors;
};

/// A command as it was applied: before the step that took the world from `step` to `step + 1`.
struct RecordedInput {
    std::uint64_t step = 0;
    Command command;
};

/// Runs a World at a fixed rate. The runtime owns the world and its one physics thread; the world's own task pool
/// does each step's parallel work. While the thread runs, the world is touched only through the runtime (commands,
/// snapshots); world() hands it out when the runtime is stopped or paused.
///
/// Without start(), advance(seconds) drives the same fixed-step clock synchronously on the caller with the elapsed
/// time it is given, which makes runs deterministic for tests and tools.
class Runtime {
public:
    explicit Runtime(World world, const RuntimeSettings& settings = {});
    /// Stops and joins the physics thread if it runs.
    ~Runtime();
    Runtime(const Runtime&) = delete;
    Runtime& operator=(const Runtime&) = delete;

    // ---- Control (from one controlling thread) ----

    /// Starts the physics thread stepping against the steady clock. Throws rubble::Error if already running.
    void start();
    /// Stops and joins the physics thread after its current step; no effect if it is not running.
    void stop();
    bool running() const;
    /// Stops stepping after the current step (returns once the thread is idle); time spent paused is not simulated.
    void pause();
    void resume();
    bool paused() const;
    /// While paused or stopped: runs exactly one step (inputs applied first) and publishes it; returns when done.
    void singleStep();
    /// Without the thread: adds `seconds` of elapsed time to the clock and runs the steps now due (at most the cap),
    /// on the caller. Throws rubble::Error while the thread runs or for negative or non-finite time.
    void advance(double seconds);
    /// Replays recorded inputs on the caller (thread not running): steps the world until stepCount() == untilStep,
    /// applying each input before the step whose index it carries. Replies to spawns and ray casts are dropped.
    void replay(const std::vector<RecordedInput>& inputs, std::uint64_t untilStep);

    /// The world, for set-up and inspection while stopped or paused. Throws rubble::Error while stepping.
    World& world();
    /// A character the runtime moves every step, before the step and after the kinematic moves (so that it rides
    /// them), as WalkCharacterCommand says. While stopped or paused (rubble::Error otherwise, and for bad settings).
    CharacterId addCharacter(Vec3 feet, const CharacterSettings& settings = {});
    /// Removes a character and its body, while stopped or paused.
    void removeCharacter(CharacterId id);
    /// The character after the last step (any thread); nullopt for one not in this runtime.
    std::optional<CharacterState> character(CharacterId id) const;
    const RuntimeSettings& settings() const;
    /// Changes the rate, cap or recording while stopped or paused.
    void setSettings(const RuntimeSettings& settings);
    /// 1 / rate.
    float stepSeconds() const;
    RuntimeStats stats() const;
    /// Seconds since the runtime was made: the steady clock while the thread runs, else the time given to advance.
    double clockTime() const;

    // ---- Input (any thread) ----

    /// Queues a command for the next step boundary. Non-finite vectors and zero ray directions are refused here
    /// (rubble::Error); a stale body handle is found when the command is applied and reported by takeInputErrors.
    void submit(const Command& command);
    /// Queues a spawn; the future holds the new body's handle after the step boundary that applied it (or the
    /// rubble::Error the world raised).
    std::future<BodyId> spawn(const BodyDef& def);
    /// Queues a ray cast against the world as it is at the step boundary; the future holds the answer.
    std::future<std::optional<RayHit>> castRay(const CastRayCommand& ray);
    /// Messages of commands the world refused when they were applied (stale handles and the like), oldest first.
    std::vector<std::string> takeInputErrors();
    /// The inputs applied since the last call (RuntimeSettings::recordInputs), in the order they were applied.
    std::vector<RecordedInput> takeRecording();
    /// The events of the steps run since the last call that had any (bodies that ask: BodyDef::contactEvents,
    /// BodyDef::sensor), oldest first. Kept for up to one second of steps (rate of them): a game that stops taking
    /// them loses the oldest, not its memory.
    std::vector<StepEvents> takeEvents();

    // ---- Render side (one render thread; never blocks the physics thread) ----

    /// The two newest snapshots blended by alpha (clamped to [0, 1]). The frame is owned by the runtime and stays
    /// valid until the next latest/interpolate call; empty (no slots) before the first step.
    const RenderFrame& latest(float alpha);
    /// The same with alpha from the clock: how far `clockSeconds` (see clockTime) is past the newer snapshot's due
    /// time, in steps. Rendering then lags the simulation by up to one step and never extrapolates.
    const RenderFrame& interpolate(double clockSeconds);
    const RenderFrame& interpolate() { return interpolate(clockTime()); }

    // ---- Debug drawing ----

    /// Makes whichever thread steps draw the world (World::debugDraw with `options`) into a line batch after each
    /// step, or stops it (nullopt). The drawing costs the stepping thread its time; it never waits for the render
    /// side (a step whose batch cannot be handed over at once is skipped). Any thread.
    void setDebugDraw(const std::optional<DebugDrawOptions>& options);
    /// Render side: swaps the newest batch into `lines` when one was drawn since the last call and returns true;
    /// else returns false and leaves `lines` alone.
    bool takeDebugLines(DebugLines& lines);

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

/// Blends two snapshots into `out` (see RenderFrame); `out` keeps its capacity, so a frame allocates nothing once
/// the slot count stops growing. Exposed for tools and tests.
void interpolateSnapshots(const Snapshot& older, const Snapshot& newer, float alpha, RenderFrame& out);

}  // namespace rubble
