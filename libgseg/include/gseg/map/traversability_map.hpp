#pragma once
/// \file traversability_map.hpp
/// Traversability OctoMaps built from segmented scans: one occupancy OcTree for the ground, one
/// for the obstacles (free space from ray casting, occupied from hits), a ColorOcTree with both,
/// and a top-down grid (traversable / obstacle / unknown) with the driven path.
///
/// Frame: everything is in one world frame (metres, z up). Callers transform points with the
/// robot pose and the sensor mounting first, and give the sensor's world position as ray origin.

#include <gseg/map/layer_grid.hpp>
#include <gseg/mrpt/picture.hpp>
#include <gseg/point_cloud.hpp>
#include <gseg/traversability_options.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

namespace octomap {
class OcTree;
class ColorOcTree;
}  // namespace octomap

namespace gseg::map {

namespace detail {
class MapTree;     // an OcTree built in sorted order (implementation detail)
class BrickMap;    // the voxels while a drive is integrated (implementation detail)
}

struct ScanUpdate;
class GroundCells;

/// What the top-down grid says about one column of voxels.
enum class CellClass : std::uint8_t { Unknown = 0, Traversable = 1, Obstacle = 2 };

/// Top-down grid: one cell per voxel column, cell (ix, iy) covering world x in
/// [ix * cell, (ix + 1) * cell) and y likewise. Sparse: only cells with data are stored, in tiles
/// of 64 x 64 cells, so memory follows the mapped area, not the extent of the path.
class TopDownGrid {
public:
    explicit TopDownGrid(double cell = 0.2) : cell_(cell) {}
    double cell() const { return cell_; }  ///< [m] cell edge

    std::int64_t cellIndex(double v) const { return std::int64_t(std::floor(v / cell_)); }
    /// Class at world (x, y); Unknown where nothing was seen.
    CellClass at(double x, double y) const { return atCell(cellIndex(x), cellIndex(y)); }
    CellClass atCell(std::int64_t ix, std::int64_t iy) const;
    void set(std::int64_t ix, std::int64_t iy, CellClass c);

    bool empty() const { return !any_; }  ///< no cell was ever set to a known class
    std::size_t count(CellClass c) const;  ///< cells of class c (Traversable or Obstacle)
    /// Cell index ranges of every cell ever set to a known class, inclusive (meaningless when empty()).
    std::int64_t minX() const { return lo_[0]; }
    std::int64_t maxX() const { return hi_[0]; }
    std::int64_t minY() const { return lo_[1]; }
    std::int64_t maxY() const { return hi_[1]; }

    /// Calls f(ix, iy, class) for every cell with data (tile by tile).
    template <class F>
    void forEachCell(F&& f) const {
        for (const auto& [key, tile] : tiles_)
            for (int j = 0; j < kTile; ++j)
                for (int i = 0; i < kTile; ++i) {
                    const CellClass c = tile[std::size_t(j * kTile + i)];
                    if (c != CellClass::Unknown) f(tileX(key) * kTile + i, tileY(key) * kTile + j, c);
                }
    }

    static constexpr int kTile = 64;  ///< [cells] tile edge

private:
    double cell_;
    std::unordered_map<std::uint64_t, std::vector<CellClass>> tiles_;
    std::int64_t lo_[2] = {0, 0}, hi_[2] = {0, 0};
    bool any_ = false;
    std::size_t counts_[3] = {0, 0, 0};  ///< per class; [Unknown] unused
    static std::uint64_t tileKey(std::int64_t tx, std::int64_t ty);
    static std::int64_t tileX(std::uint64_t key);
    static std::int64_t tileY(std::uint64_t key);
};

/// Where the top-down picture puts the grid. The picture follows the convention of gseg's scan
/// pictures: world x up, y to the left (for a kitti2rawlog drive, x is the vehicle's forward
/// direction at the first scan). It frames the cells with data and the driven path, with a margin
/// of 5 cells: a small map is enlarged (pixelsPerCell, about 640 pixels on its longer side), a
/// large one reduced to at most maxSide pixels a side (cellsPerPixel, the most blocking class of
/// the cells a pixel covers wins). Around the map: a title band above, a legend band below.
struct PictureLayout {
    std::int64_t topCell = 0;   ///< cell index along x of the map's first row (x up: rows go to smaller x)
    std::int64_t leftCell = 0;  ///< cell index along y of the map's first column (y left: columns go to smaller y)
    int cellsPerPixel = 1;      ///< > 1: a large map, reduced
    int pixelsPerCell = 1;      ///< > 1: a small map, enlarged
    int mapLeft = 0, mapTop = 0;      ///< [pixels] top-left corner of the map in the picture
    int mapWidth = 0, mapHeight = 0;  ///< [pixels] the map area
    int width = 0, height = 0;        ///< [pixels] the whole picture (0: nothing to draw)
    double cell = 0.2;                ///< [m]
    std::uint64_t cellsWide = 0, cellsHigh = 0;  ///< [cells] the framed area: along y (across), along x (down)

