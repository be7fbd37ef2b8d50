#pragma once
/// \file map_tree.hpp
/// Internal to the map layer: an OctoMap OcTree built from voxels in sorted order in one walk,
/// pruned where eight sibling leaves hold the same clamped value (every voxel keeps its value).

#include <octomap/OcTree.h>

#include <cstddef>
#include <cstdint>

namespace gseg::map::detail {

class MapTree : public octomap::OcTree {
public:
    explicit MapTree(double resolution) : octomap::OcTree(resolution) {}

    /// Sets the log-odds of `n` voxels (Morton codes, see voxel_keys.hpp), creating them; codes
    /// must be increasing, also from one call to the next. Inner nodes get their children's
    /// maximum (OcTreeNode::updateOccupancyChildren()).
    void setSorted(const std::uint64_t* codes, const float* values, std::size_t n);
};

}  // namespace gseg::map::detail
