#pragma once
// Whether this build runs under a sanitizer (RUBBLE_SANITIZE). The whole-scene stability tests then run their scenes
// for a few steps, so that the sanitizer watches the code they reach, and leave their physical bounds to the plain
// build: under ASan a 200-step run of a 5,000-body wall takes minutes, not seconds.
namespace rubble::test {

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

/// The steps a whole-scene test runs: all of them, or at most 10 under a sanitizer.
inline int scaledSteps(int steps) { return kSanitized && steps > 10 ? 10 : steps; }

}  // namespace rubble::test
