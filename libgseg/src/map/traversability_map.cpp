#include <gseg/map/traversability_map.hpp>

#include <gseg/io/ply.hpp>
#include <gseg/io/atomic_file.hpp>
#include <gseg/io/output_checks.hpp>
#include <gseg/map/scan_update.hpp>
#include <gseg/map/layer_file.hpp>
#include <gseg/map/layer_picture.hpp>
#include <gseg/map/map_colours.hpp>
#include <gseg/map/terrain_layers.hpp>
#include <gseg/map/top_down_picture.hpp>
#include <gseg/mrpt/scene.hpp>

#include "brick_map.hpp"
#include "map_scene.hpp"
#include "map_tree.hpp"
#include "voxel_keys.hpp"

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>


#include <algorithm>
#include <cmath>
#include <future>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace gseg::map {

namespace {

std::unique_ptr<detail::MapTree> makeTree(const TraversabilityOptions& o) {
    auto t = std::make_unique<detail::MapTree>(o.resolution);
    t->setProbHit(o.probHit);
    t->setProbMiss(o.probMiss);
    t->setClampingThresMin(o.clampMin);
    t->setClampingThresMax(o.clampMax);
    t->setOccupancyThres(o.occupancyThreshold);
    return t;
}

/// Lowest ground and obstacle voxel of a column, for the top-down grid.
struct Column {
    float minGround = std::numeric_limits<float>::infinity();
    float minObstacle = std::numeric_limits<float>::infinity();
};

using detail::kGround;
using detail::kObstacles;

/// The occupied voxels as every output shows them, each once (obstacles first, then ground): the
/// rule "a voxel occupied in both maps is an obstacle" (ground never lowers an obstacle voxel).
template <class F>
void forEachShownVoxel(const detail::BrickMap& voxels, float occupied, F&& f) {
    voxels.forEachVoxel(kObstacles, [&](std::uint64_t code, float value) {
        if (value >= occupied) f(code, ColumnClass::Obstacle);
    });
    voxels.forEachVoxel(kGround, [&](std::uint64_t code, float value) {
        if (value >= occupied && !voxels.occupied(kObstacles, code)) f(code, ColumnClass::Traversable);
    });
}

/// The occupied voxels of the map as they are shown (.ply, .3Dscene): centres [m] and labels (1
/// ground, 0 obstacle; forEachShownVoxel()), in Morton-code order.
struct OccupiedVoxels {
    std::vector<float> xyz;
    std::vector<std::uint8_t> labels;
    std::size_t groundUnderObstacles = 0;  ///< occupied ground voxels shown as obstacles (the rule above)
};

OccupiedVoxels occupiedVoxels(const detail::BrickMap& voxels, const detail::MapTree& configured) {
    std::vector<std::pair<std::uint64_t, std::uint8_t>> codes;
    forEachShownVoxel(voxels, configured.getOccupancyThresLog(), [&](std::uint64_t code, ColumnClass c) {
        codes.emplace_back(code, c == ColumnClass::Traversable ? 1 : 0);
    });
    std::sort(codes.begin(), codes.end());  // the files must not depend on the order the bricks were made in
    OccupiedVoxels v;
    voxels.forEachVoxel(kGround, [&](std::uint64_t code, float g) {
        v.groundUnderObstacles += g >= configured.getOccupancyThresLog() && voxels.occupied(kObstacles, code);
    });
    v.xyz.reserve(3 * codes.size());
    v.labels.reserve(codes.size());
    for (const auto& [code, label] : codes) {
        const octomap::point3d c = configured.keyToCoord(detail::keyOfCode(code));
        v.xyz.insert(v.xyz.end(), {c.x(), c.y(), c.z()});
        v.labels.push_back(label);
    }
    return v;
}

std::string mapPlyBytes(const OccupiedVoxels& v, double resolution) {
    gseg::io::PlyColours colours;
    auto set = [](std::uint8_t* rgb, Rgb c) { rgb[0] = c.r, rgb[1] = c.g, rgb[2] = c.b; };
    set(colours.ground, colourOf(ColumnClass::Traversable));
    set(colours.nonGround, colourOf(ColumnClass::Obstacle));
    gseg::io::PlyOptions options;
    char comment[128];
    std::snprintf(comment, sizeof comment, "gseg traversability map: centres of the occupied %.2f m voxels", resolution);
    options.comment = comment;
    options.nonGroundName = "obstacle";
    return gseg::io::labelledPlyBytes(PointCloudView(v.xyz.data(), v.labels.size()), v.labels, colours, options);
}

/// The free, occupied and unknown cells of the costmap over the box of `tiles` (costmapOf(): the
/// class layer's traversable free, not traversable occupied, the rest unknown).
void countCostmapCells(const LayerTiles& tiles, std::size_t (&cells)[3]) {
    cells[0] = cells[1] = 0;
    const std::size_t cls = tiles.layerIndex("class");
    const std::int64_t n = LayerTiles::kTile;
    for (const auto& [tx, ty] : tiles.tileList())
        for (std::int64_t iy = std::max(ty * n, tiles.minY()); iy < std::min((ty + 1) * n, tiles.maxY() + 1); ++iy)
            for (std::int64_t ix = std::max(tx * n, tiles.minX()); ix < std::min((tx + 1) * n, tiles.maxX() + 1); ++ix) {
                const float c = tiles.get(cls, ix, iy);
                cells[0] += c == float(ColumnClass::Traversable);
                cells[1] += c == float(ColumnClass::Obstacle);
            }
    cells[2] = std::size_t(tiles.boxWidth() * tiles.boxHeight()) - cells[0] - cells[1];
}

/// The costmap tiles (x, y) of `edge` cells that hold a known cell, sorted by y then x.
std::vector<std::pair<std::int64_t, std::int64_t>> costmapTiles(const LayerTiles& tiles, int edge) {
    std::vector<std::pair<std::int64_t, std::int64_t>> list;
    const std::size_t cls = tiles.layerIndex("class");
    const std::int64_t n = LayerTiles::kTile;
    for (const auto& [tx, ty] : tiles.tileList())
        for (std::int64_t iy = ty * n; iy < (ty + 1) * n; ++iy)
            for (std::int64_t ix = tx * n; ix < (tx + 1) * n; ++ix)
                if (!std::isnan(tiles.get(cls, ix, iy))) list.emplace_back(LayerTiles::floorDiv(iy, edge), LayerTiles::floorDiv(ix, edge));
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    for (auto& p : list) std::swap(p.first, p.second);
    return list;
}

/// "PREFIX_costmap_3_-2" for tile (3, -2).
std::string costmapTileStem(const std::string& prefix, std::int64_t x, std::int64_t y) {
    return prefix + "_costmap_" + std::to_string(x) + "_" + std::to_string(y);
}

std::string fileName(const std::string& path) {
    const std::size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? path : path.substr(slash + 1);
}

/// The tiles' metadata in the layout of Autoware's divided maps (traversability_map.hpp).
std::string costmapMetadata(const std::string& prefix, const std::vector<std::pair<std::int64_t, std::int64_t>>& list, int edge,
                            double res) {
    std::string text = "# gseg costmap tiles (the layout of Autoware's divided maps): each tile's map_server YAML and the\n"
                       "# map-frame origin [m] of its lower-left corner; a tile covers x_resolution x y_resolution metres\n";
    char line[256];
    std::snprintf(line, sizeof line, "# %d x %d cells of %.12g m each; tiles not listed are unknown\n", edge, edge, res);
    text += line;
    std::snprintf(line, sizeof line, "x_resolution: %.12g\ny_resolution: %.12g\n", edge * res, edge * res);
    text += line;
    for (const auto& [x, y] : list) {
        std::snprintf(line, sizeof line, ": [%.12g, %.12g]\n", double(x * edge) * res, double(y * edge) * res);
        text += fileName(costmapTileStem(prefix, x, y)) + ".yaml" + line;
    }
    return text;
}

/// A costmap's PGM and YAML (files `pgm` and `pgm + 1`; the YAML names the PGM by its file name).
void writeCostmap(gseg::io::AtomicFileSet& files, std::size_t pgm, const gseg::io::RosMap& map) {
    const std::string bytes = gseg::io::encodePgm(map);
    files[pgm].write(bytes.data(), bytes.size());
    const std::string yaml = gseg::io::encodeRosMapYaml(map, fileName(files.paths()[pgm]));
    files[pgm + 1].write(yaml.data(), yaml.size());
}

}  // namespace

