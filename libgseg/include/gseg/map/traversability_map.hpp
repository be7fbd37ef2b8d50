#pragma once
/// \file traversability_map.hpp
/// Traversability OctoMaps built from segmented scans: one occupancy OcTree for the ground, one
/// for the obstacles (free space from ray casting, occupied from hits), a ColorOcTree with both,
/// and a top-down grid (traversable / obstacle / unknown, gseg/map/top_down_grid.hpp) with the
/// driven path (its picture: gseg/map/top_down_picture.hpp).
///
/// Frame: everything is in one world frame (metres, z up). Callers transform points with the
/// robot pose and the sensor mounting first, and give the sensor's world position as ray origin.

#include <gseg/map/layer_grid.hpp>
#include <gseg/map/layer_tiles.hpp>
#include <gseg/map/map_stats.hpp>
#include <gseg/map/top_down_grid.hpp>
#include <gseg/point_cloud.hpp>
#include <gseg/traversability_options.hpp>

#include <Eigen/Core>

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
class MapTree;     // an OcTree built in sorted order (implementation detail)
class BrickMap;    // the voxels while a drive is integrated (implementation detail)
}

struct ScanUpdate;
class GroundCells;

/// The process (of `ranks`, from 0) that holds a voxel (an OctoMap Morton code at the map's
/// resolution) when the voxels are shared (TraversabilityMap::shareVoxels()): by its 8 x 8 x 8
/// brick, a checkerboard of 2 x 2 bricks dealt round robin (processes 4 and up hold none).
int voxelOwner(std::uint64_t code, int ranks);
constexpr int kVoxelHolders = 4;  ///< processes that can hold voxels (voxelOwner() < 4)
/// The voxels of `u` that `rank` holds, taken out of it: their free, groundHits and obstacleHits
/// (sorted, as in `u`) with u's origin, the other fields empty (what that process applies). They
/// leave u.free and u.groundHits; u.obstacleHits stays whole (the memory guard reads it; a map
/// holding other voxels skips them).
ScanUpdate takeVoxels(ScanUpdate& u, int rank, int ranks);
}  // namespace gseg::map
namespace gseg {
class TerrainModel;
}
namespace gseg::map {

/// How TraversabilityMap::write() lays out the costmap and the layers' GeoTIFF (#35): a map whose
/// box is at most `tiledAbove` cells a side gets the files of a small map (one costmap PGM + YAML,
/// one GeoTIFF, pictures of every cell); a bigger one, or any with `tiles`, the costmap as tiles,
/// the layers as one Cloud-Optimized GeoTIFF with overviews, pictures of an overview.
struct MapOutputOptions {
    bool tiles = false;      ///< always write tiles (rawlog-octomap --tiles)
    int tiledAbove = 4096;   ///< [cells] write tiles when the map's box is wider or higher than this (--tiled-above), >= 1
    int costmapTile = 1024;  ///< [cells] edge of a costmap tile, 64 to 16384
    int pictureSide = 2048;  ///< [cells] a tiled map's pictures show an overview at most this many cells a side, >= 16
    /// Threads that write: 1, one file at a time; 2, a second thread builds the layers while the
    /// voxel maps, the top-down picture and the point cloud are written, then writes the costmap,
    /// the GeoTIFF and the layer pictures while the scene is (the same bytes; the memory estimate
    /// counts a picture being encoded beside the other files), 1 or 2.
    int writers = 1;
    /// Throws std::invalid_argument naming the field of a value out of its range.
    void validate() const;
    /// Whether a map of this box gets tiles.
    bool tiled(std::int64_t boxWidth, std::int64_t boxHeight) const { return tiles || boxWidth > tiledAbove || boxHeight > tiledAbove; }
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
    /// Threads apply() may use for the voxels (default 1): the maps are the same for any number.
    void setUpdateThreads(unsigned threads);

