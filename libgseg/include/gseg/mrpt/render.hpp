#pragma once
/// \file render.hpp
/// Top-down pictures of a labelled scan (PNG), drawn with the shared picture conventions of
/// gseg/mrpt/picture.hpp.

#include <gseg/mrpt/picture.hpp>
#include <gseg/mrpt/png.hpp>
#include <gseg/mrpt/top_view.hpp>
#include <gseg/palette.hpp>
#include <gseg/point_cloud.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace gseg::mrpt {

/// How the picture is drawn. The sensor is at the centre; x (forward) points up, y (left) points left.
using RenderOptions = TopViewOptions;

/// Colours of the labels in scan pictures and scenes: the one palette (gseg/palette.hpp), as the
/// PLYs and the map's traversable / obstacle cells.
inline constexpr Colour kGroundColour{palette::kGround[0], palette::kGround[1], palette::kGround[2]};
inline constexpr Colour kNonGroundColour{palette::kNonGround[0], palette::kNonGround[1], palette::kNonGround[2]};

/// A top-down picture of a labelled scan as PNG bytes (drawTopView(), encodePng()): ground green,
/// non-ground red (drawn over the ground), with the title, orientation, range circles, forward
/// arrow, scale bar and a legend with the counts; points with a NaN or infinite coordinate are not
/// drawn. Throws std::invalid_argument if the label count differs from the point count.
std::string topDownPng(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                       const RenderOptions& options = RenderOptions());

}  // namespace gseg::mrpt