TraversabilityMap::TraversabilityMap(const TraversabilityOptions& options)
    : options_(options) {
    options_.validate();
    configured_ = makeTree(options_);
    detail::LogOdds l;
    l.hit = configured_->getProbHitLog(), l.miss = configured_->getProbMissLog();
    l.clampMin = configured_->getClampingThresMinLog(), l.clampMax = configured_->getClampingThresMaxLog();
    l.occupied = configured_->getOccupancyThresLog();
    voxels_ = std::make_unique<detail::BrickMap>(l);
    groundCells_ = std::make_unique<GroundCells>();
    terrain_ = std::make_unique<gseg::TerrainModel>(options_.terrainOptions());
}

TraversabilityMap::~TraversabilityMap() = default;
TraversabilityMap::TraversabilityMap(TraversabilityMap&&) noexcept = default;
TraversabilityMap& TraversabilityMap::operator=(TraversabilityMap&&) noexcept = default;

const octomap::OcTree& TraversabilityMap::groundTree() const {
    if (!groundTree_) groundTree_ = voxels_->toTree(kGround, *configured_);
    return *groundTree_;
}

const octomap::OcTree& TraversabilityMap::obstacleTree() const {
    if (!obstacleTree_) obstacleTree_ = voxels_->toTree(kObstacles, *configured_);
    return *obstacleTree_;
}

