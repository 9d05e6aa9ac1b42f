#pragma once
// What the command-line programs in apps/ share: whole-number option values and where the default scene is.
#include <unistd.h>

#include <charconv>
#include <optional>
#include <string>
#include <string_view>

namespace rubble::apps {

/// `text` read whole as a number in [min, max], or nothing (not a number, trailing characters, out of range).
inline std::optional<long> parseWhole(std::string_view text, long min, long max) {
    long value = 0;
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc{} || ptr != text.data() + text.size() || value < min || value > max) return std::nullopt;
    return value;
}

/// What to tell the user when `flag` was given `text` instead of a whole number in [min, max].
inline std::string wholeNumberError(std::string_view flag, std::string_view text, long min, long max) {
    return std::string(flag) + " takes a whole number in [" + std::to_string(min) + ", " + std::to_string(max) +
           "], not '" + std::string(text) + "'";
}

/// An argument no option claimed: the first bare word is the scene; an unknown option or a second scene is an error,
/// returned as what to tell the user.
inline std::optional<std::string> takeSceneArgument(std::string_view arg, std::string& scene) {
    if (!arg.empty() && arg[0] == '-') return "unknown option '" + std::string(arg) + "'";
    if (!scene.empty()) return "more than one scene given ('" + scene + "' and '" + std::string(arg) + "')";
    scene = std::string(arg);
    return std::nullopt;
}

/// S1 from the working directory when it is there (a checkout), else from `scenesDir` (the source tree's scenes).
inline std::string defaultScene(const std::string& scenesDir) {
    const std::string candidates[] = {"scenes/s1_pyramid.json", scenesDir + "/s1_pyramid.json"};
    for (const std::string& path : candidates)
        if (access(path.c_str(), R_OK) == 0) return path;
    return candidates[0];
}

}  // namespace rubble::apps
