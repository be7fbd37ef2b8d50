#pragma once
/// \file traversability_map.hpp
/// Traversability OctoMaps built from segmented scans: one occupancy OcTree for the ground, one
/// for the obstacles (free space from ray casting, occupied from hits), a ColorOcTree with both,
/// and a top-down grid (traversable / obstacle / unknown) with the driven path.
///
/// Frame: everything is in one world frame (metres, z up). Callers transform points with the
/// robot pose and the sensor mounting first, and give the sensor's world position as ray origin.

#include <gseg/point_cloud.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace octomap {
class OcTree;
class ColorOcTree;
}  // namespace octomap

namespace gseg::map {

namespace detail {
struct KeyMemory;  // voxel keys ever occupied as obstacle (implementation detail)
}

/// How scans are fused. Probabilities are OctoMap's (log-odds update per scan and voxel).
struct TraversabilityOptions {
    double resolution = 0.2;          ///< [m] voxel edge (also the top-down grid cell)
    double maxRange = 50.0;           ///< [m] longer rays clear free space up to this range and add no hit
    double probHit = 0.7;             ///< [-] occupancy probability of a hit
    double probMiss = 0.4;            ///< [-] occupancy probability of a ray passing through
    double clampMin = 0.12;           ///< [-] lower clamping of the occupancy probability
    double clampMax = 0.97;           ///< [-] upper clamping (lower: quicker clearing of moved obstacles)
    double occupancyThreshold = 0.5;  ///< [-] a voxel is occupied above this probability
    double clearance = 2.0;           ///< [m] obstacle voxels higher than this above the column's ground do not block it (branches, bridges)
    void validate() const;            ///< throws std::invalid_argument naming the first invalid field
};

/// What the top-down grid says about one column of voxels.
enum class CellClass : std::uint8_t { Unknown = 0, Traversable = 1, Obstacle = 2 };

/// Top-down grid: one cell per voxel column. Row 0 is the largest y (north up), column 0 the
/// smallest x; the PNG shows the same cells, one pixel each.
struct TopDownGrid {
    double minX = 0, maxY = 0;  ///< [m] world x of the left edge and world y of the top edge
    double cell = 0.2;          ///< [m] cell edge
    int width = 0, height = 0;  ///< [cells]
    std::vector<CellClass> cells;  ///< row-major, width * height

    /// Column / row of world (x, y); false if outside the grid.
    bool toPixel(double x, double y, int& col, int& row) const;
    /// Class at world (x, y); Unknown outside the grid.
    CellClass at(double x, double y) const;
};

/// Figures of a map, voxels counted at the finest resolution.
struct MapStats {
    std::size_t scans = 0;             ///< scans inserted
    std::size_t groundPoints = 0;      ///< ground points given (all scans)
    std::size_t obstaclePoints = 0;    ///< obstacle points given (all scans)
    std::size_t rays = 0;              ///< rays cast (one per endpoint voxel and scan)
    std::size_t groundVoxels = 0;      ///< occupied voxels of the ground tree
    std::size_t obstacleVoxels = 0;    ///< occupied voxels of the obstacle tree
    std::size_t freeVoxels = 0;        ///< voxels known free in the obstacle tree
    std::size_t clearedObstacleVoxels = 0;  ///< voxels once occupied as obstacle, free by the end (seen through)
    std::size_t groundUnderObstacle = 0;    ///< occupied in both trees: shown as obstacle
    std::size_t cellsTraversable = 0, cellsObstacle = 0, cellsUnknown = 0;  ///< top-down grid
    double pathLength = 0;             ///< [m] length of the sensor path
};

/// Builds the maps scan by scan. Per scan, every voxel crossed by a ray (to a ground or an obstacle
/// point) gets a miss in both trees, except voxels holding a hit of that scan; ground hits update
/// the ground tree only, obstacle hits the obstacle tree only. So an obstacle that later scans see
/// through is cleared, and a ground hit never lowers an obstacle voxel (a voxel occupied in both
/// trees counts as obstacle). Misses never lower an occupied ground voxel: rays to distant ground
/// graze the road just before their end and would erode it (ground does not move).
class TraversabilityMap {
public:
    /// Throws std::invalid_argument on invalid options.
    explicit TraversabilityMap(const TraversabilityOptions& options = TraversabilityOptions());
    ~TraversabilityMap();
    TraversabilityMap(TraversabilityMap&&) noexcept;
    TraversabilityMap& operator=(TraversabilityMap&&) noexcept;

    const TraversabilityOptions& options() const { return options_; }

    /// Inserts one scan: ground and obstacle points and the sensor origin, all in the world frame
    /// [m]. Throws std::invalid_argument on a NaN/infinite origin; NaN points are skipped.
    void insertScan(const PointCloudView& ground, const PointCloudView& obstacles, const Eigen::Vector3d& sensorOrigin);

    bool empty() const { return stats_.scans == 0; }
    const octomap::OcTree& groundTree() const { return *ground_; }
    const octomap::OcTree& obstacleTree() const { return *obstacles_; }
    const std::vector<Eigen::Vector3d>& path() const { return path_; }  ///< sensor origins, in order

    /// Ground and obstacle voxels in one tree: ground green, obstacle red (occupied voxels only).
    std::unique_ptr<octomap::ColorOcTree> colouredTree() const;
    /// The top-down grid over every occupied voxel and the path.
    TopDownGrid topDown() const;
    /// Counters and voxel counts (walks both trees).
    MapStats stats() const;

    /// Writes `<prefix>_ground.bt`, `<prefix>_obstacles.bt`, `<prefix>_traversability.ot` and
    /// `<prefix>_traversability.png`: all of them or none (temporary files, then renamed). Throws
    /// std::runtime_error naming the file on failure and std::logic_error if no scan was inserted.
    /// Returns the paths written.
    std::vector<std::string> write(const std::string& prefix) const;

private:
    TraversabilityOptions options_;
    std::unique_ptr<octomap::OcTree> ground_, obstacles_;
    std::unique_ptr<detail::KeyMemory> everObstacle_;
    std::vector<Eigen::Vector3d> path_;
    MapStats stats_;
};

/// Writes the grid as a PNG (one pixel per cell: traversable green, obstacle red, unknown dark
/// grey), the path as a blue polyline with its start marked white. Atomic. Throws
/// std::runtime_error naming the file on failure.
void writeTopDownPng(const std::string& path, const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath);

/// RGB of each class in the PNG.
struct Rgb {
    std::uint8_t r, g, b;
};
Rgb colourOf(CellClass c);

}  // namespace gseg::map