void TraversabilityMap::insertScan(const PointCloudView& ground, const PointCloudView& obstacles,
                                   const Eigen::Vector3d& sensorOrigin) {
    apply(castScan(ground, obstacles, sensorOrigin, options_));
}

void TraversabilityMap::apply(const ScanUpdate& u) {
    if (!u.origin.allFinite()) throw std::invalid_argument("TraversabilityMap::apply: sensor origin is not finite");
    // Hits of a scan are never in its `free` list, so the order within a scan does not matter;
    // ground does not move, so misses never lower an occupied ground voxel (rays to distant
    // ground graze the road near their end and would erode it scan after scan).
    voxels_->applyScan(u.free, u.groundHits, u.obstacleHits);
    groundCells_->add(u.groundCells);
    if (options_.driveTerrain) terrain_->add(u.terrain);
    groundTree_.reset(), obstacleTree_.reset(), topDown_.reset();
    if (!path_.empty()) stats_.pathLength += (u.origin - path_.back()).norm();
    path_.push_back(u.origin);
    ++stats_.scans;
    stats_.groundPoints += u.groundPoints;
    stats_.obstaclePoints += u.obstaclePoints;
    stats_.pointsSkipped += u.pointsSkipped;
    stats_.rays += u.rays;
}

void TraversabilityMap::setUpdateThreads(unsigned threads) { voxels_->setThreads(threads); }

int voxelOwner(std::uint64_t code, int ranks) { return int(detail::BrickMap::shardOfVoxel(code) % unsigned(std::max(1, ranks))); }

ScanUpdate takeVoxels(ScanUpdate& u, int rank, int ranks) {
    ScanUpdate part;
    part.origin = u.origin;
    bool mine[4];  // by shard
    for (unsigned s = 0; s < 4; ++s) mine[s] = voxelOwner(std::uint64_t(s) << 9, ranks) == rank;
    auto take = [&](std::vector<std::uint64_t>& from, std::vector<std::uint64_t>& to, bool leave) {
        std::size_t kept = 0;
        for (std::uint64_t code : from) {
            if (mine[(code >> 9) & 3]) to.push_back(code);
            if (leave || !mine[(code >> 9) & 3]) from[kept++] = code;
        }
        from.resize(kept);
    };
    {  // the free bricks
        std::size_t kept = 0;
        for (std::size_t b = 0; b < u.free.bricks.size(); ++b) {
            const std::uint64_t* words = &u.free.words[8 * b];
            if (mine[u.free.bricks[b] & 3]) {
                part.free.bricks.push_back(u.free.bricks[b]);
                part.free.words.insert(part.free.words.end(), words, words + 8);
            } else {
                u.free.bricks[kept] = u.free.bricks[b];
                std::copy(words, words + 8, u.free.words.begin() + std::ptrdiff_t(8 * kept));
                ++kept;
            }
        }
        u.free.bricks.resize(kept), u.free.words.resize(8 * kept);
    }
    take(u.groundHits, part.groundHits, false);
    take(u.obstacleHits, part.obstacleHits, true);
    return part;
}

void TraversabilityMap::shareVoxels(int rank, int ranks) {
    if (ranks < 1 || rank < 0 || rank >= ranks)
        throw std::invalid_argument("TraversabilityMap::shareVoxels: rank " + std::to_string(rank) + " of " + std::to_string(ranks));
    unsigned mask = 0;
    for (unsigned s = 0; s < detail::BrickMap::shards(); ++s)
        if (int(s % unsigned(ranks)) == rank) mask |= 1u << s;
    voxels_->setOwnedShards(mask);
}

