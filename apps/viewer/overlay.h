#pragma once
// The Dear ImGui overlay: rates, counts, the per-stage profile, the runtime's slowdown, debug-draw toggles, the
// selected body and the keys.
#include <cstdint>
#include <optional>
#include <string>

#include "rubble/runtime.h"

namespace rubble::viewer {

/// Debug-draw layers the overlay toggles.
struct DebugLayers {
    bool contacts = false;
    bool aabbs = false;
    bool islands = false;
    bool sleeping = true;  ///< sleeping bodies tinted (and, with islands, drawn in the sleeping colour)
    bool cells = false;    ///< the broad phase's grid cells (when the grid ran) and the static tree's top boxes
    bool joints = false;
    friend bool operator==(const DebugLayers&, const DebugLayers&) = default;
};

struct SelectedBody {
    BodyId id;
    std::string type;   ///< static, kinematic or dynamic
    std::string shape;  ///< shape type
    Vec3 position, velocity;
    bool velocityExact = false;  ///< from the world (paused), else estimated from snapshots
};

struct OverlayInfo {
    std::string title;
    double renderFps = 0;
    const RenderFrame* frame = nullptr;
    RuntimeStats stats;
    double rate = 120;
    bool paused = false;
    bool followCamera = false;
    bool marble = false;
    bool autopilot = false;
    bool atGoal = false;
    bool character = false;  ///< the character demo
    int coins = 0;
    bool atEnd = false;
    std::size_t instances = 0, triangles = 0, lines = 0;
    int drawCalls = 0;
    std::optional<SelectedBody> selected;
};

/// Draws the overlay; the toggles write into `layers`.
void drawOverlay(const OverlayInfo& info, DebugLayers& layers);

}  // namespace rubble::viewer
