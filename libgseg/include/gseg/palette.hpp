#pragma once
/// \file palette.hpp
/// The class colours of every output, one palette: the scan and map PLYs (gseg/io/ply.hpp), the
/// scan and map PNGs and the scan and map `.3Dscene` files. Ground (a scan's label 1, a map's
/// traversable voxels and cells) is green, non-ground (label 0, obstacles) red.

#include <cstdint>

namespace gseg::palette {

/// RGB, 0-255: ground / traversable.
inline constexpr std::uint8_t kGround[3] = {60, 180, 75};
/// RGB, 0-255: non-ground / obstacle.
inline constexpr std::uint8_t kNonGround[3] = {220, 40, 40};

}  // namespace gseg::palette
