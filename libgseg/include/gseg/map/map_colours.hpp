#pragma once
/// \file map_colours.hpp
/// The colours of the map layer's pictures and files: one per cell class (the top-down PNG, the
/// layer pictures, the voxels of the `.ot`, `.ply` and `.3Dscene`) and the page around a map.

#include <gseg/map/column_class.hpp>
#include <gseg/mrpt/picture.hpp>

namespace gseg::map {

/// The one colour type of gseg's pictures and files (8-bit RGB, gseg/mrpt/picture.hpp).
using Rgb = gseg::mrpt::Colour;
/// RGB of each class in the PNG (also the voxel colours of the `.ot`, `.ply` and `.3Dscene`).
Rgb colourOf(ColumnClass c);
/// RGB of the page around the mapped area (darker than Unknown).
Rgb backgroundColour();

}  // namespace gseg::map
