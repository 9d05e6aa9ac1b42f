#pragma once
// The characters a runtime steps (Runtime::addCharacter): each step, after the commands and the kinematic moves
// (platforms move first, so that a character rides them), every character walks as its last WalkCharacterCommand
// said, and its state is kept for other threads to read.
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "rubble/character.h"
#include "rubble/runtime.h"
#include "rubble/world.h"

namespace rubble::detail {

class RuntimeCharacters {
public:
    /// While the world is free (no thread stepping it).
    CharacterId add(World& world, Vec3 feet, const CharacterSettings& settings);
    void remove(CharacterId id);
    /// Physics side. Throws rubble::Error for a character that is not (or no longer) there.
    void walk(const WalkCharacterCommand& command);
    /// Physics side, before a step of `dt`.
    void update(float dt);
    /// Physics side, after the step: the states other threads read.
    void publish();
    /// Any thread.
    std::optional<CharacterState> state(CharacterId id) const;

private:
    struct Entry {
        std::unique_ptr<CharacterController> controller;
        Vec3 walk;
        float jumpSpeed = 0;
    };
    Entry& entry(CharacterId id, const char* where);

    std::vector<Entry> entries_;  ///< by CharacterId::index; removed ones keep their place, without a controller
    mutable std::mutex statesMutex_;
    std::vector<std::optional<CharacterState>> states_;
};

}  // namespace rubble::detail
