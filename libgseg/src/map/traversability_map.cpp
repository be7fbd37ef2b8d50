#include <gseg/map/traversability_map.hpp>

#include <gseg/map/output_files.hpp>
#include <gseg/map/scan_update.hpp>

#include "map_tree.hpp"
#include "voxel_keys.hpp"

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace gseg::map {

namespace detail {
struct KeyMemory {
    CodeIndex codes;
    std::vector<std::uint64_t> list;  ///< the same codes, in insertion order
};
}  // namespace detail

namespace {

/// lo < v < hi (or lo <= v <= hi with `inclusive`).
void requireInRange(double v, const char* name, double lo, double hi, bool inclusive = false) {
    const bool ok = inclusive ? (v >= lo && v <= hi) : (v > lo && v < hi);
    if (!ok) {
        std::ostringstream s;
        s << "TraversabilityOptions." << name << " = " << v << ": must lie in " << (inclusive ? "[" : "(") << lo << ", "
          << hi << (inclusive ? "]" : ")");
        throw std::invalid_argument(s.str());
    }
}

std::unique_ptr<detail::MapTree> makeTree(const TraversabilityOptions& o) {
    auto t = std::make_unique<detail::MapTree>(o.resolution);
    t->setProbHit(o.probHit);
    t->setProbMiss(o.probMiss);
    t->setClampingThresMin(o.clampMin);
    t->setClampingThresMax(o.clampMax);
    t->setOccupancyThres(o.occupancyThreshold);
    return t;
}

/// Calls f(x, y, z) for the centre of every finest voxel of every occupied leaf (pruned leaves
/// stand for several voxels).
template <class Tree, class F>
void forEachOccupiedVoxel(const Tree& tree, F&& f) {
    const double res = tree.getResolution();
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
        if (!tree.isNodeOccupied(*it)) continue;
        const double size = it.getSize();
        const int n = std::max(1, int(std::lround(size / res)));
        const double x0 = it.getX() - size / 2 + res / 2, y0 = it.getY() - size / 2 + res / 2,
                     z0 = it.getZ() - size / 2 + res / 2;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j)
                for (int k = 0; k < n; ++k) f(x0 + i * res, y0 + j * res, z0 + k * res);
    }
}

/// Voxels (finest resolution) in occupied or in free leaves.
std::size_t countVoxels(const octomap::OcTree& tree, bool occupied) {
    const double res = tree.getResolution();
    std::size_t n = 0;
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
        if (tree.isNodeOccupied(*it) != occupied) continue;
        const std::size_t side = std::size_t(std::max(1L, std::lround(it.getSize() / res)));
        n += side * side * side;
    }
    return n;
}

bool occupiedAt(const octomap::OcTree& tree, double x, double y, double z) {
    const octomap::OcTreeNode* node = tree.search(x, y, z);
    return node && tree.isNodeOccupied(node);
}

/// Lowest ground and obstacle voxel of a column, for the top-down grid.
struct Column {
    float minGround = std::numeric_limits<float>::infinity();
    float minObstacle = std::numeric_limits<float>::infinity();
};

}  // namespace

void TraversabilityOptions::validate() const {
    requireInRange(resolution, "resolution [m]", 0.01, 10.0, true);
    if (!(maxRange > 0)) throw std::invalid_argument("TraversabilityOptions.maxRange = " + std::to_string(maxRange) + ": must be > 0 m");
    if (maxRange / resolution > kMaxRayVoxels)
        throw std::invalid_argument("TraversabilityOptions: maxRange / resolution = " + std::to_string(maxRange) + " / " +
                                    std::to_string(resolution) + " gives rays of " + std::to_string(long(maxRange / resolution)) +
                                    " voxels: at most " + std::to_string(long(kMaxRayVoxels)));
    requireInRange(probHit, "probHit", 0.5, 1.0);
    requireInRange(probMiss, "probMiss", 0.0, 0.5);
    requireInRange(clampMin, "clampMin", 0.0, 0.5);
    requireInRange(clampMax, "clampMax", 0.5, 1.0);
    requireInRange(occupancyThreshold, "occupancyThreshold", 0.0, 1.0);
    if (!(clearance > 0)) throw std::invalid_argument("TraversabilityOptions.clearance = " + std::to_string(clearance) + ": must be > 0 m");
}

Rgb colourOf(CellClass c) {
    switch (c) {
        case CellClass::Traversable: return {60, 180, 75};
        case CellClass::Obstacle: return {220, 40, 40};
        default: return {45, 45, 50};
    }
}

TraversabilityMap::TraversabilityMap(const TraversabilityOptions& options)
    : options_(options), everObstacle_(std::make_unique<detail::KeyMemory>()) {
    options_.validate();
    ground_ = makeTree(options_);
    obstacles_ = makeTree(options_);
}

TraversabilityMap::~TraversabilityMap() = default;
TraversabilityMap::TraversabilityMap(TraversabilityMap&&) noexcept = default;
TraversabilityMap& TraversabilityMap::operator=(TraversabilityMap&&) noexcept = default;

const octomap::OcTree& TraversabilityMap::groundTree() const { return *ground_; }
const octomap::OcTree& TraversabilityMap::obstacleTree() const { return *obstacles_; }

void TraversabilityMap::insertScan(const PointCloudView& ground, const PointCloudView& obstacles,
                                   const Eigen::Vector3d& sensorOrigin) {
    apply(castScan(ground, obstacles, sensorOrigin, options_));
}