    /// The voxels shared by `ranks` processes (#35): this map holds those of `rank`
    /// (voxelOwner()) and apply() leaves the others alone; each process applies every scan's
    /// update (or its takeVoxels() part) in scan order, so every voxel sees what it would in one map.
    /// Before writing, the others' voxelBytes() are merged with mergeVoxels(). Default (0, 1):
    /// every voxel. Throws std::invalid_argument unless 0 <= rank < ranks.
    void shareVoxels(int rank, int ranks);
    /// The voxels this map holds, as bytes for mergeVoxels() in another process.
    std::string voxelBytes() const;
    /// Adds another process's voxelBytes() (voxels of other owners) to this map: then it holds
    /// both. Throws std::runtime_error on malformed bytes or a voxel held by both.
    void mergeVoxels(const std::string& bytes);

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
    /// Counters and voxel counts (walks both trees), and the costmap's cells (the layers are
    /// computed for them unless write() has already counted them for this many scans).
    MapStats stats() const;
    /// The 2.5D layers (elevation, slope, step, roughness, clearance, class, cost) from the ground
    /// points of every scan and the occupied obstacle voxels (gseg/map/terrain_layers.hpp), in
    /// sparse tiles: memory follows the ground seen. Without any ground point or obstacle: one
    /// unknown cell at the first sensor position.
    LayerTiles layerTiles() const;
    /// layerTiles() as one dense grid over its box; throws std::length_error where the box is
    /// too big for one (LayerTiles::dense()).
    LayerGrid layers() const;

    /// The files write() writes for `prefix` for a map of a small box (not tiled), in this order. Throws std::invalid_argument for a
    /// prefix io::checkOutputPrefix() refuses (empty, "out/", a folder, /dev/null).
    static std::vector<std::string> outputPaths(const std::string& prefix);
    /// The files that must not exist before a write() without overwrite: outputPaths() and the
    /// tiles' metadata (a tiled map's tiles, whose names depend on the map, come with it), for the
    /// up-front check of io::checkOutputs().
    static std::vector<std::string> pathsToCheck(const std::string& prefix);
    /// Writes, all of them or none (temporary files, then renamed; if a rename fails the previous
    /// versions are put back):
    /// - `<prefix>_ground.bt`, `<prefix>_obstacles.bt`: the occupancy OcTrees (liboctomap, octovis);
    /// - `<prefix>_traversability.ot`: ground and obstacle voxels in one ColorOcTree;
    /// - `<prefix>_traversability.png`: the top-down picture (encodeTopDownPng());
    /// - `<prefix>_traversability.ply`: the centres of the occupied voxels, coloured, with a
    ///   class scalar field `scalar_class` (1 ground, 2 obstacle; CloudCompare's "class") and a
    ///   `label` property (1 ground, 0 obstacle) for other programs (gseg/io/ply.hpp);
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
    /// A map with tiles (MapOutputOptions::tiled()) gets, instead of the costmap's PGM and YAML
    /// and the one GeoTIFF:
    /// - `<prefix>_costmap_metadata.yaml`: the tiles in the layout of Autoware's divided maps
    ///   (`x_resolution`, `y_resolution`: the tile edge [m]; then each tile's YAML file name with
    ///   the map-frame origin [m] of its lower-left corner: `PREFIX_costmap_3_-2.yaml: [614.4, -409.6]`);
    /// - `<prefix>_costmap_<x>_<y>.pgm` and `.yaml`: tile (x, y) (cells x * costmapTile ... along
    ///   x, likewise y), a ROS map_server map of costmapTile x costmapTile cells, for every tile
    ///   with a known cell;
    /// - `<prefix>_layers.tif`: one Cloud-Optimized GeoTIFF with overviews (encodeLayersCog());
    /// and the layer pictures and the scene's elevation mesh drawn from an overview of at most
    /// pictureSide cells a side (LayerTiles::overview()).
    /// The same map always gives the same bytes. Throws std::runtime_error naming the file on
    /// failure and std::logic_error if no scan was inserted. Returns the paths written.
    std::vector<std::string> write(const std::string& prefix, const MapOutputOptions& how = MapOutputOptions()) const;
    /// The first line of the picture's title: "6 scans, 3.55 m driven".
    std::string pictureTitle() const;

private:
    TraversabilityOptions options_;
    std::unique_ptr<detail::MapTree> configured_;  ///< an empty tree with the options: OctoMap's own log-odds
    std::unique_ptr<detail::BrickMap> voxels_;
    std::unique_ptr<GroundCells> groundCells_;  ///< the ground points of every scan, per cell
    std::unique_ptr<gseg::TerrainModel> terrain_;  ///< the drive's terrain model (driveTerrain), built when the layers are
    mutable std::unique_ptr<detail::MapTree> groundTree_, obstacleTree_;
    mutable std::unique_ptr<TopDownGrid> topDown_;
    /// The costmap's free, occupied and unknown cells, as of `costmapScans_` scans (write()
    /// counts them as it writes the PGM; stats() when asked before).
    mutable std::size_t costmapCells_[3] = {0, 0, 0};
    mutable std::size_t costmapScans_ = 0;
    std::vector<Eigen::Vector3d> path_;
    MapStats stats_;
};

}  // namespace gseg::map