std::string TraversabilityMap::voxelBytes() const { return voxels_->encode(); }

void TraversabilityMap::mergeVoxels(const std::string& bytes) {
    voxels_->merge(bytes);
    groundTree_.reset(), obstacleTree_.reset(), topDown_.reset();
    costmapScans_ = 0;
}

std::unique_ptr<octomap::ColorOcTree> TraversabilityMap::colouredTree() const {
    auto tree = std::make_unique<octomap::ColorOcTree>(options_.resolution);
    tree->setOccupancyThres(options_.occupancyThreshold);
    auto add = [&](std::uint64_t code, Rgb c) {
        const octomap::OcTreeKey key = detail::keyOfCode(code);
        tree->updateNode(key, true, true);
        tree->setNodeColor(key, c.r, c.g, c.b);
    };
    forEachShownVoxel(*voxels_, configured_->getOccupancyThresLog(), [&](std::uint64_t code, ColumnClass c) { add(code, colourOf(c)); });
    if (tree->size() > 0) tree->updateInnerOccupancy();  // ColorOcTree's crashes on an empty tree
    return tree;
}

TopDownGrid TraversabilityMap::topDown() const {
    if (topDown_) return *topDown_;
    std::unordered_map<std::uint64_t, Column> columns;
    const float occupied = configured_->getOccupancyThresLog();
    auto lowest = [&](detail::MapIndex m, float Column::*field) {
        voxels_->forEachVoxel(m, [&](std::uint64_t code, float v) {
            if (v < occupied) return;
            const octomap::OcTreeKey k = detail::keyOfCode(code);
            const std::int64_t ix = std::int64_t(k[0]) - 32768, iy = std::int64_t(k[1]) - 32768;
            float& z = columns[detail::pairKey(ix, iy)].*field;
            z = std::min(z, float(configured_->keyToCoord(k[2])));
        });
    };
    lowest(kGround, &Column::minGround);
    lowest(kObstacles, &Column::minObstacle);
    TopDownGrid g(options_.resolution);
    for (const auto& [key, c] : columns) {
        const auto [ix, iy] = detail::splitPairKey(key);
        const bool hasGround = std::isfinite(c.minGround);
        const float reference = hasGround ? c.minGround : c.minObstacle;
        const bool blocked = c.minObstacle <= reference + float(options_.clearance);
        g.set(ix, iy, blocked ? ColumnClass::Obstacle : ColumnClass::Traversable);
    }
    topDown_ = std::make_unique<TopDownGrid>(g);
    return g;
}

MapStats TraversabilityMap::stats() const {
    MapStats s = stats_;
    s.groundVoxels = voxels_->count(kGround, true);
    s.obstacleVoxels = voxels_->count(kObstacles, true);
    s.freeVoxels = voxels_->count(kObstacles, false);
    s.clearedObstacleVoxels = voxels_->clearedObstacles();
    const float occupied = configured_->getOccupancyThresLog();
    voxels_->forEachVoxel(kGround, [&](std::uint64_t code, float g) {
        s.groundUnderObstacle += g >= occupied && voxels_->occupied(kObstacles, code);
    });
    s.bricks = voxels_->bricks();
    s.brickValueBlocks = voxels_->blocksInUse();
    s.mapBytes = voxels_->bytes();
    const TopDownGrid g = topDown();
    s.cellsTraversable = g.count(ColumnClass::Traversable);
    s.cellsObstacle = g.count(ColumnClass::Obstacle);
    const PictureLayout layout = pictureLayout(g, path_);
    s.cellsUnknown = std::size_t(layout.cellsWide * layout.cellsHigh) - s.cellsTraversable - s.cellsObstacle;
    if (costmapScans_ != stats_.scans && !empty()) {
        countCostmapCells(layerTiles(), costmapCells_);
        costmapScans_ = stats_.scans;
    }
    s.costmapFree = costmapCells_[0], s.costmapOccupied = costmapCells_[1], s.costmapUnknown = costmapCells_[2];
    return s;
}

LayerGrid TraversabilityMap::layers() const { return layerTiles().dense(); }

