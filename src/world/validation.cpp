#include "world/validation.h"

#include <cmath>
#include <sstream>

#include "rubble/error.h"

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

}  // namespace rubble::detail
