#pragma once
/// \file scan_update.hpp
/// What one scan does to the traversability maps, computed without the maps: the voxels its rays
/// cross (misses) and the voxels its ground and obstacle points fall in (hits). Ray casting a
/// scan is independent of every other scan, so scans can be cast on any thread (or process) in
/// any order; TraversabilityMap::apply() then applies the updates strictly in scan order, which
/// makes the maps the same whatever the order the casting finished in.
///
/// Voxels are OctoMap keys at the map resolution as Morton codes (see TraversabilityMap): sorted,
/// so an update is one walk down the trees.

#include <gseg/terrain_model.hpp>
#include <gseg/traversability_options.hpp>
#include <gseg/point_cloud.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace gseg::map {

/// The ground points of one scan that fall in one map cell (a column of voxels): what the 2.5D
/// layers (terrain_layers.hpp) accumulate over the drive, so they come from the points' heights,
/// not from voxel centres, and need no point lists.
struct GroundCellSample {
    std::uint32_t cell = 0;  ///< OctoMap key of the column: (key x << 16) | key y (cell ix = key x - 32768)
    std::uint32_t count = 0; ///< ground points in the cell
    double sumZ = 0;         ///< [m] sum of their world z
    double sumZ2 = 0;        ///< [m^2] sum of their squared world z
    double sumX = 0, sumY = 0;  ///< [m] sums of their world x and y (the centroid, for the slope)
    float minZ = 0, maxZ = 0;  ///< [m] lowest and highest of them

    bool operator==(const GroundCellSample& o) const {
        return cell == o.cell && count == o.count && sumZ == o.sumZ && sumZ2 == o.sumZ2 && sumX == o.sumX && sumY == o.sumY && minZ == o.minZ && maxZ == o.maxZ;
    }
};

/// A set of voxels as bricks of 8 x 8 x 8 (Morton code >> 9: the OctoMap subtrees three levels
/// above the leaves), in increasing order, each with eight words of 64 voxels: bit v of word w is
/// the voxel whose last nine Morton bits are 64 w + v. No brick is empty. A scan's free space is a
/// few hundred thousand voxels in a few ten thousand bricks: kept this way from the ray casting to
/// the map update (and between processes), it is never listed voxel by voxel.
struct VoxelBricks {
    std::vector<std::uint64_t> bricks;  ///< brick codes, increasing
    std::vector<std::uint64_t> words;   ///< eight per brick

    bool empty() const { return bricks.empty(); }
    std::size_t voxels() const;                ///< how many voxels
    std::vector<std::uint64_t> codes() const;  ///< the voxels' Morton codes, increasing
    /// The set of `codes` (sorted).
    static VoxelBricks fromCodes(const std::vector<std::uint64_t>& codes);
    bool operator==(const VoxelBricks& o) const { return bricks == o.bricks && words == o.words; }
};

/// The per-scan result: a plain value (serialisable with serializeScanUpdate()).
struct ScanUpdate {
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< [m] sensor position, world frame
    VoxelBricks free;                         ///< voxels crossed by a ray and holding no hit of this scan
    std::vector<std::uint64_t> groundHits;    ///< voxels holding a ground point within maxRange (sorted)
    std::vector<std::uint64_t> obstacleHits;  ///< voxels holding an obstacle point within maxRange (sorted)
    std::uint64_t groundPoints = 0;           ///< ground points given
    std::uint64_t obstaclePoints = 0;         ///< obstacle points given
    std::uint64_t rays = 0;                   ///< rays cast (one per endpoint voxel)
    std::uint64_t pointsSkipped = 0;          ///< points not used: NaN/infinite or outside the map's extent
    std::vector<GroundCellSample> groundCells;  ///< ground points within maxRange per cell (sorted by cell)
    std::vector<gseg::TerrainSample> terrain;   ///< the drive's terrain model's evidence, points within maxRange (driveTerrain; sorted by cell)

    bool operator==(const ScanUpdate& o) const;
};

/// Ray casts one scan, all in the world frame [m]: one ray from `sensorOrigin` to the first point
/// of each endpoint voxel (ground points first, then obstacles; points beyond maxRange end their
/// ray at maxRange and add no hit), as OctoMap's discretized insertion does. Throws
/// std::invalid_argument on invalid options and std::out_of_range (naming the position and the
/// extent) if the origin lies outside the map's extent (TraversabilityOptions::extent()).
ScanUpdate castScan(const PointCloudView& ground, const PointCloudView& obstacles, const Eigen::Vector3d& sensorOrigin,
                    const TraversabilityOptions& options);

/// A compact byte string of the update (sorted codes and bricks delta-encoded as varints, the
/// free bricks' nonzero words as they are), for sending the per-scan result to another process.
/// Little-endian, versioned: "GSU4" (free space as bricks); deserializeScanUpdate() also reads
/// "GSU3" (free space as codes), "GSU2" (no terrain samples either) and "GSU1" (no ground cells).
std::string serializeScanUpdate(const ScanUpdate& update);
/// Inverse of serializeScanUpdate(). Throws std::runtime_error on a truncated or malformed string.
ScanUpdate deserializeScanUpdate(const std::string& bytes);

}  // namespace gseg::map