LayerTiles TraversabilityMap::layerTiles() const {
    ObstacleColumns columns;
    const float occupied = configured_->getOccupancyThresLog();
    const double p = options_.obstacleClearProbability;
    const float cleared = float(std::log(p / (1 - p)));  // a voxel once hit is an obstacle above this log-odds
    auto add = [&](std::uint64_t code) {
        const octomap::OcTreeKey k = detail::keyOfCode(code);
        columns[(std::uint32_t(k[0]) << 16) | k[1]].push_back(float(configured_->keyToCoord(k[2])));
    };
    // Only obstacle hits raise an obstacle voxel, so every occupied one was hit at least once.
    voxels_->forEachEverObstacle([&](std::uint64_t code, float v) {
        if (v > cleared || v >= occupied) add(code);
    });
    const Eigen::Vector3d first = path_.empty() ? Eigen::Vector3d::Zero() : path_.front();
    if (options_.driveTerrain) terrain_->build();
    // Gap filling asks whether a ray crossed a column between two heights and left a voxel free.
    const float occupiedLog = occupied;
    auto rayFree = [&](std::uint32_t column, float zLow, float zHigh) {
        octomap::OcTreeKey key;
        key[0] = std::uint16_t(column >> 16), key[1] = std::uint16_t(column & 0xffffu);
        octomap::OcTreeKey lowKey, highKey;
        if (!configured_->coordToKeyChecked(0.0, 0.0, double(zLow), lowKey)) return false;
        if (!configured_->coordToKeyChecked(0.0, 0.0, double(zHigh), highKey)) return false;
        for (unsigned kz = lowKey[2]; kz <= highKey[2]; ++kz) {
            key[2] = std::uint16_t(kz);
            float v = 0;
            if (voxels_->value(detail::kObstacles, detail::mortonCode(key), v) && v < occupiedLog) return true;
        }
        return false;
    };
    return terrainLayerTiles(*groundCells_, columns, options_, first.x(), first.y(), options_.driveTerrain ? terrain_.get() : nullptr,
                         rayFree);
}

std::vector<std::string> TraversabilityMap::outputPaths(const std::string& prefix) {
    gseg::io::checkOutputPrefix(prefix);  // not empty, not "out/", not /dev/null
    std::vector<std::string> paths{prefix + "_ground.bt",          prefix + "_obstacles.bt",       prefix + "_traversability.ot",
            prefix + "_traversability.png", prefix + "_traversability.ply", prefix + "_traversability.3Dscene",
            prefix + "_costmap.pgm",        prefix + "_costmap.yaml"};
    paths.push_back(prefix + "_layers.tif");
    for (const std::string& name : terrainLayerNames()) paths.push_back(prefix + "_layer_" + name + ".png");
    return paths;
}

std::vector<std::string> TraversabilityMap::pathsToCheck(const std::string& prefix) {
    std::vector<std::string> paths = outputPaths(prefix);
    paths.push_back(prefix + "_costmap_metadata.yaml");
    return paths;
}

std::string TraversabilityMap::pictureTitle() const {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%zu scan%s, %.2f m driven", stats_.scans, stats_.scans == 1 ? "" : "s", stats_.pathLength);
    return buf;
}

void MapOutputOptions::validate() const {
    if (tiledAbove < 1) throw std::invalid_argument("map outputs: tiledAbove must be at least 1 cell");
    if (costmapTile < 64 || costmapTile > 16384) throw std::invalid_argument("map outputs: costmapTile must be 64 to 16384 cells");
    if (pictureSide < 16) throw std::invalid_argument("map outputs: pictureSide must be at least 16 cells");
    if (writers < 1 || writers > 2) throw std::invalid_argument("map outputs: writers must be 1 or 2");
}

