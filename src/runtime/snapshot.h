#pragma once
// Writing a snapshot of a world's body poses (the physics side of the runtime's render hand-off).
#include "rubble/runtime.h"
#include "rubble/world.h"

namespace rubble::detail {

/// Writes every body's pose into `out`, indexed by slot. With `layoutChanged` false the buffer is trusted to hold the
/// same bodies in the same slots as the world (no body added or removed, no static body moved, since it was last
/// written): only the moving bodies' poses and flags are rewritten, in parallel on the world's task pool.
void writeSnapshot(const World& world, bool layoutChanged, Snapshot& out);

}  // namespace rubble::detail