    /// Top-left pixel (in the picture) of the block that shows world (x, y); false outside the map.
    bool toPixel(double x, double y, int& col, int& row) const;
    /// [pixels per metre] of the map area.
    double pixelsPerMetre() const { return double(pixelsPerCell) / (double(cellsPerPixel) * cell); }
};
PictureLayout pictureLayout(const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath, int maxSide = 4096);

/// Figures of a map, voxels counted at the finest resolution.
struct MapStats {
    std::size_t scans = 0;             ///< scans inserted
    std::size_t groundPoints = 0;      ///< ground points given (all scans)
    std::size_t obstaclePoints = 0;    ///< obstacle points given (all scans)
    std::size_t pointsSkipped = 0;     ///< points not used: NaN/infinite or outside the map's extent
    std::size_t rays = 0;              ///< rays cast (one per endpoint voxel and scan)
    std::size_t groundVoxels = 0;      ///< occupied voxels of the ground tree
    std::size_t obstacleVoxels = 0;    ///< occupied voxels of the obstacle tree
    std::size_t freeVoxels = 0;        ///< voxels known free in the obstacle tree
    std::size_t clearedObstacleVoxels = 0;  ///< voxels once occupied as obstacle, free by the end (seen through)
    std::size_t groundUnderObstacle = 0;    ///< occupied in both trees: shown as obstacle
    std::size_t cellsTraversable = 0, cellsObstacle = 0;  ///< top-down grid
    std::size_t cellsUnknown = 0;      ///< cells without data inside the picture's frame
    double pathLength = 0;             ///< [m] length of the sensor path
    std::size_t bricks = 0;            ///< 8 x 8 x 8 voxel bricks holding the maps while integrating
    std::size_t brickValueBlocks = 0;  ///< words of 4 x 4 x 4 voxels with a value each (the others hold one)
    std::size_t mapBytes = 0;          ///< [bytes] memory of the bricks, their index and values
};

/// Builds the maps scan by scan. Per scan, every voxel crossed by a ray (to a ground or an obstacle
/// point) gets a miss in both trees, except voxels holding a hit of that scan; ground hits update
/// the ground tree only, obstacle hits the obstacle tree only. So an obstacle that later scans see
/// through is cleared, and a ground hit never lowers an obstacle voxel (a voxel occupied in both
/// trees counts as obstacle). Misses never lower an occupied ground voxel: rays to distant ground
/// graze the road just before their end and would erode it (ground does not move).
///
/// Every voxel gets exactly the value OctoMap's OcTree::updateNode() calls would give it, and the
/// `.bt` files are byte for byte what OcTree::writeBinaryConst() writes for those trees; while
/// the drive is integrated the voxels are kept in bricks of 8 x 8 x 8 (a brick whose voxels all
/// sit at one clamping bound keeps one value), which makes a scan's update cheap.
class TraversabilityMap {
public:
    /// Throws std::invalid_argument on invalid options.
    explicit TraversabilityMap(const TraversabilityOptions& options = TraversabilityOptions());
    ~TraversabilityMap();
    TraversabilityMap(TraversabilityMap&&) noexcept;
    TraversabilityMap& operator=(TraversabilityMap&&) noexcept;

    const TraversabilityOptions& options() const { return options_; }

    /// Inserts one scan: ground and obstacle points and the sensor origin, all in the world frame
    /// [m]: castScan() then apply(). Throws std::invalid_argument on a NaN/infinite origin and
    /// std::out_of_range on an origin outside the map's extent; NaN points are skipped.
    void insertScan(const PointCloudView& ground, const PointCloudView& obstacles, const Eigen::Vector3d& sensorOrigin);
    /// Applies one scan's update (castScan() with this map's options). Updates must be applied in
    /// scan order; the result depends on nothing else.
    void apply(const ScanUpdate& update);

