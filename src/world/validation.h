#pragma once
// The checks at the API boundary and the words of what they refuse: every refusal is a rubble::Error reading
// "where: what", where `where` names the call or the definition (World::createBody, ConvexHullDef) and `what` the
// field and its value.
#include <string>

#include "rubble/math.h"

namespace rubble::detail {

/// Throws rubble::Error as "where: what".
[[noreturn]] void fail(const char* where, const std::string& what);

/// A number as a message shows it: short ("-1", "0.5"), non-finite values spelt out.
std::string formatNumber(double value);
std::string describe(Vec3 v);
std::string describe(Quat q);

void requireFinite(const char* where, const char* name, Vec3 v);
void requireFinite(const char* where, const char* name, float f);
void requireNonNegative(const char* where, const char* name, float f);
/// `f` in [lo, hi] (a limit of include/rubble/limits.h; the message names it and docs/limits.md), `unit` after it.
void requireWithin(const char* where, const char* name, float f, float lo, float hi, const char* unit);
/// Every coordinate within limits::kMaxCoordinate of the origin (false for NaN): body positions, mesh vertices, and
/// the scene loader's bodies, so that all refuse at one number.
bool withinCoordinateLimit(Vec3 v);
/// Every coordinate within limits::kMaxCoordinate of the origin.
void requireInWorld(const char* where, const char* name, Vec3 v);
/// Unit quaternions are required; small drift (from user arithmetic) is normalised away, anything else refused.
Quat requireUnit(const char* where, const char* name, Quat q);

}  // namespace rubble::detail
