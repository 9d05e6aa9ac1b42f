// Scene files: reading, JSON parsing and validation. The format is documented in docs/scene_format.md.
//
// Every refusal is a rubble::Error whose message starts with the file name, then either line:column (syntax) or
// "at <JSON pointer>" (meaning), then the problem. Parsing runs in three steps:
//  1. a linear pre-scan that refuses absurd nesting before anything recurses, and notes (with line and column)
//     duplicate keys and numbers that overflow to infinity, which nlohmann accepts silently or reports without
//     a position;
//  2. nlohmann's parser (syntax, UTF-8);
//  3. a walk over the document that checks every key against the keys its object may hold.
#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <variant>

#include <nlohmann/json.hpp>

#include "core/file_reading.h"
#include "rubble/error.h"
#include "rubble/limits.h"
#include "rubble/scene.h"
#include "scene/generators.h"
#include "world/validation.h"

namespace rubble {
namespace {

using Json = nlohmann::ordered_json;
using scene_detail::jsonPointerToken;

constexpr int kMaxDepth = 64;

// ---------------------------------------------------------------------------------------------------------------
// Small text helpers

std::string formatNumber(double v) {
    std::ostringstream s;
    s.precision(9);
    s << v;
    return s.str();
}

std::string formatCount(double v) {
    std::ostringstream s;
    s.setf(std::ios::fixed);
    s.precision(0);
    s << v;
    return s.str();
}

/// Makes text safe to quote in a message: control and non-ASCII bytes become \xNN, and it is cut to `limit`.
std::string printable(std::string_view text, std::size_t limit = 40) {
    std::string out;
    for (const char ch : text) {
        if (out.size() >= limit) {
            out += "...";
            break;
        }
        const auto c = static_cast<unsigned char>(ch);
        if (c >= 0x20 && c < 0x7F) {
            out += ch;
        } else {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02X", c);
            out += buf;
        }
    }
    return out;
}

std::size_t editDistance(std::string_view a, std::string_view b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diag = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
            diag = up;
        }
    }
    return row[b.size()];
}

/// " (did you mean 'x'?)" when a candidate is close, else " (expected one of: a, b, c)"; with `alwaysList` both
/// (for references to names the file defines, where seeing the list helps). Long lists are cut.
template <class Names>
std::string suggestion(std::string_view given, const Names& candidates, std::string_view listIntro = "expected one of",
                       bool alwaysList = false) {
    std::string best;
    std::size_t bestDistance = std::numeric_limits<std::size_t>::max();
    std::string list;
    std::size_t count = 0;
    for (const auto& c : candidates) {
        const std::string_view name(c);
        const std::size_t d = editDistance(given, name);
        if (d < bestDistance) {
            bestDistance = d;
            best = std::string(name);
        }
        if (count < 20) {
            if (!list.empty()) list += ", ";
            list += printable(name);
        } else if (count == 20) {
            list += ", ...";
        }
        ++count;
    }
    if (count == 0) return " (there are none)";
    const bool close = bestDistance <= std::max<std::size_t>(1, given.size() / 3) && bestDistance < given.size();
    const std::string listPart = std::string(listIntro) + ": " + list;
    if (close) return " (did you mean '" + printable(best) + "'?" + (alwaysList ? " " + listPart : std::string()) + ")";
    return " (" + listPart + ")";
}

struct LineColumn {
    std::size_t line = 1, column = 1;
};

/// Line and column (1-based, in bytes) of byte `offset` (0-based) of `text`.
LineColumn lineColumnAt(std::string_view text, std::size_t offset) {
    offset = std::min(offset, text.size());
    LineColumn lc;
    std::size_t lineStart = 0;
    for (std::size_t i = 0; i < offset; ++i) {
        if (text[i] == '\n') {
            ++lc.line;
            lineStart = i + 1;
        }
    }
    lc.column = offset - lineStart + 1;
    return lc;
}

// ---------------------------------------------------------------------------------------------------------------
// Step 1: pre-scan

struct PreScan {
    // First duplicate key / overflowing number, if any, reported after nlohmann accepted the syntax.
    std::optional<std::string> duplicateKey;
    std::optional<std::string> overflow;
};

PreScan preScan(std::string_view text, const std::string& file) {
    PreScan result;
    struct Level {
        bool object = false;
        bool expectKey = false;
        std::unordered_set<std::string_view> keys;
    };
    std::vector<Level> stack;
    stack.reserve(kMaxDepth + 1);
    std::size_t line = 1, lineStart = 0;
    const std::size_t n = text.size();
    auto where = [&](std::size_t i) { return std::to_string(line) + ":" + std::to_string(i - lineStart + 1); };
    for (std::size_t i = 0; i < n; ++i) {
        const char c = text[i];
        switch (c) {
            case '\n':
                ++line;
                lineStart = i + 1;
                break;
            case '{':
            case '[':
                if (static_cast<int>(stack.size()) >= kMaxDepth)
                    throw Error(file + ":" + where(i) + ": nesting deeper than " + std::to_string(kMaxDepth) +
                                " levels at line " + std::to_string(line));
                stack.emplace_back();
                stack.back().object = c == '{';
                stack.back().expectKey = c == '{';
                break;
            case '}':
            case ']':
                if (!stack.empty()) stack.pop_back();
                break;
            case ',':
                if (!stack.empty() && stack.back().object) stack.back().expectKey = true;
                break;
            case ':':
                if (!stack.empty()) stack.back().expectKey = false;
                break;
            case '"': {
                const std::size_t start = i + 1;
                std::size_t j = start;
                while (j < n && text[j] != '"') {
                    if (text[j] == '\\')
                        ++j;  // skip the escaped character (an escaped quote among them)
                    else if (text[j] == '\n')
                        break;  // invalid JSON; nlohmann reports it
                    ++j;
                }
                if (j >= n || text[j] != '"') return result;  // unterminated string: a syntax error for step 2
                const std::string_view key = text.substr(start, j - start);
                if (!stack.empty() && stack.back().object && stack.back().expectKey) {
                    if (!stack.back().keys.insert(key).second && !result.duplicateKey)
                        result.duplicateKey = file + ":" + where(i) + ": duplicate key '" + printable(key) + "'";
                    stack.back().expectKey = false;
                }
                i = j;
                break;
            }
            case '\0':
                // nlohmann stops at a NUL as if the input ended there, which would accept whatever follows.
                throw Error(file + ":" + where(i) + ": syntax error: NUL byte (binary data?)");
            default:
                if (c == '-' || (c >= '0' && c <= '9')) {
                    std::size_t j = i;
                    bool exponent = false;
                    while (j < n && (std::isdigit(static_cast<unsigned char>(text[j])) || text[j] == '-' ||
                                     text[j] == '+' || text[j] == '.' || text[j] == 'e' || text[j] == 'E')) {
                        exponent = exponent || text[j] == 'e' || text[j] == 'E';
                        ++j;
                    }
                    // Without an exponent a number needs over 300 digits to overflow a double.
                    if (!result.overflow && (exponent || j - i > 300)) {
                        const std::string token(text.substr(i, j - i));
                        const double v = std::strtod(token.c_str(), nullptr);
                        if (std::isinf(v))
                            result.overflow = file + ":" + where(i) + ": number out of range: " + printable(token);
                    }
                    i = j - 1;
                }
                break;
        }
    }
    return result;
}

// ---------------------------------------------------------------------------------------------------------------
// Step 2: nlohmann

/// "unexpected '}'; expected string literal" from nlohmann's what().
std::string syntaxReason(const std::string& what) {
    std::string reason = what;
    const std::string marker = "syntax error while parsing ";
    if (const auto p = reason.find(marker); p != std::string::npos) {
        reason = reason.substr(p + marker.size());
        if (const auto dash = reason.find(" - "); dash != std::string::npos) reason = reason.substr(dash + 3);
    } else if (const auto colon = reason.find(": "); colon != std::string::npos) {
        reason = reason.substr(colon + 2);
    }
    // "...; last read: '<text>'" may be followed by "; expected ...".
    std::string lastRead, expected;
    if (const auto lr = reason.find("; last read: '"); lr != std::string::npos) {
        std::string rest = reason.substr(lr + 14);
        reason = reason.substr(0, lr);
        if (const auto end = rest.rfind("'; "); end != std::string::npos) {
            expected = rest.substr(end + 1);
            rest = rest.substr(0, end);
        } else if (!rest.empty() && rest.back() == '\'') {
            rest.pop_back();
        }
        lastRead = rest;
    }
    if (!lastRead.empty()) {
        // Quote only the tail: that is where the problem is.
        if (lastRead.size() > 30) lastRead = lastRead.substr(lastRead.size() - 30);
        reason += " near '" + printable(lastRead) + "'";
    }
    reason += expected;
    if (reason.find("unexpected end of input") != std::string::npos) reason += " (truncated file?)";
    return printable(reason, 200);
}