std::vector<std::string> TraversabilityMap::write(const std::string& prefix, const MapOutputOptions& how) const {
    if (empty()) throw std::logic_error("TraversabilityMap::write: no scan was inserted");
    how.validate();
    // The files: the voxel maps and pictures (0-5), the costmap (one PGM + YAML, or the tiles'
    // metadata and a PGM + YAML per tile), the layers' GeoTIFF, the layer pictures. Each is
    // written straight to its temporary, in this order, with the same bytes whatever `writers`.
    //
    // With two writers, a second thread builds the layers (the drive's terrain model and gap
    // filling: seconds on a long drive) while this one writes the voxel maps, the top-down
    // picture and the point cloud, which do not need them; then the second thread writes the
    // costmap and the GeoTIFF and encodes the layer pictures while this one writes the scene.
    // They share only what neither changes (the voxels, the layers once built).
    const bool second = how.writers >= 2;
    std::future<LayerTiles> tilesBuilt =
        std::async(second ? std::launch::async : std::launch::deferred, [this] { return layerTiles(); });
    std::vector<std::string> paths = outputPaths(prefix);
    gseg::io::AtomicFileSet files({paths.begin(), paths.begin() + 6});
    const double res = configured_->getResolution();
    {
        const std::string topDownPng = encodeTopDownPng(topDown(), path_, pictureTitle());
        files[0].write([&](std::ostream& out) { voxels_->writeBinary(kGround, out, res); });
        files[1].write([&](std::ostream& out) { voxels_->writeBinary(kObstacles, out, res); });
        files[2].write([&](std::ostream& out) {
            const octomap::ColorOcTree defaults(res);  // colouredTree() leaves the hit probability as it is
            const Rgb g = colourOf(ColumnClass::Traversable), o = colourOf(ColumnClass::Obstacle);
            const std::uint8_t ground[3] = {g.r, g.g, g.b}, obstacle[3] = {o.r, o.g, o.b};
            voxels_->writeColoured(out, res, defaults.getProbHitLog(), ground, obstacle);
        });
        files[3].write(topDownPng.data(), topDownPng.size());
    }
    const OccupiedVoxels v = occupiedVoxels(*voxels_, *configured_);
    {
        const std::string ply = mapPlyBytes(v, res);
        files[4].write(ply.data(), ply.size());
    }
    const LayerTiles tiles = tilesBuilt.get();
    const bool tiled = how.tiled(tiles.boxWidth(), tiles.boxHeight());
    std::vector<std::pair<std::int64_t, std::int64_t>> costTiles;
    if (tiled) {
        costTiles = costmapTiles(tiles, how.costmapTile);
        std::vector<std::string> costmap{prefix + "_costmap_metadata.yaml"};
        for (const auto& [x, y] : costTiles) {
            costmap.push_back(costmapTileStem(prefix, x, y) + ".pgm");
            costmap.push_back(costmapTileStem(prefix, x, y) + ".yaml");
        }
        paths.erase(paths.begin() + 6, paths.begin() + 8);
        paths.insert(paths.begin() + 6, costmap.begin(), costmap.end());
    }
    for (std::size_t i = 6; i < paths.size(); ++i) files.add(paths[i]);
    const std::size_t tif = paths.size() - terrainLayerNames().size() - 1;
    countCostmapCells(tiles, costmapCells_);
    costmapScans_ = stats_.scans;
    // A small map: one dense grid of its box; a tiled one: an overview for the scene and pictures.
    const int factor = tiled ? int((std::max(tiles.boxWidth(), tiles.boxHeight()) + how.pictureSide - 1) / how.pictureSide) : 1;
    const LayerGrid grid = tiled ? tiles.overview(factor).dense() : tiles.dense();
    const std::vector<std::string>& names = terrainLayerNames();
    auto costmapAndLayers = [&] {  // the costmap, the GeoTIFF and the layer pictures
        if (!tiled) {
            writeCostmap(files, 6, costmapOf(grid));
            const std::string bytes = encodeLayersGeoTiff(grid);
            files[tif].write(bytes.data(), bytes.size());
        } else {
            const std::string metadata = costmapMetadata(prefix, costTiles, how.costmapTile, res);
            files[6].write(metadata.data(), metadata.size());
            for (std::size_t k = 0; k < costTiles.size(); ++k) {
                const int edge = how.costmapTile;
                writeCostmap(files, 7 + 2 * k, costmapOf(tiles.window(costTiles[k].first * edge, costTiles[k].second * edge, edge, edge)));
            }
            const std::string bytes = encodeLayersCog(tiles);
            files[tif].write(bytes.data(), bytes.size());
        }
        for (std::size_t i = 0; i < names.size(); ++i) {  // one at a time
            LayerPictureOptions o;
            o.title = pictureTitle();
            if (names[i] == "cost") o.min = 0, o.max = 100;
            const std::string png = encodeLayerPng(grid, names[i], o);
            files[tif + 1 + i].write(png.data(), png.size());
        }
    };
    // (A future of std::async waits for its task when destroyed: on an error here, before `files`
    // and `grid` go.)
    std::future<void> layersWritten;
    if (second) layersWritten = std::async(std::launch::async, costmapAndLayers);
    detail::writeMapScene(files[5], v.xyz, v.labels, res, path_, &grid, v.groundUnderObstacles);
    if (layersWritten.valid()) layersWritten.get();
    else costmapAndLayers();
    files.commit();
    return files.paths();
}

}  // namespace gseg::map