    bool empty() const { return stats_.scans == 0; }
    /// The maps as OctoMap trees (built when first asked for after a scan; pruned where eight
    /// leaves hold the same clamped value).
    const octomap::OcTree& groundTree() const;
    const octomap::OcTree& obstacleTree() const;
    const std::vector<Eigen::Vector3d>& path() const { return path_; }  ///< sensor origins, in order

    /// Ground and obstacle voxels in one tree: ground green, obstacle red (occupied voxels only;
    /// an empty tree when no voxel is occupied).
    std::unique_ptr<octomap::ColorOcTree> colouredTree() const;
    /// The top-down grid of every occupied voxel column.
    TopDownGrid topDown() const;
    /// Counters and voxel counts (walks both trees).
    MapStats stats() const;
    /// The 2.5D layers (elevation, slope, step, roughness, clearance, class, cost) from the ground
    /// points of every scan and the occupied obstacle voxels (gseg/map/terrain_layers.hpp).
    /// Without any ground point or obstacle: one unknown cell at the first sensor position.
    LayerGrid layers() const;

    /// The files write() writes for `prefix`, in this order.
    static std::vector<std::string> outputPaths(const std::string& prefix);
    /// Writes, all of them or none (temporary files, then renamed; if a rename fails the previous
    /// versions are put back):
    /// - `<prefix>_ground.bt`, `<prefix>_obstacles.bt`: the occupancy OcTrees (liboctomap, octovis);
    /// - `<prefix>_traversability.ot`: ground and obstacle voxels in one ColorOcTree;
    /// - `<prefix>_traversability.png`: the top-down picture (writeTopDownPng());
    /// - `<prefix>_traversability.ply`: the centres of the occupied voxels, coloured, with a
    ///   `label` property (1 ground, 0 obstacle) for CloudCompare and other point-cloud viewers;
    /// - `<prefix>_traversability.3Dscene`: an MRPT scene for SceneViewer3D: the same voxels as
    ///   coloured boxes (COctoMapVoxels), the driven path as a blue line with a blue box at each
    ///   sensor position, axes at its start;
    /// - `<prefix>_costmap.pgm`, `<prefix>_costmap.yaml`: the `class` layer as a ROS map_server
    ///   map (trinary: traversable free, not traversable occupied, the rest unknown; map frame =
    ///   the world frame), what Nav2's map_server and MRPT's loadFromROSMapServerYAML load;
    /// - `<prefix>_layers.tif`: the layers as a GeoTIFF (gseg/map/layer_file.hpp), one named
    ///   float32 band per layer, NaN unknown;
    /// - `<prefix>_layer_<name>.png` for each layer (terrainLayerNames()): its picture
    ///   (gseg/map/layer_picture.hpp).
    /// The same map always gives the same bytes. Throws std::runtime_error naming the file on
    /// failure and std::logic_error if no scan was inserted. Returns the paths written.
    std::vector<std::string> write(const std::string& prefix) const;
    /// The first line of the picture's title: "6 scans, 3.55 m driven".
    std::string pictureTitle() const;

private:
    TraversabilityOptions options_;
    std::unique_ptr<detail::MapTree> configured_;  ///< an empty tree with the options: OctoMap's own log-odds
    std::unique_ptr<detail::BrickMap> voxels_;
    std::unique_ptr<GroundCells> groundCells_;  ///< the ground points of every scan, per cell
    mutable std::unique_ptr<detail::MapTree> groundTree_, obstacleTree_;
    mutable std::unique_ptr<TopDownGrid> topDown_;
    std::vector<Eigen::Vector3d> path_;
    MapStats stats_;
};

/// Writes the picture (pictureLayout(): traversable green, obstacle red, unknown grey, the page
/// around the mapped area darker; the path as a blue line from a white start square to an
/// arrowhead in the direction of travel; title, legend naming every colour, scale bar and the
/// x / y axes) as a PNG, atomically. `title` is the first line (e.g. "6 scans, 3.55 m driven").
/// Throws std::runtime_error naming the file on failure.
void writeTopDownPng(const std::string& path, const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath,
                     const std::string& title = "");
/// The same PNG as bytes.
std::string encodeTopDownPng(const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath,
                             const std::string& title = "");

/// The one colour type of gseg's pictures and files (8-bit RGB, gseg/mrpt/picture.hpp).
using Rgb = gseg::mrpt::Colour;
/// RGB of each class in the PNG (also the voxel colours of the `.ot`, `.ply` and `.3Dscene`).
Rgb colourOf(CellClass c);
/// RGB of the page around the mapped area (darker than Unknown).
Rgb backgroundColour();

}  // namespace gseg::map
