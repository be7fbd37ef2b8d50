#pragma once
/// \file fuzz_input.hpp
/// Structured values from a fuzzer's bytes (past the end: zeros), and the check that ends a run.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace gseg::fuzz {

/// A violated property: print it and abort (libFuzzer saves the input as a crash).
#define GSEG_FUZZ_CHECK(cond)                                                             \
    do {                                                                                  \
        if (!(cond)) {                                                                    \
            std::fprintf(stderr, "gseg fuzz check failed: %s (%s:%d)\n", #cond, __FILE__, __LINE__); \
            std::abort();                                                                 \
        }                                                                                 \
    } while (0)

class FuzzInput {
public:
    FuzzInput(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

    template <typename T>
    T take() {
        T v{};
        const std::size_t n = std::min(sizeof(T), size_ - pos_);
        std::memcpy(&v, data_ + pos_, n);
        pos_ += n;
        return v;
    }
    bool flag() { return take<std::uint8_t>() & 1; }
    /// 0..max
    std::size_t count(std::size_t max) { return max == 0 ? 0 : take<std::uint16_t>() % (max + 1); }
    /// Uniform in [lo, hi].
    double uniform(double lo, double hi) { return lo + (hi - lo) * take<std::uint16_t>() / 65535.0; }
    /// Log-uniform in [lo, hi] (lo > 0).
    double logUniform(double lo, double hi) { return lo * std::pow(hi / lo, take<std::uint16_t>() / 65535.0); }
    /// Any float bit pattern (NaN, infinities, denormals, huge values included).
    float anyFloat() { return take<float>(); }
    std::string text(std::size_t maxLength) {
        const std::size_t n = std::min(count(maxLength), size_ - pos_);
        std::string s(reinterpret_cast<const char*>(data_ + pos_), n);
        pos_ += n;
        return s;
    }
    std::size_t remaining() const { return size_ - pos_; }
    const std::uint8_t* here() const { return data_ + pos_; }

private:
    const std::uint8_t* data_;
    std::size_t size_, pos_ = 0;
};

}  // namespace gseg::fuzz
