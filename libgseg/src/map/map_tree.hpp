#pragma once
/// \file map_tree.hpp
/// Internal to the map layer: an OctoMap OcTree updated from sorted voxel lists in one walk, pruned
/// as it goes, and written in the exact bytes of the unpruned tree that voxel-by-voxel
/// OcTree::updateNode() calls would have built.

#include <octomap/OcTree.h>

#include <cstdint>
#include <ostream>
#include <vector>

namespace gseg::map::detail {

/// How a voxel list changes the voxels.
enum class VoxelUpdate {
    Hit,                 ///< add the hit log-odds
    Miss,                ///< add the miss log-odds
    MissUnlessOccupied,  ///< add the miss log-odds to voxels not already occupied
};

class MapTree : public octomap::OcTree {
public:
    explicit MapTree(double resolution) : octomap::OcTree(resolution) {}

    /// Updates every voxel of `codes` (sorted Morton codes, see voxel_keys.hpp), creating the
    /// missing ones, with the same per-voxel arithmetic as OcTree::updateNode(key, hit/miss, lazy).
    /// Inner nodes get their children's maximum, and eight equal leaf siblings are pruned into
    /// their parent (every voxel keeps its value).
    void applySorted(const std::vector<std::uint64_t>& codes, VoxelUpdate how);

    /// What writeBinaryConst() writes for the unpruned tree with the same voxels (header included).
    void writeUnprunedBinary(std::ostream& out) const;

    /// Nodes the unpruned tree would have.
    std::uint64_t unprunedSize() const;
};

}  // namespace gseg::map::detail
