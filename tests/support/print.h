#pragma once
// GoogleTest printers for Rubble's enums, so parameterised tests name their parameter instead of dumping bytes.
#include <ostream>

#include "rubble/settings.h"

namespace rubble {

inline void PrintTo(Integrator integrator, std::ostream* os) { *os << integratorName(integrator); }
inline void PrintTo(BroadPhaseKind kind, std::ostream* os) { *os << broadPhaseName(kind); }

}  // namespace rubble
