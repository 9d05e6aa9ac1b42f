#include "rubble/profile.h"

#include <iterator>

namespace rubble {

std::string_view stageName(Stage s) {
    static constexpr std::string_view kNames[] = {
        "integrate_velocities",  //
        "update_bounds",         //
        "broad_phase",           //
        "narrow_phase",          //
        "contact_cache",         //
        "islands",               //
        "solver",                //
        "integrate_positions",   //
        "ccd",                   //
        "events",                //
    };
    // A stage added to the enum without a name here fails the build instead of printing an empty name.
    static_assert(std::size(kNames) == kStageCount, "every stage needs a name");
    const int i = static_cast<int>(s);
    return i >= 0 && i < kStageCount ? kNames[i] : "?";
}

}  // namespace rubble