Json parseJson(std::string_view text, const std::string& file) {
    bool blank = true;
    for (const char c : text) {
        if (c != ' ' && c != '\t' && c != '\n' && c != '\r') {
            blank = false;
            break;
        }
    }
    if (blank) throw Error(file + ": empty file (expected a JSON object)");

    const PreScan scan = preScan(text, file);
    Json doc;
    try {
        doc = Json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/true, /*ignore_comments=*/false);
    } catch (const Json::parse_error& e) {
        const std::size_t offset = e.byte == 0 ? 0 : e.byte - 1;
        const LineColumn lc = lineColumnAt(text, offset);
        std::string reason = syntaxReason(e.what());
        if (offset + 1 >= text.size() && reason.find("missing closing quote") != std::string::npos)
            reason += " (the file ends here: truncated?)";
        throw Error(file + ":" + std::to_string(lc.line) + ":" + std::to_string(lc.column) +
                    ": syntax error: " + reason);
    } catch (const Json::exception& e) {
        if (scan.overflow) throw Error(*scan.overflow);
        throw Error(file + ": " + printable(e.what(), 200));
    }
    if (scan.overflow) throw Error(*scan.overflow);
    if (scan.duplicateKey) throw Error(*scan.duplicateKey);
    return doc;
}

// ---------------------------------------------------------------------------------------------------------------
// Step 3: the document

std::string describe(const Json& j) {
    switch (j.type()) {
        case Json::value_t::null:
            return "null";
        case Json::value_t::boolean:
            return "a boolean";
        case Json::value_t::number_integer:
        case Json::value_t::number_unsigned:
        case Json::value_t::number_float:
            return "a number (" + formatNumber(j.get<double>()) + ")";
        case Json::value_t::string:
            return "a string";
        case Json::value_t::array:
            return "an array of " + std::to_string(j.size()) + " elements";
        case Json::value_t::object:
            return "an object";
        default:
            return "binary data";
    }
}

/// Where a value lives: the file and its JSON pointer.
struct Loc {
    const std::string* file;
    std::string path;

    Loc operator/(std::string_view key) const { return {file, path + "/" + jsonPointerToken(key)}; }
    Loc operator/(std::size_t index) const { return {file, path + "/" + std::to_string(index)}; }
    std::string where() const { return *file + ": at " + (path.empty() ? std::string("/") : path) + ": "; }
    [[noreturn]] void fail(const std::string& problem) const { throw Error(where() + problem); }
};

enum class Sign { Any, Positive, NonNegative };

double getNumber(const Json& j, const Loc& at) {
    if (!j.is_number()) at.fail("expected a number, got " + describe(j));
    const double v = j.get<double>();
    if (!std::isfinite(v)) at.fail("expected a finite number, got " + formatNumber(v));
    return v;
}

double checkSign(double v, Sign sign, const Loc& at) {
    if (sign == Sign::Positive && !(v > 0)) at.fail("must be > 0 (got " + formatNumber(v) + ")");
    if (sign == Sign::NonNegative && !(v >= 0)) at.fail("must be >= 0 (got " + formatNumber(v) + ")");
    return v;
}

float getFloat(const Json& j, const Loc& at, Sign sign = Sign::Any) {
    const double v = checkSign(getNumber(j, at), sign, at);
    if (std::fabs(v) > static_cast<double>(std::numeric_limits<float>::max()))
        at.fail("number too large for a 32-bit float (got " + formatNumber(v) + ")");
    const auto f = static_cast<float>(v);
    if (sign == Sign::Positive && !(f > 0)) at.fail("must be > 0 (got " + formatNumber(v) + ", 0 as a float)");
    return f;
}

/// `v` within one of the engine's limits (include/rubble/limits.h): the same numbers the World refuses with.
float checkWithin(float v, const Loc& at, float lo, float hi, const char* unit) {
    const auto shortly = [](float f) {  // as the World's messages print them: 1e-05, not 9.99999975e-06
        char text[32];
        std::snprintf(text, sizeof text, "%g", static_cast<double>(f));
        return std::string(text);
    };
    if (!(v >= lo && v <= hi))
        at.fail("must be in [" + shortly(lo) + ", " + shortly(hi) + "] " + unit + " (got " + shortly(v) +
                "; docs/limits.md)");
    return v;
}

float getFloatIn(const Json& j, const Loc& at, float lo, float hi, const char* unit) {
    return checkWithin(getFloat(j, at), at, lo, hi, unit);
}

/// A radius or half extent.
float getSize(const Json& j, const Loc& at) {
    return getFloatIn(j, at, limits::kMinShapeSize, limits::kMaxShapeSize, "m");
}

double getDouble(const Json& j, const Loc& at, Sign sign = Sign::Any) {
    const double v = checkSign(getNumber(j, at), sign, at);
    // Generators round positions to float in the end: refuse what cannot be represented.
    if (std::fabs(v) > 1e30) at.fail("number too large (got " + formatNumber(v) + ")");
    return v;
}

/// An integer in [lo, hi]; floats with an integral value are accepted (600.0), others are refused.
std::int64_t getInt(const Json& j, const Loc& at, std::int64_t lo, std::int64_t hi) {
    if (!j.is_number()) at.fail("expected an integer, got " + describe(j));
    std::int64_t v = 0;
    if (j.is_number_unsigned()) {
        const auto u = j.get<std::uint64_t>();
        if (u > static_cast<std::uint64_t>(hi))
            at.fail("must be <= " + std::to_string(hi) + " (got " + std::to_string(u) + ")");
        v = static_cast<std::int64_t>(u);
    } else if (j.is_number_integer()) {
        v = j.get<std::int64_t>();
    } else {
        const double d = j.get<double>();
        if (!std::isfinite(d) || std::trunc(d) != d) at.fail("expected an integer, got " + formatNumber(d));
        if (d < static_cast<double>(lo)) at.fail("must be >= " + std::to_string(lo) + " (got " + formatNumber(d) + ")");
        if (d > static_cast<double>(hi)) at.fail("must be <= " + std::to_string(hi) + " (got " + formatNumber(d) + ")");
        v = static_cast<std::int64_t>(d);
    }
    if (v < lo) at.fail("must be >= " + std::to_string(lo) + " (got " + std::to_string(v) + ")");
    if (v > hi) at.fail("must be <= " + std::to_string(hi) + " (got " + std::to_string(v) + ")");
    return v;
}

std::uint64_t getUint64(const Json& j, const Loc& at) {
    if (j.is_number_unsigned()) return j.get<std::uint64_t>();
    if (j.is_number_integer()) at.fail("must be >= 0 (got " + std::to_string(j.get<std::int64_t>()) + ")");
    if (j.is_number_float()) {
        const double d = j.get<double>();
        if (std::trunc(d) != d || d < 0 || d >= 18446744073709551616.0)
            at.fail("expected an integer in 0 .. 2^64-1, got " + formatNumber(d));
        return static_cast<std::uint64_t>(d);
    }
    at.fail("expected an integer, got " + describe(j));
}

const std::string& getString(const Json& j, const Loc& at) {
    if (!j.is_string()) at.fail("expected a string, got " + describe(j));
    return j.get_ref<const std::string&>();
}

bool getBool(const Json& j, const Loc& at) {
    if (!j.is_boolean()) at.fail("expected true or false, got " + describe(j));
    return j.get<bool>();
}

const Json& expectObject(const Json& j, const Loc& at, std::string_view what = "an object") {
    if (!j.is_object()) at.fail("expected " + std::string(what) + ", got " + describe(j));
    return j;
}

const Json& expectArray(const Json& j, const Loc& at, std::string_view what = "an array") {
    if (!j.is_array()) at.fail("expected " + std::string(what) + ", got " + describe(j));
    return j;
}

/// Refuses keys outside `allowed` (and `more`), naming the closest one.
void checkKeys(const Json& obj, const Loc& at, std::initializer_list<std::string_view> allowed,
               std::span<const std::string_view> more = {}) {
    std::vector<std::string_view> all(allowed);
    all.insert(all.end(), more.begin(), more.end());
    for (const auto& [key, value] : obj.items()) {
        if (std::find(all.begin(), all.end(), std::string_view(key)) == all.end())
            (at / key).fail("unknown key '" + printable(key) + "'" + suggestion(key, all, "allowed keys"));
    }
}

/// Keys every generator accepts besides its own.
constexpr std::string_view kGeneratorBodyKeys[] = {
    "type",     "shape",          "shapes",         "body_type",       "rotation",      "velocity",  "angular_velocity",
    "material", "filter",         "linear_damping", "angular_damping", "gravity_scale", "user_data", "allow_sleep",
    "bullet",   "contact_events", "sensor"};

