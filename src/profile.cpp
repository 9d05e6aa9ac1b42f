#include "rubble/profile.h"

#include <array>

namespace rubble {

std::string_view stageName(Stage s) {
    static constexpr std::array<std::string_view, kStageCount> kNames{
        "integrate_velocities", "update_bounds", "broad_phase", "narrow_phase", "integrate_positions",
    };
    const int i = static_cast<int>(s);
    return i >= 0 && i < kStageCount ? kNames[i] : "?";
}

}  // namespace rubble
