#pragma once
/// \file column_class.hpp
/// The traversability class of one map cell (a column of voxels of the top-down grid, a cell of
/// the `class` layer): the one classification every map output shows.

#include <cstdint>

namespace gseg::map {

/// What the top-down grid says about one column of voxels (also the values of the `class` layer).
/// Not the core's gseg::CellClass (gseg/cell_types.hpp: the eigen class of a segmentation cell).
enum class ColumnClass : std::uint8_t { Unknown = 0, Traversable = 1, Obstacle = 2 };

}  // namespace gseg::map