void require(const Json& obj, const Loc& at, std::string_view key) {
    if (!obj.contains(key)) at.fail("missing required key '" + std::string(key) + "'");
}

Vec3 getVec3(const Json& j, const Loc& at, Sign sign = Sign::Any) {
    if (!j.is_array() || j.size() != 3) at.fail("expected an array of 3 numbers, got " + describe(j));
    return {getFloat(j[0], at / 0, sign), getFloat(j[1], at / 1, sign), getFloat(j[2], at / 2, sign)};
}

/// An array of N numbers, or one number standing for all N.
template <std::size_t N>
void getDoubles(const Json& j, const Loc& at, double (&out)[N], Sign sign = Sign::Any, bool allowScalar = true) {
    if (allowScalar && j.is_number()) {
        const double v = getDouble(j, at, sign);
        for (double& o : out) o = v;
        return;
    }
    if (!j.is_array() || j.size() != N)
        at.fail("expected an array of " + std::to_string(N) + " numbers" + (allowScalar ? " (or one number)" : "") +
                ", got " + describe(j));
    for (std::size_t i = 0; i < N; ++i) out[i] = getDouble(j[i], at / i, sign);
}

template <std::size_t N>
void getFloats(const Json& j, const Loc& at, float (&out)[N]) {
    if (j.is_number()) {
        const float v = getFloat(j, at);
        for (float& o : out) o = v;
        return;
    }
    if (!j.is_array() || j.size() != N)
        at.fail("expected an array of " + std::to_string(N) + " numbers (or one number), got " + describe(j));
    for (std::size_t i = 0; i < N; ++i) out[i] = getFloat(j[i], at / i);
}

/// [x, y, z, w] (unit within 1e-3, normalised here) or {"axis": [x, y, z], "degrees" | "radians": a}.
Quat getRotation(const Json& j, const Loc& at) {
    if (j.is_array()) {
        if (j.size() != 4)
            at.fail("expected a quaternion [x, y, z, w] or {\"axis\": [x, y, z], \"degrees\": a}, got " + describe(j));
        const float x = getFloat(j[0], at / 0), y = getFloat(j[1], at / 1), z = getFloat(j[2], at / 2),
                    w = getFloat(j[3], at / 3);
        const double len = std::sqrt(double(x) * x + double(y) * y + double(z) * z + double(w) * w);
        if (!(std::fabs(len - 1.0) <= 1e-3))
            at.fail("quaternion must have unit length (got length " + formatNumber(len) + ")");
        const auto inv = static_cast<float>(1.0 / len);
        return {x * inv, y * inv, z * inv, w * inv};
    }
    if (!j.is_object())
        at.fail("expected a quaternion [x, y, z, w] or {\"axis\": [x, y, z], \"degrees\": a}, got " + describe(j));
    checkKeys(j, at, {"axis", "degrees", "radians"});
    require(j, at, "axis");
    const Vec3 axis = getVec3(j["axis"], at / "axis");
    // In double: a float axis of 1e30 has a squared length beyond float's range (the rotation came out of unit
    // length), and one of 1e-30 one below it.
    const double ax = axis.x, ay = axis.y, az = axis.z, len = std::sqrt(ax * ax + ay * ay + az * az);
    if (!(len > 0)) (at / "axis").fail("axis must not be zero");
    const bool deg = j.contains("degrees"), rad = j.contains("radians");
    if (deg == rad) at.fail("give exactly one of 'degrees' and 'radians'");
    // Two turns are the quaternion's period: reduced first, a huge angle keeps sine and cosine consistent.
    constexpr double kPi = 3.14159265358979323846;
    const double angle = deg ? std::fmod(getDouble(j["degrees"], at / "degrees"), 720.0) * (kPi / 180.0)
                             : std::fmod(getDouble(j["radians"], at / "radians"), 4.0 * kPi);
    const Vec3 unit{static_cast<float>(ax / len), static_cast<float>(ay / len), static_cast<float>(az / len)};
    return Quat::fromAxisAngle(unit, static_cast<float>(angle));
}

/// The end of a message about a body position past limits::kMaxCoordinate, the World's limit.
std::string farFromOrigin() {
    return ", farther than " + formatNumber(limits::kMaxCoordinate) +
           " m from the origin on an axis, where float spacing exceeds the contact slop (docs/limits.md)";
}

// ---------------------------------------------------------------------------------------------------------------
// The scene being built

struct Builder {
    std::string file;
    std::filesystem::path dir;  ///< for relative OBJ paths
    Scene scene;
    std::unordered_map<std::string, Material> materials;
    std::vector<std::string> materialNames;  // in file order, for messages
    std::unordered_map<std::string, std::uint32_t> shapeIndex;
    scene_detail::SceneCaps caps;

    Loc root() const { return {&file, ""}; }

    void parseSettings(const Json& j, const Loc& at);
    void parseMaterials(const Json& j, const Loc& at);
    Material parseMaterialObject(const Json& j, const Loc& at) const;
    Material materialRef(const Json& j, const Loc& at) const;
    void parseShapes(const Json& j, const Loc& at);
    ShapeDef parseShape(const Json& j, const Loc& at, bool childOnly, const Json* shapesObject);
    std::uint32_t shapeRef(const Json& j, const Loc& at) const;
    void checkShapeForType(std::uint32_t shape, BodyType type, const Loc& at) const;
    void parseBodyFields(const Json& j, const Loc& at, std::string_view typeKey, BodyDef& def) const;
    void parseBodies(const Json& j, const Loc& at);
    void parseGenerators(const Json& j, const Loc& at);
    void parseFigures(const Json& j, const Loc& at);
    void parseJoints(const Json& j, const Loc& at);
    /// One joint between bodies a and b (indices checked) from the keys of `o`; anchors default to the midpoint.
    SceneJoint jointFrom(const Json& o, const Loc& at, const std::string& type, std::uint32_t a, std::uint32_t b) const;
    void reserveBodies(double count, const Loc& at) const;
};

