#pragma once
/// \file float_cast.hpp
/// double to float without undefined behaviour: values beyond the float range become +-infinity
/// (a plain cast of such a value is undefined in C++), NaN stays NaN.

#include <cmath>
#include <limits>

namespace gseg::io {

inline float toFloat(double v) {
    constexpr double kMax = std::numeric_limits<float>::max();
    if (v > kMax) return std::numeric_limits<float>::infinity();
    if (v < -kMax) return -std::numeric_limits<float>::infinity();
    return static_cast<float>(v);
}

}  // namespace gseg::io
