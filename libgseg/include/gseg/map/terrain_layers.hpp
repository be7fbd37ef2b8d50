#pragma once
/// \file terrain_layers.hpp
/// The 2.5D layers of a traversability map and the costmap derived from them.
///
/// Per map cell (x, y at the map resolution, map = world frame, metres, z up), from the ground
/// points of the whole drive (summed per cell and scan: GroundCellSample in scan_update.hpp) and
/// the occupied obstacle voxels at the end of the drive (ray casting has cleared what moved away):
///
/// | layer | unit | meaning |
/// |---|---|---|
/// | `elevation` | m | mean world z of the cell's ground points (cells with >= minGroundPoints) |
/// | `slope` | deg | of the least-squares plane through the ground-point centroids (mean x, y, z) of the cell and its 8 neighbours (>= 3 cells) |
/// | `step` | m | largest height difference between a ground point of the cell and one of a neighbouring cell, up or down (a drop is a step) |
/// | `roughness` | m | standard deviation of the cell's ground point heights |
/// | `clearance` | m | free height above the elevation up to the bottom of the lowest obstacle voxel that lies at least minObstacleHeight above it; +inf where none |
/// | `class` | - | 1 traversable, 2 not traversable, NaN unknown |
/// | `cost` | - | 0-100 (nav_msgs/OccupancyGrid): traversable cells 0-99 (99 x the largest of slope / maxSlope, step / maxStep, roughness / maxRoughness), 100 not traversable, NaN unknown |
/// | `source` | - | where a cell's ground comes from: 0 ground points of the scans, 1 the drive's terrain model (lowest returns several scans agree on, grown from confident ground: gseg/terrain_model.hpp), 2 interpolated across a gap (fillGaps); NaN no ground |
///
/// A cell with an elevation is traversable when slope <= maxSlope, step <= maxStep, roughness <=
/// maxRoughness and clearance >= clearance (TraversabilityOptions). A cell without ground points
/// but with obstacle voxels is not traversable when one of them lies between minObstacleHeight and
/// clearance above its reference ground (the median elevation of the cells within 1 m, or else the
/// bottom of its lowest obstacle voxel); else it stays unknown.
///
/// With the drive's terrain model (driveTerrain, built from every scan's TerrainSample list), a cell
/// without enough ground points whose ground the model grew takes the model's elevation (`source`
/// 1; roughness 0, the step from that elevation) and is judged by the same rules; it is traversable
/// only where a ray also crossed the voxels from minObstacleHeight to minObstacleHeight + two
/// voxels above that ground and left them free (ground seen only through a low slot, under a car's
/// body or a ledge whose top no ray reached, stays unknown). With fillGaps, an
/// unknown cell that lies on a straight line (along x, y or a diagonal) between two traversable
/// cells at most maxGapWidth apart (TraversabilityOptions::gapWidth()) becomes traversable (`source`
/// 2, elevation interpolated, cost from the interpolated slope, clearance infinite) where the two
/// ends differ by at most maxStep and maxSlope, no obstacle voxel of the column reaches (its top)
/// higher than minObstacleHeight above that ground (at any height: a column that returned a tree's
/// crown or a bush's top is not a gap, its ground was hidden), a ray of the drive crossed the column between
/// the interpolated ground and the clearance, and no ray crossed it more than maxStep below that
/// ground (a ditch or a drop: rays went into it). The first known cell along a line ends the search
/// (an obstacle between is never crossed).

#include <gseg/io/ros_map.hpp>
#include <gseg/map/column_class.hpp>
#include <gseg/map/layer_grid.hpp>
#include <gseg/map/layer_tiles.hpp>
#include <gseg/map/scan_update.hpp>
#include <gseg/terrain_model.hpp>
#include <gseg/traversability_options.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

namespace gseg::map {

/// The ground points of the drive per cell: sums, so memory follows the mapped area.
struct GroundCellSums {
    std::uint64_t count = 0;
    double sumZ = 0, sumZ2 = 0;  ///< [m], [m^2]
    double sumX = 0, sumY = 0;   ///< [m]
    float minZ = 0, maxZ = 0;    ///< [m]
};

/// Accumulates the GroundCellSample lists of the scans, in scan order, in tiles of 16 x 16 cells
/// allocated where ground was seen (a scan's samples, sorted by cell, fall in runs of one tile).
class GroundCells {
public:
    GroundCells();
    ~GroundCells();

    void add(const std::vector<GroundCellSample>& samples);
    /// Calls f(cell, sums) for every cell with ground points (cell: the column key of
    /// GroundCellSample::cell), in no particular order.
    void forEach(const std::function<void(std::uint32_t, const GroundCellSums&)>& f) const;

private:
    struct Tile;
    std::unordered_map<std::uint32_t, std::unique_ptr<Tile>> tiles_;  ///< by the cell key's x and y >> 4
};

/// The z [m] of the centres of the occupied obstacle voxels of each column (by column key).
using ObstacleColumns = std::unordered_map<std::uint32_t, std::vector<float>>;

/// The names of the layers, in the order of the table above (and of the GeoTIFF's bands).
const std::vector<std::string>& terrainLayerNames();

/// Whether a ray of the drive crossed column `column` (OctoMap column key, as GroundCellSample::cell)
/// in a voxel whose centre lies in [zLow, zHigh] [m] and left it free.
using RayFreeQuery = std::function<bool(std::uint32_t column, float zLow, float zHigh)>;

/// The layers of the table above, in sparse tiles (gseg/map/layer_tiles.hpp) where a cell has
/// ground points, obstacle voxels, modelled ground or a filled gap; the box (LayerTiles::setBox())
/// is the bounding box of every cell with ground points, obstacle voxels or modelled ground, and
/// without any, one unknown cell holding map position (emptyX, emptyY) [m]. Memory follows the
/// tiles, not the box (#35). `terrain`: the drive's terrain model, built (TerrainModel::build()) at
/// the map's resolution, or nullptr; `rayFree`: the rays' free space (gap filling needs it; without
/// it no gap is filled).
LayerTiles terrainLayerTiles(const GroundCells& ground, const ObstacleColumns& obstacles, const TraversabilityOptions& options,
                             double emptyX = 0, double emptyY = 0, const gseg::TerrainModel* terrain = nullptr,
                             const RayFreeQuery& rayFree = RayFreeQuery());

/// terrainLayerTiles() as one dense grid over its box (LayerTiles::dense(): throws
/// std::length_error on a box too big for one grid).
LayerGrid terrainLayers(const GroundCells& ground, const ObstacleColumns& obstacles, const TraversabilityOptions& options,
                        double emptyX = 0, double emptyY = 0, const gseg::TerrainModel* terrain = nullptr,
                        const RayFreeQuery& rayFree = RayFreeQuery());

/// The costmap of a `class` layer in map_server's trinary form: traversable free, not traversable
/// occupied, the rest unknown; the same cells, resolution and origin.
gseg::io::RosMap costmapOf(const LayerGrid& layers);

}  // namespace gseg::map