void Builder::parseSettings(const Json& j, const Loc& at) {
    expectObject(j, at);
    // clang-format off (it would put one key per line)
    checkKeys(j, at,
              {"dt",
               "gravity",
               "substeps",
               "velocity_iterations",
               "position_iterations",
               "threads",
               "integrator",
               "effects",
               "broadphase",
               "position_correction",
               "warm_starting",
               "seed_resting_loads",
               "shock_propagation",
               "sleep",
               "contact_hertz",
               "contact_damping_ratio",
               "max_push_out_velocity",
               "baumgarte",
               "linear_slop",
               "manifold_reuse_distance",
               "contact_feature_drift",
               "hit_event_speed"});
    // clang-format on
    WorldSettings& s = scene.settings;
    if (j.contains("dt")) s.timeStep = getFloatIn(j["dt"], at / "dt", limits::kMinTimeStep, limits::kMaxTimeStep, "s");
    if (j.contains("gravity")) s.gravity = getVec3(j["gravity"], at / "gravity");
    if (j.contains("substeps"))
        s.substeps = static_cast<int>(getInt(j["substeps"], at / "substeps", 1, limits::kMaxSubsteps));
    if (j.contains("velocity_iterations"))
        s.velocityIterations =
            static_cast<int>(getInt(j["velocity_iterations"], at / "velocity_iterations", 0, limits::kMaxIterations));
    if (j.contains("position_iterations"))
        s.positionIterations =
            static_cast<int>(getInt(j["position_iterations"], at / "position_iterations", 0, limits::kMaxIterations));
    if (j.contains("threads"))
        s.threads = static_cast<int>(getInt(j["threads"], at / "threads", 0, limits::kMaxThreads));
    if (j.contains("integrator")) {
        const std::string& name = getString(j["integrator"], at / "integrator");
        const auto v = integratorFromName(name);
        if (!v) {
            std::vector<std::string> names;
            for (const auto i : {Integrator::SemiImplicitEuler, Integrator::ExplicitEuler, Integrator::Verlet,
                                 Integrator::RungeKutta4})
                names.emplace_back(integratorName(i));
            (at / "integrator").fail("unknown integrator '" + printable(name) + "'" + suggestion(name, names));
        }
        s.integrator = *v;
    }
    if (j.contains("position_correction")) {
        const std::string& name = getString(j["position_correction"], at / "position_correction");
        const auto v = positionCorrectionFromName(name);
        if (!v) {
            std::vector<std::string> names;
            for (const auto p :
                 {PositionCorrection::SoftStep, PositionCorrection::Baumgarte, PositionCorrection::SplitImpulse})
                names.emplace_back(positionCorrectionName(p));
            (at / "position_correction")
                .fail("unknown position correction '" + printable(name) + "'" + suggestion(name, names));
        }
        s.solver.positionCorrection = *v;
    }
    if (j.contains("warm_starting")) s.solver.warmStarting = getBool(j["warm_starting"], at / "warm_starting");
    if (j.contains("seed_resting_loads"))
        s.solver.seedRestingLoads = getBool(j["seed_resting_loads"], at / "seed_resting_loads");
    if (j.contains("shock_propagation"))
        s.solver.shockPropagation = getBool(j["shock_propagation"], at / "shock_propagation");
    const auto solverFloat = [&](const char* key, float& value, Sign sign) {
        if (j.contains(key)) value = getFloat(j[key], at / key, sign);
    };
    solverFloat("contact_hertz", s.solver.contactHertz, Sign::Positive);
    solverFloat("contact_damping_ratio", s.solver.contactDampingRatio, Sign::NonNegative);
    solverFloat("max_push_out_velocity", s.solver.maxPushOutVelocity, Sign::NonNegative);
    solverFloat("baumgarte", s.solver.baumgarte, Sign::NonNegative);
    solverFloat("linear_slop", s.solver.linearSlop, Sign::NonNegative);
    solverFloat("manifold_reuse_distance", s.manifoldReuseDistance, Sign::NonNegative);
    solverFloat("contact_feature_drift", s.contactFeatureDrift, Sign::NonNegative);
    solverFloat("hit_event_speed", s.hitEventSpeed, Sign::NonNegative);
    if (j.contains("sleep")) {
        const Loc sl = at / "sleep";
        const Json& o = expectObject(j["sleep"], sl, "a sleep settings object");
        checkKeys(o, sl, {"linear_threshold", "angular_threshold", "time_to_sleep"});
        if (o.contains("linear_threshold"))
            s.sleep.linearThreshold = getFloat(o["linear_threshold"], sl / "linear_threshold", Sign::NonNegative);
        if (o.contains("angular_threshold"))
            s.sleep.angularThreshold = getFloat(o["angular_threshold"], sl / "angular_threshold", Sign::NonNegative);
        if (o.contains("time_to_sleep"))
            s.sleep.timeToSleep = getFloat(o["time_to_sleep"], sl / "time_to_sleep", Sign::NonNegative);
    }
    if (j.contains("broadphase")) {
        const std::string& name = getString(j["broadphase"], at / "broadphase");
        const auto v = broadPhaseFromName(name);
        if (!v) {
            std::vector<std::string> names;
            for (const auto b : {BroadPhaseKind::Auto, BroadPhaseKind::SweepAndPrune, BroadPhaseKind::Grid})
                names.emplace_back(broadPhaseName(b));
            (at / "broadphase").fail("unknown broad phase '" + printable(name) + "'" + suggestion(name, names));
        }
        s.broadPhase = *v;
    }
    if (j.contains("effects")) {
        const Loc el = at / "effects";
        const Json& arr = expectArray(j["effects"], el, "an array of effect names");
        EffectSet set;
        for (std::size_t i = 0; i < arr.size(); ++i) {
            const std::string& name = getString(arr[i], el / i);
            const auto e = effectFromName(name);
            if (!e) {
                std::vector<std::string> names;
                for (int b = 0; b < kEffectCount; ++b) names.emplace_back(effectName(static_cast<Effect>(1u << b)));
                (el / i).fail("unknown effect '" + printable(name) + "'" + suggestion(name, names));
            }
            if (set.has(*e)) (el / i).fail("effect '" + name + "' listed twice");
            set = set.with(*e);
        }
        s.effects = set;
    }
}

Material Builder::parseMaterialObject(const Json& j, const Loc& at) const {
    expectObject(j, at, "a material object");
    checkKeys(j, at, {"friction", "restitution", "density"});
    Material m;
    if (j.contains("friction")) m.friction = getFloat(j["friction"], at / "friction", Sign::NonNegative);
    if (j.contains("restitution")) {
        m.restitution = getFloat(j["restitution"], at / "restitution", Sign::NonNegative);
        if (m.restitution > 1) (at / "restitution").fail("must be <= 1 (got " + formatNumber(m.restitution) + ")");
    }
    if (j.contains("density"))
        m.density = getFloatIn(j["density"], at / "density", limits::kMinDensity, limits::kMaxDensity, "kg/m^3");
    return m;
}

void Builder::parseMaterials(const Json& j, const Loc& at) {
    expectObject(j, at, "an object of named materials");
    for (const auto& [name, value] : j.items()) {
        if (name.empty()) at.fail("material names must not be empty");
        materials[name] = parseMaterialObject(value, at / name);
        materialNames.push_back(name);
    }
}

Material Builder::materialRef(const Json& j, const Loc& at) const {
    if (j.is_object()) return parseMaterialObject(j, at);
    if (!j.is_string()) at.fail("expected a material name or a material object, got " + describe(j));
    const std::string& name = j.get_ref<const std::string&>();
    const auto it = materials.find(name);
    if (it == materials.end())
        at.fail("unknown material '" + printable(name) + "'" + suggestion(name, materialNames, "materials", true));
    return it->second;
}

std::vector<Vec3> getPoints(const Json& j, const Loc& at, std::string_view what) {
    const Json& arr = expectArray(j, at, what);
    std::vector<Vec3> points;
    points.reserve(arr.size());
    for (std::size_t i = 0; i < arr.size(); ++i) points.push_back(getVec3(arr[i], at / i));
    return points;
}

