#pragma once
// Library-internal access to a World's state for code that is not a World member (the runtime's snapshots).
#include "world/world_impl.h"

namespace rubble::detail {

struct WorldAccess {
    static World::Impl& of(World& world) { return *world.impl_; }
    static const World::Impl& of(const World& world) { return *world.impl_; }
};

}  // namespace rubble::detail
