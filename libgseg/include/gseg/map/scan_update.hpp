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

/// The per-scan result: a plain value (serialisable with serializeScanUpdate()).
struct ScanUpdate {
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< [m] sensor position, world frame
    std::vector<std::uint64_t> free;          ///< voxels crossed by a ray and holding no hit of this scan (sorted)
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

/// A compact byte string of the update (sorted codes delta-encoded as varints), for sending the
/// per-scan result to another process. Little-endian, versioned: "GSU3" (with groundCells and the
/// terrain samples); deserializeScanUpdate() also reads "GSU2" (no terrain samples) and "GSU1" (no
/// ground cells either).
std::string serializeScanUpdate(const ScanUpdate& update);
/// Inverse of serializeScanUpdate(). Throws std::runtime_error on a truncated or malformed string.
ScanUpdate deserializeScanUpdate(const std::string& bytes);

}  // namespace gseg::map
