#pragma once
/// \file png.hpp
/// Internal to the map layer: a PNG (8-bit RGB) encoded in memory, row by row, so that a large
/// picture never exists uncompressed and every byte of the file is written by checked code.

#include <cstdint>
#include <functional>
#include <string>

namespace gseg::map::detail {

/// PNG bytes of a width x height RGB image; fillRow(row, rgb) writes the 3 * width bytes of a row.
/// Throws std::invalid_argument on a size of 0 or above 2^31 - 1 pixels a side.
std::string encodePngRgb(int width, int height, const std::function<void(int, std::uint8_t*)>& fillRow);

}  // namespace gseg::map::detail
