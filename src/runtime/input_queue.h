#pragma once
// Game input for the runtime: commands from any number of producer threads, swapped out under a mutex by the physics
// thread at a step boundary and applied there in submission order. Spawns and ray casts carry a promise that the
// physics thread fulfils after applying them.
#include <future>
#include <mutex>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "rubble/runtime.h"
#include "rubble/world.h"
#include "runtime/kinematic_moves.h"
#include "runtime/runtime_characters.h"

namespace rubble::detail {

using Reply = std::variant<std::monostate, std::promise<BodyId>, std::promise<std::optional<RayHit>>>;

struct PendingCommand {
    Command command;
    Reply reply;
};

/// Refuses non-finite numbers and zero directions on the submitting thread (rubble::Error naming the field).
void validateCommand(const Command& command);

/// What commands act on besides the world.
struct CommandTargets {
    float stepSeconds = 0;
    KinematicMoves& moves;
    RuntimeCharacters& characters;
};

/// Applies one command to the world (or the runtime's kinematic moves and characters) before a step and fulfils its
/// reply. A command the world refuses (a stale handle, a bad BodyDef) does not stop the runtime: its error goes to
/// the reply when there is one, else to `errors`.
void applyCommand(World& world, const Command& command, CommandTargets targets, Reply* reply,
                  std::vector<std::string>& errors);

/// True for commands that add, remove or teleport bodies, after which snapshots must be rewritten in full.
bool changesLayout(const Command& command);

class InputQueue {
public:
    void push(PendingCommand command) {
        std::lock_guard lock(mutex_);
        pending_.push_back(std::move(command));
    }
    /// Moves everything queued into `out` (cleared first); `out`'s old storage becomes the queue's, so the
    /// steady state allocates nothing.
    void takeAll(std::vector<PendingCommand>& out) {
        out.clear();
        std::lock_guard lock(mutex_);
        out.swap(pending_);
    }

private:
    std::mutex mutex_;
    std::vector<PendingCommand> pending_;
};

}  // namespace rubble::detail
