#include "runtime/runtime_characters.h"

#include <string>

#include "world/validation.h"

namespace rubble::detail {

CharacterId RuntimeCharacters::add(World& world, Vec3 feet, const CharacterSettings& settings) {
    entries_.push_back({std::make_unique<CharacterController>(world, feet, settings), {}, 0});
    std::lock_guard lock(statesMutex_);
    states_.emplace_back();
    return {static_cast<unsigned>(entries_.size() - 1), 1};
}

RuntimeCharacters::Entry& RuntimeCharacters::entry(CharacterId id, const char* where) {
    if (id.isNull() || id.index >= entries_.size() || !entries_[id.index].controller)
        fail(where, "character " + std::to_string(id.index) + " is not in this runtime (null, removed, or another's)");
    return entries_[id.index];
}

void RuntimeCharacters::remove(CharacterId id) {
    entry(id, "Runtime::removeCharacter").controller.reset();
    std::lock_guard lock(statesMutex_);
    states_[id.index].reset();
}

void RuntimeCharacters::walk(const WalkCharacterCommand& command) {
    Entry& e = entry(command.character, "WalkCharacterCommand");
    e.walk = command.velocity;
    if (command.jumpSpeed > 0) e.jumpSpeed = command.jumpSpeed;
}

void RuntimeCharacters::update(float dt) {
    for (Entry& e : entries_) {
        if (!e.controller) continue;
        // A jump waits for the ground; the command that asked for it is the last say until then.
        if (e.jumpSpeed > 0 && e.controller->jump(e.jumpSpeed)) e.jumpSpeed = 0;
        e.controller->update(dt, e.walk);
    }
}

void RuntimeCharacters::publish() {
    std::lock_guard lock(statesMutex_);
    for (std::size_t k = 0; k < entries_.size(); ++k) {
        const CharacterController* c = entries_[k].controller.get();
        if (c)
            states_[k] =
                CharacterState{c->position(), c->velocity(), c->grounded(), c->ground(), c->groundNormal(), c->body()};
    }
}

std::optional<CharacterState> RuntimeCharacters::state(CharacterId id) const {
    std::lock_guard lock(statesMutex_);
    if (id.isNull() || id.index >= states_.size()) return std::nullopt;
    return states_[id.index];
}

}  // namespace rubble::detail