void TraversabilityMap::apply(const ScanUpdate& u) {
    if (!u.origin.allFinite()) throw std::invalid_argument("TraversabilityMap::apply: sensor origin is not finite");
    // Free first: hits of the same scan are never in `free`, so the order within a scan does not
    // matter; ground does not move, so misses never lower an occupied ground voxel (rays to
    // distant ground graze the road near their end and would erode it scan after scan).
    ground_->applySorted(u.free, detail::VoxelUpdate::MissUnlessOccupied);
    obstacles_->applySorted(u.free, detail::VoxelUpdate::Miss);
    ground_->applySorted(u.groundHits, detail::VoxelUpdate::Hit);
    obstacles_->applySorted(u.obstacleHits, detail::VoxelUpdate::Hit);
    for (std::uint64_t c : u.obstacleHits) {
        bool inserted = false;
        everObstacle_->codes.insert(c, inserted);
        if (inserted) everObstacle_->list.push_back(c);
    }
    if (!path_.empty()) stats_.pathLength += (u.origin - path_.back()).norm();
    path_.push_back(u.origin);
    ++stats_.scans;
    stats_.groundPoints += u.groundPoints;
    stats_.obstaclePoints += u.obstaclePoints;
    stats_.pointsSkipped += u.pointsSkipped;
    stats_.rays += u.rays;
}

std::unique_ptr<octomap::ColorOcTree> TraversabilityMap::colouredTree() const {
    auto tree = std::make_unique<octomap::ColorOcTree>(options_.resolution);
    tree->setOccupancyThres(options_.occupancyThreshold);
    auto add = [&](double x, double y, double z, Rgb c) {
        const octomap::OcTreeKey key = tree->coordToKey(x, y, z);
        tree->updateNode(key, true, true);
        tree->setNodeColor(key, c.r, c.g, c.b);
    };
    forEachOccupiedVoxel(*obstacles_, [&](double x, double y, double z) { add(x, y, z, colourOf(CellClass::Obstacle)); });
    forEachOccupiedVoxel(*ground_, [&](double x, double y, double z) {
        if (!occupiedAt(*obstacles_, x, y, z)) add(x, y, z, colourOf(CellClass::Traversable));
    });
    if (tree->size() > 0) tree->updateInnerOccupancy();  // ColorOcTree's crashes on an empty tree
    return tree;
}

TopDownGrid TraversabilityMap::topDown() const {
    const double res = options_.resolution;
    std::unordered_map<std::uint64_t, Column> columns;
    TopDownGrid g(res);
    auto column = [&](double x, double y) -> Column& { return columns[detail::pairKey(g.cellIndex(x), g.cellIndex(y))]; };
    forEachOccupiedVoxel(*ground_, [&](double x, double y, double z) {
        Column& c = column(x, y);
        c.minGround = std::min(c.minGround, float(z));
    });
    forEachOccupiedVoxel(*obstacles_, [&](double x, double y, double z) {
        Column& c = column(x, y);
        c.minObstacle = std::min(c.minObstacle, float(z));
    });
    for (const auto& [key, c] : columns) {
        const auto [ix, iy] = detail::splitPairKey(key);
        const bool hasGround = std::isfinite(c.minGround);
        const float reference = hasGround ? c.minGround : c.minObstacle;
        const bool blocked = c.minObstacle <= reference + float(options_.clearance);
        g.set(ix, iy, blocked ? CellClass::Obstacle : CellClass::Traversable);
    }
    return g;
}

MapStats TraversabilityMap::stats() const {
    MapStats s = stats_;
    s.groundVoxels = countVoxels(*ground_, true);
    s.obstacleVoxels = countVoxels(*obstacles_, true);
    s.freeVoxels = countVoxels(*obstacles_, false);
    s.clearedObstacleVoxels = 0;
    for (std::uint64_t c : everObstacle_->list) {
        const octomap::OcTreeNode* n = obstacles_->search(detail::keyOfCode(c));
        if (n && !obstacles_->isNodeOccupied(n)) ++s.clearedObstacleVoxels;
    }
    forEachOccupiedVoxel(*ground_, [&](double x, double y, double z) {
        if (occupiedAt(*obstacles_, x, y, z)) ++s.groundUnderObstacle;
    });
    const TopDownGrid g = topDown();
    s.cellsTraversable = g.count(CellClass::Traversable);
    s.cellsObstacle = g.count(CellClass::Obstacle);
    const PictureLayout layout = pictureLayout(g, path_);
    s.cellsUnknown = std::size_t(layout.cellsWide * layout.cellsHigh) - s.cellsTraversable - s.cellsObstacle;
    return s;
}

std::vector<std::string> TraversabilityMap::outputPaths(const std::string& prefix) {
    return {prefix + "_ground.bt", prefix + "_obstacles.bt", prefix + "_traversability.ot", prefix + "_traversability.png"};
}

std::vector<std::string> TraversabilityMap::write(const std::string& prefix) const {
    if (empty()) throw std::logic_error("TraversabilityMap::write: no scan was inserted");
    std::ostringstream groundBt, obstaclesBt, colouredOt;
    ground_->writeUnprunedBinary(groundBt);
    obstacles_->writeUnprunedBinary(obstaclesBt);
    if (!colouredTree()->write(colouredOt)) throw std::runtime_error(prefix + ": OctoMap serialisation failed");
    const std::string blobs[4] = {groundBt.str(), obstaclesBt.str(), colouredOt.str(), encodeTopDownPng(topDown(), path_)};
    AtomicFiles files(outputPaths(prefix));
    for (std::size_t i = 0; i < 4; ++i) writeFileChecked(files.temporary(i), blobs[i]);
    files.commit();
    return files.paths();
}

}  // namespace gseg::map
