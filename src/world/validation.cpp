#include "world/validation.h"

#include <cmath>
#include <sstream>

#include "rubble/error.h"
#include "rubble/limits.h"

namespace rubble::detail {

[[noreturn]] void fail(const char* where, const std::string& what) { throw Error(std::string(where) + ": " + what); }

std::string formatNumber(double value) {
    // Default stream formatting keeps messages short ("-1", "0.5") and spells non-finite values out.
    std::ostringstream out;
    out << value;
    return out.str();
}

std::string describe(Vec3 v) {
    std::ostringstream s;
    s << '(' << v.x << ", " << v.y << ", " << v.z << ')';
    return s.str();
}

std::string describe(Quat q) {
    std::ostringstream s;
    s << '(' << q.x << ", " << q.y << ", " << q.z << ", " << q.w << ')';
    return s.str();
}

void requireFinite(const char* where, const char* name, Vec3 v) {
    if (!isFinite(v)) fail(where, std::string(name) + " is not finite " + describe(v));
}

void requireFinite(const char* where, const char* name, float f) {
    if (!std::isfinite(f)) fail(where, std::string(name) + " is not finite (" + formatNumber(f) + ")");
}

void requireNonNegative(const char* where, const char* name, float f) {
    requireFinite(where, name, f);
    if (f < 0) fail(where, std::string(name) + " must be >= 0 (got " + std::to_string(f) + ")");
}

Quat requireUnit(const char* where, const char* name, Quat q) {
    if (!isFinite(q)) fail(where, std::string(name) + " is not finite " + describe(q));
    const float len = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    if (std::fabs(len - 1.0f) > 1e-3f)
        fail(where, std::string(name) + " is not a unit quaternion " + describe(q) + ", length " + std::to_string(len));
    return {q.x / len, q.y / len, q.z / len, q.w / len};
}

void requireWithin(const char* where, const char* name, float f, float lo, float hi, const char* unit) {
    requireFinite(where, name, f);
    if (!(f >= lo && f <= hi))
        fail(where, std::string(name) + " must be in [" + formatNumber(lo) + ", " + formatNumber(hi) + "] " + unit +
                        " (got " + formatNumber(f) + "; docs/limits.md)");
}

bool withinCoordinateLimit(Vec3 v) {
    const float m = limits::kMaxCoordinate;
    return std::abs(v.x) <= m && std::abs(v.y) <= m && std::abs(v.z) <= m;
}

void requireInWorld(const char* where, const char* name, Vec3 v) {
    requireFinite(where, name, v);
    const float m = limits::kMaxCoordinate;
    if (!withinCoordinateLimit(v))
        fail(where, std::string(name) + " " + describe(v) + " lies farther than " + formatNumber(m) +
                        " m from the origin on an axis (float spacing there is " +
                        formatNumber(std::nextafter(m, 2 * m) - m) + " m; docs/limits.md)");
}

}  // namespace rubble::detail
