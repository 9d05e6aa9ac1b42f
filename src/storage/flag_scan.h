#pragma once
// The bodies' flag bytes read eight at a time, so that the passes that skip sleeping bodies cost a world that mostly
// sleeps a word per eight sleepers instead of a test and a branch per body.
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace rubble::detail {

/// `bit` in every byte of a word.
constexpr std::uint64_t everyByte(std::uint8_t bit) { return 0x0101010101010101ull * bit; }

inline std::uint64_t flagWord(const std::uint8_t* flags) {
    std::uint64_t word;
    std::memcpy(&word, flags, sizeof word);
    return word;
}

/// Whether every one of flags[0, count) has `bit`.
inline bool allHave(const std::uint8_t* flags, std::size_t count, std::uint8_t bit) {
    std::size_t k = 0;
    for (; k + 8 <= count; k += 8)
        if ((flagWord(flags + k) & everyByte(bit)) != everyByte(bit)) return false;
    for (; k < count; ++k)
        if ((flags[k] & bit) == 0) return false;
    return true;
}

/// How many of flags[0, count) have `bit`.
inline std::size_t countWith(const std::uint8_t* flags, std::size_t count, std::uint8_t bit) {
    std::size_t n = 0, k = 0;
    for (; k + 8 <= count; k += 8) n += static_cast<std::size_t>(std::popcount(flagWord(flags + k) & everyByte(bit)));
    for (; k < count; ++k) n += (flags[k] & bit) != 0;
    return n;
}

/// The first index in [begin, end) whose flag lacks `bit` (end if none): a run of bodies that all have it is passed
/// over a word at a time.
inline std::size_t nextWithout(const std::uint8_t* flags, std::size_t begin, std::size_t end, std::uint8_t bit) {
    std::size_t k = begin;
    while (k + 8 <= end && (flagWord(flags + k) & everyByte(bit)) == everyByte(bit)) k += 8;
    while (k < end && (flags[k] & bit) != 0) ++k;
    return k;
}

/// The first index in [begin, end) whose flag has `bit` (end if none), likewise.
inline std::size_t nextWith(const std::uint8_t* flags, std::size_t begin, std::size_t end, std::uint8_t bit) {
    std::size_t k = begin;
    while (k + 8 <= end && (flagWord(flags + k) & everyByte(bit)) == 0) k += 8;
    while (k < end && (flags[k] & bit) == 0) ++k;
    return k;
}

}  // namespace rubble::detail
