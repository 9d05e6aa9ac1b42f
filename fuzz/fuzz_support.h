#pragma once
// What the fuzz targets share: reading typed choices out of libFuzzer's bytes, and failing loudly.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace rubble::fuzz {

/// A property an accepted input broke: print it and abort, which libFuzzer reports as a crash with the input saved.
[[noreturn]] inline void fail(const std::string& what) {
    std::fprintf(stderr, "fuzz property broken: %s\n", what.c_str());
    std::fflush(stderr);
    std::abort();
}

inline void check(bool ok, const std::string& what) {
    if (!ok) fail(what);
}

/// Draws choices from the input's bytes, front to back; once they run out every draw is zero, so a short input is a
/// short program, never an error.
class FuzzInput {
public:
    FuzzInput(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

    bool empty() const { return at_ >= size_; }
    std::uint8_t byte() { return at_ < size_ ? data_[at_++] : 0; }
    std::uint16_t u16() { return static_cast<std::uint16_t>(byte() | (byte() << 8)); }
    std::uint32_t u32() { return u16() | (static_cast<std::uint32_t>(u16()) << 16); }
    /// 0 .. n - 1 (n > 0).
    std::uint32_t below(std::uint32_t n) { return (n <= 256 ? byte() : u32()) % n; }
    bool flag() { return (byte() & 1) != 0; }
    /// Uniform over [lo, hi] in 65,536 steps.
    float in(float lo, float hi) { return lo + (hi - lo) * static_cast<float>(u16()) / 65535.0f; }
    /// Any float bit pattern: NaN, infinities, subnormals and the extremes included.
    float bits() {
        const std::uint32_t word = u32();
        float value;
        std::memcpy(&value, &word, sizeof value);
        return value;
    }
    /// Mostly a value in [lo, hi]; one draw in sixteen any bit pattern, for the checks of bad input.
    float mostlyIn(float lo, float hi) { return (byte() & 15) == 0 ? bits() : in(lo, hi); }

private:
    const std::uint8_t* data_;
    std::size_t size_;
    std::size_t at_ = 0;
};

}  // namespace rubble::fuzz