ShapeDef Builder::parseShape(const Json& j, const Loc& at, bool childOnly, const Json* shapesObject) {
    expectObject(j, at, "a shape object");
    require(j, at, "type");
    const std::string& type = getString(j["type"], at / "type");
    if (type == "sphere") {
        checkKeys(j, at, {"type", "radius"});
        require(j, at, "radius");
        return SphereDef{getSize(j["radius"], at / "radius")};
    }
    if (type == "box") {
        checkKeys(j, at, {"type", "half_extents"});
        require(j, at, "half_extents");
        const Loc h = at / "half_extents";
        const Vec3 half = getVec3(j["half_extents"], h);
        const auto size = [&](float v, std::size_t axis) {
            return checkWithin(v, h / axis, limits::kMinShapeSize, limits::kMaxShapeSize, "m");
        };
        return BoxDef{{size(half.x, 0), size(half.y, 1), size(half.z, 2)}};
    }
    if (type == "capsule") {
        checkKeys(j, at, {"type", "radius", "half_height"});
        require(j, at, "radius");
        require(j, at, "half_height");
        return CapsuleDef{getSize(j["radius"], at / "radius"),
                          getFloatIn(j["half_height"], at / "half_height", 0, limits::kMaxShapeSize, "m")};
    }
    if (type == "hull") {
        checkKeys(j, at, {"type", "points"});
        require(j, at, "points");
        ConvexHullDef hull{getPoints(j["points"], at / "points", "an array of [x, y, z] points")};
        if (hull.points.size() < 4)
            (at / "points").fail("a hull needs at least 4 points (got " + std::to_string(hull.points.size()) + ")");
        // The World's own build decides (flat, collinear or too many corners), so that a scene the loader accepts
        // is one the World takes.
        try {
            computeMassProperties(hull, 1.0f);
        } catch (const Error& e) {
            (at / "points").fail(e.what());
        }
        return hull;
    }
    if (childOnly)
        (at / "type").fail("a compound child must be a sphere, box, capsule or hull, not '" + printable(type) + "'");
    if (type == "compound") {
        checkKeys(j, at, {"type", "children"});
        require(j, at, "children");
        const Loc cl = at / "children";
        const Json& arr = expectArray(j["children"], cl, "an array of children");
        if (arr.empty()) cl.fail("a compound needs at least one child");
        CompoundDef compound;
        for (std::size_t i = 0; i < arr.size(); ++i) {
            const Loc c = cl / i;
            expectObject(arr[i], c, "a child object");
            checkKeys(arr[i], c, {"shape", "position", "rotation"});
            require(arr[i], c, "shape");
            CompoundChildDef child;
            const Json& s = arr[i]["shape"];
            ShapeDef def;
            if (s.is_string()) {
                // A child may name another shape of the file (a primitive or hull).
                const std::string& name = s.get_ref<const std::string&>();
                if (!shapesObject || !shapesObject->contains(name) || !(*shapesObject)[name].is_object())
                    (c / "shape").fail("unknown shape '" + printable(name) + "'");
                const Json& target = (*shapesObject)[name];
                def = parseShape(target, Loc{&file, "/shapes/" + jsonPointerToken(name)}, true, nullptr);
            } else {
                def = parseShape(s, c / "shape", true, nullptr);
            }
            std::visit(
                [&](auto&& d) {
                    using T = std::decay_t<decltype(d)>;
                    if constexpr (std::is_same_v<T, SphereDef> || std::is_same_v<T, BoxDef> ||
                                  std::is_same_v<T, CapsuleDef> || std::is_same_v<T, ConvexHullDef>)
                        child.shape = std::move(d);
                },
                def);
            if (arr[i].contains("position")) child.local.position = getVec3(arr[i]["position"], c / "position");
            if (arr[i].contains("rotation")) child.local.rotation = getRotation(arr[i]["rotation"], c / "rotation");
            compound.children.push_back(std::move(child));
        }
        return compound;
    }
    if (type == "mesh") {
        checkKeys(j, at, {"type", "obj", "vertices", "indices", "grid"});
        const int sources =
            int(j.contains("obj")) + int(j.contains("vertices") || j.contains("indices")) + int(j.contains("grid"));
        if (sources != 1) at.fail("a mesh needs exactly one of 'obj', 'vertices' + 'indices' or 'grid'");
        if (j.contains("obj")) {
            const std::string& rel = getString(j["obj"], at / "obj");
            if (rel.empty()) (at / "obj").fail("empty path");
            // A scene names its meshes relative to itself, so that it reads the same on any machine and cannot
            // reach for files elsewhere (a scene may come from anyone).
            if (std::filesystem::path(rel).is_absolute())
                (at / "obj")
                    .fail("'" + printable(rel) + "' is an absolute path: name the OBJ file relative to the scene");
            const std::filesystem::path objPath = dir / rel;
            TriangleMeshDef mesh;
            try {
                mesh = loadObj(objPath.string());
            } catch (const Error& e) {
                (at / "obj").fail(e.what());
            }
            if (mesh.indices.empty()) (at / "obj").fail("'" + objPath.string() + "' holds no triangles");
            return mesh;
        }
        if (j.contains("grid")) {
            const Loc g = at / "grid";
            const Json& gj = expectObject(j["grid"], g, "a terrain grid object");
            checkKeys(gj, g, {"cells", "min", "max", "amplitude", "wavelength"});
            for (const char* k : {"cells", "min", "max"}) require(gj, g, k);
            scene_detail::TerrainParams p;
            const Loc cl = g / "cells";
            if (!gj["cells"].is_array() || gj["cells"].size() != 2)
                cl.fail("expected an array of 2 integers [nx, nz], got " + describe(gj["cells"]));
            p.cells[0] = static_cast<std::uint32_t>(getInt(gj["cells"][0], cl / 0, 1, 1'000'000'000));
            p.cells[1] = static_cast<std::uint32_t>(getInt(gj["cells"][1], cl / 1, 1, 1'000'000'000));
            const double triangles = 2.0 * p.cells[0] * p.cells[1];
            if (triangles > static_cast<double>(caps.terrainTriangles))
                cl.fail("would make " + formatCount(triangles) + " triangles, more than the limit of " +
                        std::to_string(caps.terrainTriangles));
            getDoubles(gj["min"], g / "min", p.min, Sign::Any, false);
            getDoubles(gj["max"], g / "max", p.max, Sign::Any, false);
            for (std::size_t a = 0; a < 2; ++a)
                if (!(p.max[a] > p.min[a]))
                    (g / "max" / a)
                        .fail("must be > min (" + formatNumber(p.min[a]) + "), got " + formatNumber(p.max[a]));
            if (gj.contains("amplitude")) p.amplitude = getDouble(gj["amplitude"], g / "amplitude");
            if (gj.contains("wavelength")) getDoubles(gj["wavelength"], g / "wavelength", p.wavelength, Sign::Positive);
            return scene_detail::generateTerrain(p);
        }
        require(j, at, "vertices");
        require(j, at, "indices");
        TriangleMeshDef mesh;
        mesh.vertices = getPoints(j["vertices"], at / "vertices", "an array of [x, y, z] vertices");
        const Loc il = at / "indices";
        const Json& idx = expectArray(j["indices"], il, "a flat array of vertex indices, three per triangle");
        if (idx.empty() || idx.size() % 3 != 0)
            il.fail("expected a non-empty multiple of 3 indices, got " + std::to_string(idx.size()));
        if (idx.size() / 3 > limits::kMaxMeshTriangles)
            il.fail("makes " + std::to_string(idx.size() / 3) + " triangles, more than " +
                    std::to_string(limits::kMaxMeshTriangles) + " (docs/limits.md)");
        if (mesh.vertices.size() > 0xFFFFFFFFu) (at / "vertices").fail("too many vertices");
        const auto nv = static_cast<std::int64_t>(mesh.vertices.size());
        mesh.indices.reserve(idx.size());
        for (std::size_t i = 0; i < idx.size(); ++i) {
            if (nv == 0) (at / "vertices").fail("a mesh with indices needs vertices");
            mesh.indices.push_back(static_cast<std::uint32_t>(getInt(idx[i], il / i, 0, nv - 1)));
        }
        return mesh;
    }
    if (type == "heightfield") {
        checkKeys(j, at, {"type", "rows", "columns", "heights", "spacing"});
        for (const char* k : {"rows", "columns", "heights"}) require(j, at, k);
        HeightfieldDef hf;
        hf.rows = static_cast<std::uint32_t>(getInt(j["rows"], at / "rows", 2, 0xFFFFFFFF));
        hf.columns = static_cast<std::uint32_t>(getInt(j["columns"], at / "columns", 2, 0xFFFFFFFF));
        const std::uint64_t triangles = 2 * (std::uint64_t{hf.rows} - 1) * (std::uint64_t{hf.columns} - 1);
        if (triangles > limits::kMaxMeshTriangles)
            at.fail("rows and columns make " + std::to_string(triangles) + " triangles, more than " +
                    std::to_string(limits::kMaxMeshTriangles) + " (docs/limits.md)");
        const Loc hl = at / "heights";
        const Json& h = expectArray(j["heights"], hl, "an array of rows * columns heights");
        const std::uint64_t expected = std::uint64_t{hf.rows} * hf.columns;
        if (h.size() != expected)
            hl.fail("expected rows * columns = " + std::to_string(expected) + " heights, got " +
                    std::to_string(h.size()));
        hf.heights.reserve(h.size());
        for (std::size_t i = 0; i < h.size(); ++i) hf.heights.push_back(getFloat(h[i], hl / i));
        if (j.contains("spacing")) hf.spacing = getVec3(j["spacing"], at / "spacing", Sign::Positive);
        return hf;
    }
    (at / "type")
        .fail("unknown shape type '" + printable(type) + "'" +
              suggestion(type, std::initializer_list<std::string_view>{"sphere", "box", "capsule", "hull", "compound",
                                                                       "mesh", "heightfield"}));
}

void Builder::parseShapes(const Json& j, const Loc& at) {
    expectObject(j, at, "an object of named shapes");
    const std::size_t n = j.size();
    scene.shapes.resize(n);
    scene.shapeNames.reserve(n);
    std::size_t i = 0;
    for (const auto& [name, value] : j.items()) {
        if (name.empty()) at.fail("shape names must not be empty");
        scene.shapeNames.push_back(name);
        shapeIndex.emplace(name, static_cast<std::uint32_t>(i));
        scene.shapes[i] = parseShape(value, at / name, false, &j);
        ++i;
    }
}

std::uint32_t Builder::shapeRef(const Json& j, const Loc& at) const {
    const std::string& name = getString(j, at);
    const auto it = shapeIndex.find(name);
    if (it == shapeIndex.end())
        at.fail("unknown shape '" + printable(name) + "'" + suggestion(name, scene.shapeNames, "shapes", true));
    return it->second;
}

void Builder::checkShapeForType(std::uint32_t shape, BodyType type, const Loc& at) const {
    const ShapeDef& def = scene.shapes[shape];
    const bool staticOnly = std::holds_alternative<TriangleMeshDef>(def) || std::holds_alternative<HeightfieldDef>(def);
    if (staticOnly && type != BodyType::Static)
        at.fail("shape '" + scene.shapeNames[shape] + "' is a " +
                (std::holds_alternative<TriangleMeshDef>(def) ? "mesh" : "heightfield") +
                ", a static-only shape; the body must be static");
}

constexpr const char* kStaticBodyMoves = "a static body cannot have a velocity (a kinematic body can move)";

BodyType getBodyType(const Json& j, const Loc& at) {
    const std::string& t = getString(j, at);
    if (t == "static") return BodyType::Static;
    if (t == "kinematic") return BodyType::Kinematic;
    if (t == "dynamic") return BodyType::Dynamic;
    at.fail("unknown body type '" + printable(t) + "'" +
            suggestion(t, std::initializer_list<std::string_view>{"static", "kinematic", "dynamic"}));
}

/// Fields every body and body generator shares (all but shape and position).
void Builder::parseBodyFields(const Json& j, const Loc& at, std::string_view typeKey, BodyDef& def) const {
    if (j.contains(typeKey)) def.type = getBodyType(j[typeKey], at / typeKey);
    if (j.contains("rotation")) def.orientation = getRotation(j["rotation"], at / "rotation");
    if (j.contains("velocity")) def.linearVelocity = getVec3(j["velocity"], at / "velocity");
    if (j.contains("angular_velocity")) def.angularVelocity = getVec3(j["angular_velocity"], at / "angular_velocity");
    if (j.contains("material")) def.material = materialRef(j["material"], at / "material");
    if (j.contains("filter")) {
        const Loc fl = at / "filter";
        const Json& f = expectObject(j["filter"], fl, "a filter object");
        checkKeys(f, fl, {"category", "mask"});
        if (f.contains("category"))
            def.filter.category = static_cast<std::uint32_t>(getInt(f["category"], fl / "category", 0, 0xFFFFFFFF));
        if (f.contains("mask"))
            def.filter.mask = static_cast<std::uint32_t>(getInt(f["mask"], fl / "mask", 0, 0xFFFFFFFF));
    }
    if (j.contains("linear_damping"))
        def.linearDamping = getFloat(j["linear_damping"], at / "linear_damping", Sign::NonNegative);
    if (j.contains("angular_damping"))
        def.angularDamping = getFloat(j["angular_damping"], at / "angular_damping", Sign::NonNegative);
    if (j.contains("gravity_scale")) def.gravityScale = getFloat(j["gravity_scale"], at / "gravity_scale");
    if (j.contains("user_data")) def.userData = getUint64(j["user_data"], at / "user_data");
    if (j.contains("allow_sleep")) def.allowSleep = getBool(j["allow_sleep"], at / "allow_sleep");
    if (j.contains("bullet")) def.bullet = getBool(j["bullet"], at / "bullet");
    if (j.contains("contact_events")) def.contactEvents = getBool(j["contact_events"], at / "contact_events");
    if (j.contains("sensor")) def.sensor = getBool(j["sensor"], at / "sensor");
    // World::createBody refuses these too; here the message names the key.
    if (def.type == BodyType::Static) {
        if (def.linearVelocity != Vec3{}) (at / "velocity").fail(kStaticBodyMoves);
        if (def.angularVelocity != Vec3{}) (at / "angular_velocity").fail(kStaticBodyMoves);
    }
}

void Builder::reserveBodies(double count, const Loc& at) const {
    const double total = static_cast<double>(scene.bodies.size()) + count;
    if (total > static_cast<double>(caps.bodies))
        at.fail("would make the scene " + formatCount(total) + " bodies, more than the limit of " +
                std::to_string(caps.bodies));
}

void Builder::parseBodies(const Json& j, const Loc& at) {
    const Json& arr = expectArray(j, at, "an array of bodies");
    reserveBodies(static_cast<double>(arr.size()), at);
    scene.bodies.reserve(arr.size());
    for (std::size_t i = 0; i < arr.size(); ++i) {
        const Loc b = at / i;
        const Json& o = expectObject(arr[i], b, "a body object");
        checkKeys(o, b,
                  {"shape", "type", "position", "rotation", "velocity", "angular_velocity", "material", "filter",
                   "linear_damping", "angular_damping", "gravity_scale", "user_data", "allow_sleep", "bullet",
                   "contact_events", "sensor"});
        require(o, b, "shape");
        SceneBody body;
        body.shape = shapeRef(o["shape"], b / "shape");
        if (o.contains("position")) {
            body.def.position = getVec3(o["position"], b / "position");
            if (!detail::withinCoordinateLimit(body.def.position))
                (b / "position").fail(detail::describe(body.def.position) + farFromOrigin());
        }
        parseBodyFields(o, b, "type", body.def);
        checkShapeForType(body.shape, body.def.type, b / "shape");
        scene.bodies.push_back(body);
    }
}

void Builder::parseGenerators(const Json& j, const Loc& at) {
    // A generator's random_rotation: whether it draws each body's orientation (instead of one `rotation` for all).
    const auto drawsRotations = [](const Json& o, const Loc& g) {
        if (!o.contains("random_rotation")) return false;
        const bool draw = getBool(o["random_rotation"], g / "random_rotation");
        if (draw && o.contains("rotation"))
            (g / "random_rotation").fail("give either 'rotation' or 'random_rotation', not both");
        return draw;
    };
    const Json& arr = expectArray(j, at, "an array of generators");
    for (std::size_t gi = 0; gi < arr.size(); ++gi) {
        const Loc g = at / gi;
        const std::size_t firstGenerated = scene.bodies.size();
        const Json& o = expectObject(arr[gi], g, "a generator object");
        require(o, g, "type");
        const std::string& type = getString(o["type"], g / "type");
        if (type != "pyramid" && type != "grid" && type != "random")
            (g / "type")
                .fail("unknown generator type '" + printable(type) + "'" +
                      suggestion(type, std::initializer_list<std::string_view>{"pyramid", "grid", "random"}));

        // Common fields first (the key check below is per type).
        scene_detail::GeneratorCommon common;
        const bool one = o.contains("shape"), many = o.contains("shapes");
        if (one == many) g.fail("give exactly one of 'shape' and 'shapes'");
        if (one) {
            common.shapes.push_back(shapeRef(o["shape"], g / "shape"));
        } else {
            const Json& list = expectArray(o["shapes"], g / "shapes", "an array of shape names");
            if (list.empty()) (g / "shapes").fail("must name at least one shape");
            for (std::size_t s = 0; s < list.size(); ++s) common.shapes.push_back(shapeRef(list[s], g / "shapes" / s));
        }
        auto finishCommon = [&] {
            parseBodyFields(o, g, "body_type", common.prototype.def);
            for (std::size_t s = 0; s < common.shapes.size(); ++s)
                checkShapeForType(common.shapes[s], common.prototype.def.type, one ? g / "shape" : g / "shapes" / s);
        };
        if (type == "pyramid") {
            checkKeys(o, g, {"base", "layers", "footprint", "spacing", "center", "repeat"}, kGeneratorBodyKeys);
            finishCommon();
            require(o, g, "base");
            scene_detail::PyramidParams p;
            p.base = static_cast<std::uint32_t>(getInt(o["base"], g / "base", 1, 1'000'000));
            p.layers = o.contains("layers") ? static_cast<std::uint32_t>(getInt(o["layers"], g / "layers", 1, p.base))
                                            : p.base;
            if (o.contains("footprint")) {
                const std::string& f = getString(o["footprint"], g / "footprint");
                if (f == "wall")
                    p.wall = true;
                else if (f != "square")
                    (g / "footprint")
                        .fail("unknown footprint '" + printable(f) + "'" +
                              suggestion(f, std::initializer_list<std::string_view>{"square", "wall"}));
            }
            if (o.contains("spacing")) {
                getDoubles(o["spacing"], g / "spacing", p.spacing, Sign::Positive);
            } else {
                const auto* box = std::get_if<BoxDef>(&scene.shapes[common.shapes[0]]);
                if (!box || common.shapes.size() != 1)
                    g.fail("'spacing' is required unless the pyramid is made of one box shape");
                p.spacing[0] = 2.0 * box->halfExtents.x;
                p.spacing[1] = 2.0 * box->halfExtents.y;
                p.spacing[2] = 2.0 * box->halfExtents.z;
            }
            p.center[0] = 0;
            p.center[1] = 0.5 * p.spacing[1];
            p.center[2] = 0;
            if (o.contains("center")) getDoubles(o["center"], g / "center", p.center, Sign::Any, false);
            if (o.contains("repeat")) {
                const Loc r = g / "repeat";
                const Json& rj = expectObject(o["repeat"], r, "a repeat object");
                checkKeys(rj, r, {"count", "spacing"});
                require(rj, r, "count");
                require(rj, r, "spacing");
                const Loc rc = r / "count";
                if (!rj["count"].is_array() || rj["count"].size() != 2)
                    rc.fail("expected an array of 2 integers [nx, nz], got " + describe(rj["count"]));
                for (std::size_t a = 0; a < 2; ++a)
                    p.repeatCount[a] = static_cast<std::uint32_t>(getInt(rj["count"][a], rc / a, 1, 1'000'000));
                getDoubles(rj["spacing"], r / "spacing", p.repeatSpacing, Sign::Positive);
            }
            reserveBodies(scene_detail::pyramidBodyCount(p), g);
            scene_detail::generatePyramids(p, common, scene.bodies);
        } else if (type == "grid") {
            checkKeys(o, g, {"count", "spacing", "origin", "random_rotation", "seed"}, kGeneratorBodyKeys);
            finishCommon();
            for (const char* k : {"count", "spacing"}) require(o, g, k);
            scene_detail::GridParams p;
            const Loc cl = g / "count";
            if (!o["count"].is_array() || o["count"].size() != 3)
                cl.fail("expected an array of 3 integers [nx, ny, nz], got " + describe(o["count"]));
            for (std::size_t a = 0; a < 3; ++a)
                p.count[a] = static_cast<std::uint32_t>(getInt(o["count"][a], cl / a, 0, 1'000'000'000));
            getDoubles(o["spacing"], g / "spacing", p.spacing, Sign::NonNegative);
            if (o.contains("origin")) getDoubles(o["origin"], g / "origin", p.origin, Sign::Any, false);
            p.drawRotation = drawsRotations(o, g);
            if (o.contains("seed")) {
                if (!p.drawRotation) (g / "seed").fail("a grid draws nothing without 'random_rotation'");
                p.seed = static_cast<std::uint32_t>(getInt(o["seed"], g / "seed", 0, 0xFFFFFFFF));
            }
            reserveBodies(scene_detail::gridBodyCount(p), g);
            scene_detail::generateGrid(p, common, scene.bodies);
        } else {  // random
            checkKeys(o, g, {"count", "seed", "min", "max", "velocity_min", "velocity_max", "random_rotation"},
                      kGeneratorBodyKeys);
            finishCommon();
            for (const char* k : {"count", "min", "max"}) require(o, g, k);
            scene_detail::RandomParams p;
            p.count = static_cast<std::uint64_t>(getInt(o["count"], g / "count", 0, std::int64_t{1} << 40));
            if (o.contains("seed")) p.seed = static_cast<std::uint32_t>(getInt(o["seed"], g / "seed", 0, 0xFFFFFFFF));
            getFloats(o["min"], g / "min", p.min);
            getFloats(o["max"], g / "max", p.max);
            const bool vmin = o.contains("velocity_min"), vmax = o.contains("velocity_max");
            if (vmin != vmax) g.fail("give both 'velocity_min' and 'velocity_max' or neither");
            if (o.contains("velocity")) {
                if (vmin) g.fail("give either 'velocity' or 'velocity_min' + 'velocity_max', not both");
            }
            p.drawVelocity = vmin;
            if (vmin) {
                getFloats(o["velocity_min"], g / "velocity_min", p.velocityMin);
                getFloats(o["velocity_max"], g / "velocity_max", p.velocityMax);
                for (const float v : {p.velocityMin[0], p.velocityMin[1], p.velocityMin[2], p.velocityMax[0],
                                      p.velocityMax[1], p.velocityMax[2]})
                    if (v != 0 && common.prototype.def.type == BodyType::Static)
                        (g / "velocity_min").fail(kStaticBodyMoves);
            }
            auto checkRange = [&](const float(&lo)[3], const float(&hi)[3], const char* hiKey) {
                for (std::size_t a = 0; a < 3; ++a) {
                    if (!(lo[a] <= hi[a]))
                        (g / hiKey).fail("must be >= the minimum on every axis (axis " + std::to_string(a) + ": " +
                                         formatNumber(lo[a]) + " > " + formatNumber(hi[a]) + ")");
                    if (!std::isfinite(hi[a] - lo[a])) (g / hiKey).fail("range too wide for a 32-bit float");
                }
            };
            checkRange(p.min, p.max, "max");
            if (vmin) checkRange(p.velocityMin, p.velocityMax, "velocity_max");
            p.drawRotation = drawsRotations(o, g);
            reserveBodies(static_cast<double>(p.count), g / "count");
            scene_detail::generateRandom(p, common, scene.bodies);
        }
        // A spacing or a repeat can carry generated bodies far out, whichever kind the generator is.
        for (std::size_t k = firstGenerated; k < scene.bodies.size(); ++k)
            if (!detail::withinCoordinateLimit(scene.bodies[k].def.position))
                g.fail("puts body " + std::to_string(k) + " at " + detail::describe(scene.bodies[k].def.position) +
                       farFromOrigin());
    }
}

void Builder::parseFigures(const Json& j, const Loc& at) {
    const Json& arr = expectArray(j, at, "an array of figure names");
    std::vector<std::string_view> names;
    for (int f = 0; f < kSceneFigureCount; ++f) names.push_back(sceneFigureName(static_cast<SceneFigure>(f)));
    for (std::size_t i = 0; i < arr.size(); ++i) {
        const std::string& name = getString(arr[i], at / i);
        const auto known = std::find(names.begin(), names.end(), name);
        if (known == names.end()) (at / i).fail("unknown figure '" + printable(name) + "'" + suggestion(name, names));
        const auto f = static_cast<SceneFigure>(known - names.begin());
        if (std::find(scene.figures.begin(), scene.figures.end(), f) != scene.figures.end())
            (at / i).fail("figure '" + name + "' listed twice");
        scene.figures.push_back(f);
    }
}

SceneJoint Builder::jointFrom(const Json& o, const Loc& at, const std::string& type, std::uint32_t a,
                              std::uint32_t b) const {
    const SceneBody &bodyA = scene.bodies[a], &bodyB = scene.bodies[b];
    if (a == b) at.fail("a joint needs two different bodies (got body " + std::to_string(a) + " twice)");
    if (bodyA.def.type == BodyType::Static && bodyB.def.type == BodyType::Static)
        at.fail("bodies " + std::to_string(a) + " and " + std::to_string(b) + " are both static");
    SceneJoint joint;
    joint.bodyA = a, joint.bodyB = b;
    const Vec3 midpoint = (bodyA.def.position + bodyB.def.position) * 0.5f;
    joint.anchorA = joint.anchorB = midpoint;
    const bool rod = type == "distance" || type == "spring";
    if (o.contains("anchor") && o.contains("anchors")) at.fail("give 'anchor' or 'anchors', not both");
    if (o.contains("anchor")) joint.anchorA = joint.anchorB = getVec3(o["anchor"], at / "anchor");
    if (o.contains("anchors")) {
        const Loc al = at / "anchors";
        if (!rod) al.fail("only distance and spring joints have two anchors; a " + type + " joint has one ('anchor')");
        if (!o["anchors"].is_array() || o["anchors"].size() != 2)
            al.fail("expected two points [[x, y, z], [x, y, z]], got " + describe(o["anchors"]));
        joint.anchorA = getVec3(o["anchors"][0], al / 0);
        joint.anchorB = getVec3(o["anchors"][1], al / 1);
    }
    JointBase base;
    if (o.contains("collide_connected"))
        base.collideConnected = getBool(o["collide_connected"], at / "collide_connected");
    if (o.contains("break_force")) base.breakForce = getFloat(o["break_force"], at / "break_force", Sign::Positive);
    if (o.contains("break_torque")) base.breakTorque = getFloat(o["break_torque"], at / "break_torque", Sign::Positive);
    if (type == "distance") {
        DistanceJointDef d;
        static_cast<JointBase&>(d) = base;
        if (o.contains("length")) {
            d.length = getFloat(o["length"], at / "length", Sign::Positive);
            if (*d.length < 1e-3f) (at / "length").fail("must be >= 0.001 m (use a ball joint for coincident anchors)");
        } else if (!(length(joint.anchorB - joint.anchorA) >= 1e-3f)) {
            at.fail("a distance joint's anchors must be at least 1 mm apart (give 'anchors' or 'length')");
        }
        joint.def = d;
    } else if (type == "spring") {
        SpringJointDef d;
        static_cast<JointBase&>(d) = base;
        if (o.contains("stiffness")) d.stiffness = getFloat(o["stiffness"], at / "stiffness", Sign::NonNegative);
        if (o.contains("damping")) d.damping = getFloat(o["damping"], at / "damping", Sign::NonNegative);
        if (o.contains("rest_length")) d.restLength = getFloat(o["rest_length"], at / "rest_length", Sign::NonNegative);
        joint.def = d;
    } else if (type == "ball") {
        BallJointDef d;
        static_cast<JointBase&>(d) = base;
        joint.def = d;
    } else {  // hinge
        HingeJointDef d;
        static_cast<JointBase&>(d) = base;
        if (o.contains("axis")) {
            joint.axis = getVec3(o["axis"], at / "axis");
            if (!(length(joint.axis) > 0)) (at / "axis").fail("axis must not be zero");
        }
        // An object of exactly two numbers, as the limit and the motor are.
        const auto numberPair = [&](const char* key, const char* first, const char* second, Sign secondSign) {
            const Loc l = at / key;
            const Json& pair =
                expectObject(o[key], l, std::string("an object {\"") + first + "\": .., \"" + second + "\": ..}");
            checkKeys(pair, l, {first, second});
            require(pair, l, first);
            require(pair, l, second);
            return std::pair{getFloat(pair[first], l / first), getFloat(pair[second], l / second, secondSign)};
        };
        if (o.contains("limit")) {
            d.enableLimit = true;
            std::tie(d.lowerAngle, d.upperAngle) = numberPair("limit", "lower", "upper", Sign::Any);
            constexpr float kPi = 3.14159265358979f;
            if (!(d.lowerAngle >= -kPi && d.upperAngle <= kPi && d.lowerAngle <= d.upperAngle))
                (at / "limit")
                    .fail("needs -pi <= lower <= upper <= pi (got [" + formatNumber(d.lowerAngle) + ", " +
                          formatNumber(d.upperAngle) + "])");
        }
        if (o.contains("motor")) {
            d.enableMotor = true;
            std::tie(d.motorSpeed, d.maxMotorTorque) = numberPair("motor", "speed", "max_torque", Sign::NonNegative);
        }
        joint.def = d;
    }
    return joint;
}

void Builder::parseJoints(const Json& j, const Loc& at) {
    const Json& arr = expectArray(j, at, "an array of joints");
    if (!arr.empty() && !scene.settings.effects.has(Effect::Joints))
        at.fail("the scene has joints but its settings' effects leave out 'joints': add it, or they would not act");
    const auto bodyIndex = [&](const Json& v, const Loc& l) {
        if (scene.bodies.empty()) l.fail("the scene has no bodies to join");
        return static_cast<std::uint32_t>(getInt(v, l, 0, static_cast<std::int64_t>(scene.bodies.size()) - 1));
    };
    for (std::size_t i = 0; i < arr.size(); ++i) {
        const Loc jl = at / i;
        const Json& o = expectObject(arr[i], jl, "a joint object");
        checkKeys(o, jl,
                  {"type", "bodies", "lattice", "anchor", "anchors", "axis", "collide_connected", "break_force",
                   "break_torque", "length", "stiffness", "damping", "rest_length", "limit", "motor"});
        require(o, jl, "type");
        const std::string& type = getString(o["type"], jl / "type");
        if (type != "distance" && type != "spring" && type != "ball" && type != "hinge")
            (jl / "type")
                .fail("unknown joint type '" + printable(type) + "'" +
                      suggestion(type, std::initializer_list<std::string_view>{"distance", "spring", "ball", "hinge"}));
        const std::string_view springKeys[] = {"stiffness", "damping", "rest_length"};
        for (const std::string_view k : springKeys)
            if (o.contains(k) && type != "spring") (jl / k).fail("only spring joints have '" + std::string(k) + "'");
        if (o.contains("length") && type != "distance") (jl / "length").fail("only distance joints have 'length'");
        for (const char* k : {"axis", "limit", "motor"})
            if (o.contains(k) && type != "hinge") (jl / k).fail(std::string("only hinges have '") + k + "'");
        if (o.contains("bodies") == o.contains("lattice")) jl.fail("give exactly one of 'bodies' and 'lattice'");
        if (o.contains("bodies")) {
            const Loc bl = jl / "bodies";
            if (!o["bodies"].is_array() || o["bodies"].size() != 2)
                bl.fail("expected two body indices [a, b], got " + describe(o["bodies"]));
            scene.joints.push_back(
                jointFrom(o, jl, type, bodyIndex(o["bodies"][0], bl / 0), bodyIndex(o["bodies"][1], bl / 1)));
            continue;
        }
        // A lattice: the bodies [first, first + nx ny nz) laid out as a grid generator lays them (layer y outermost,
        // then x, then z), each joined to its next neighbour along the axes named, at their midpoint.
        const Loc ll = jl / "lattice";
        const Json& l = expectObject(o["lattice"], ll, "a lattice object");
        checkKeys(l, ll, {"first", "count", "along"});
        for (const char* k : {"first", "count", "along"}) require(l, ll, k);
        if (o.contains("anchor") || o.contains("anchors"))
            jl.fail("a lattice joins neighbours at their midpoints: it takes no 'anchor' or 'anchors'");
        const std::uint32_t first = bodyIndex(l["first"], ll / "first");
        const Loc cl = ll / "count";
        if (!l["count"].is_array() || l["count"].size() != 3)
            cl.fail("expected an array of 3 integers [nx, ny, nz], got " + describe(l["count"]));
        std::int64_t count[3];
        for (std::size_t a = 0; a < 3; ++a) count[a] = getInt(l["count"][a], cl / a, 1, 1'000'000'000);
        const double total = double(count[0]) * double(count[1]) * double(count[2]);
        if (double(first) + total > double(scene.bodies.size()))
            ll.fail("bodies " + std::to_string(first) + " .. " + formatNumber(double(first) + total - 1) +
                    " do not exist (the scene has " + std::to_string(scene.bodies.size()) + ")");
        const Loc al = ll / "along";
        const Json& along = expectArray(l["along"], al, "an array of axis names (\"x\", \"y\", \"z\")");
        bool axes[3] = {false, false, false};
        for (std::size_t k = 0; k < along.size(); ++k) {
            const std::string& name = getString(along[k], al / k);
            if (name != "x" && name != "y" && name != "z") (al / k).fail("expected \"x\", \"y\" or \"z\"");
            axes[name[0] - 'x'] = true;
        }
        const std::int64_t nx = count[0], ny = count[1], nz = count[2];
        const auto at3 = [&](std::int64_t ix, std::int64_t iy, std::int64_t iz) {
            return static_cast<std::uint32_t>(first + iy * nx * nz + ix * nz + iz);
        };
        // Two static neighbours (a fixed edge) have nothing to join.
        const auto join = [&](std::uint32_t a, std::uint32_t b) {
            if (scene.bodies[a].def.type == BodyType::Static && scene.bodies[b].def.type == BodyType::Static) return;
            scene.joints.push_back(jointFrom(o, jl, type, a, b));
        };
        for (std::int64_t iy = 0; iy < ny; ++iy)
            for (std::int64_t ix = 0; ix < nx; ++ix)
                for (std::int64_t iz = 0; iz < nz; ++iz) {
                    const std::uint32_t self = at3(ix, iy, iz);
                    if (axes[0] && ix + 1 < nx) join(self, at3(ix + 1, iy, iz));
                    if (axes[1] && iy + 1 < ny) join(self, at3(ix, iy + 1, iz));
                    if (axes[2] && iz + 1 < nz) join(self, at3(ix, iy, iz + 1));
                }
    }
}

}  // namespace

Scene parseScene(std::string_view text, const std::string& sourceName) {
    return scene_detail::parseSceneWithin(text, sourceName, scene_detail::SceneCaps{});
}

Scene scene_detail::parseSceneWithin(std::string_view text, const std::string& sourceName, const SceneCaps& caps) {
    if (text.size() > limits::kMaxSceneFileBytes)
        throw Error(sourceName + ": larger than " + std::to_string(limits::kMaxSceneFileBytes >> 20) +
                    " MiB, the most a scene file may be (docs/limits.md)");
    Builder b;
    b.caps = caps;
    b.file = sourceName;
    b.dir = std::filesystem::path(sourceName).parent_path();
    b.scene.source = sourceName;
    b.scene.name = std::filesystem::path(sourceName).stem().string();

    const Json doc = parseJson(text, sourceName);
    const Loc root = b.root();
    if (!doc.is_object()) throw Error(sourceName + ": the top level must be an object, got " + describe(doc));
    checkKeys(doc, root,
              {"name", "description", "steps", "settings", "materials", "shapes", "bodies", "generators", "joints",
               "figures"});
    if (doc.contains("name")) b.scene.name = getString(doc["name"], root / "name");
    if (doc.contains("description")) getString(doc["description"], root / "description");
    if (doc.contains("steps"))
        b.scene.steps = static_cast<int>(getInt(doc["steps"], root / "steps", 0, limits::kMaxRunnerSteps));
    if (doc.contains("settings")) b.parseSettings(doc["settings"], root / "settings");
    if (doc.contains("materials")) b.parseMaterials(doc["materials"], root / "materials");
    if (doc.contains("shapes")) b.parseShapes(doc["shapes"], root / "shapes");
    if (doc.contains("bodies")) b.parseBodies(doc["bodies"], root / "bodies");
    if (doc.contains("generators")) b.parseGenerators(doc["generators"], root / "generators");
    if (doc.contains("joints")) b.parseJoints(doc["joints"], root / "joints");
    if (doc.contains("figures")) b.parseFigures(doc["figures"], root / "figures");
    return std::move(b.scene);
}

void overrideSettings(Scene& scene, std::string_view settingsJson, const std::string& sourceName) {
    Builder b;
    b.file = sourceName;
    b.scene.settings = scene.settings;
    const Json doc = parseJson(settingsJson, sourceName);
    if (!doc.is_object()) throw Error(sourceName + ": settings must be an object, got " + describe(doc));
    b.parseSettings(doc, b.root());
    scene.settings = b.scene.settings;
}

Scene loadScene(const std::string& path) {
    return parseScene(detail::readRegularFile(path, limits::kMaxSceneFileBytes, "a scene file"), path);
}

}  // namespace rubble
