#include <gseg/map/traversability_map.hpp>


#include <mrpt/img/CImage.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unistd.h>
#include <unordered_map>

namespace gseg::map {

namespace detail {
struct KeyMemory {
    octomap::KeySet keys;
};
}  // namespace detail

namespace {

void requireProbability(double v, const char* name, double lo, double hi) {
    if (!(v > lo && v < hi))
        throw std::invalid_argument(std::string("TraversabilityOptions.") + name + " = " + std::to_string(v) +
                                    ": must lie in (" + std::to_string(lo) + ", " + std::to_string(hi) + ")");
}

std::unique_ptr<octomap::OcTree> makeTree(const TraversabilityOptions& o) {
    auto t = std::make_unique<octomap::OcTree>(o.resolution);
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

/// Column extremes for the top-down grid.
struct Column {
    float minGround = std::numeric_limits<float>::infinity();
    float minObstacle = std::numeric_limits<float>::infinity();
};

std::int64_t columnKey(std::int64_t ix, std::int64_t iy) { return (ix << 32) ^ (iy & 0xffffffff); }

void drawPath(::mrpt::img::CImage& img, const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& path) {
    const ::mrpt::img::TColor blue(40, 120, 255), white(255, 255, 255);
    int pc = 0, pr = 0;
    for (std::size_t i = 0; i < path.size(); ++i) {
        int c = 0, r = 0;
        if (!grid.toPixel(path[i].x(), path[i].y(), c, r)) continue;
        if (i > 0) img.line(pc, pr, c, r, blue, 1);
        pc = c, pr = r;
    }
    int c = 0, r = 0;
    if (!path.empty() && grid.toPixel(path[0].x(), path[0].y(), c, r)) img.filledRectangle(c - 1, r - 1, c + 1, r + 1, white);
}

std::string tempPath(const std::string& path) {
    // The extension stays last: MRPT's CImage picks the image format from it.
    const auto slash = path.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
    const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
    return dir + ".tmp" + std::to_string(::getpid()) + "_" + name;
}

void writeBytes(const std::string& path, const std::string& bytes) {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) throw std::runtime_error(path + ": cannot create");
    const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
    if (std::fclose(f) != 0 || !ok) {
        std::remove(path.c_str());
        throw std::runtime_error(path + ": write failed (disk full?)");
    }
}

}  // namespace

void TraversabilityOptions::validate() const {
    if (!(resolution > 0.001 && resolution < 100))
        throw std::invalid_argument("TraversabilityOptions.resolution = " + std::to_string(resolution) +
                                    ": must lie in (0.001, 100) m");
    if (!(maxRange > 0)) throw std::invalid_argument("TraversabilityOptions.maxRange = " + std::to_string(maxRange) + ": must be > 0 m");
    requireProbability(probHit, "probHit", 0.5, 1.0);
    requireProbability(probMiss, "probMiss", 0.0, 0.5);
    requireProbability(clampMin, "clampMin", 0.0, 0.5);
    requireProbability(clampMax, "clampMax", 0.5, 1.0);
    requireProbability(occupancyThreshold, "occupancyThreshold", 0.0, 1.0);
    if (!(clearance > 0)) throw std::invalid_argument("TraversabilityOptions.clearance = " + std::to_string(clearance) + ": must be > 0 m");
}

bool TopDownGrid::toPixel(double x, double y, int& col, int& row) const {
    const double c = std::floor((x - minX) / cell), r = std::floor((maxY - y) / cell);
    if (!(c >= 0 && c < width && r >= 0 && r < height)) return false;
    col = int(c), row = int(r);
    return true;
}

CellClass TopDownGrid::at(double x, double y) const {
    int c = 0, r = 0;
    return toPixel(x, y, c, r) ? cells[std::size_t(r) * std::size_t(width) + std::size_t(c)] : CellClass::Unknown;
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

void TraversabilityMap::insertScan(const PointCloudView& ground, const PointCloudView& obstacles,
                                   const Eigen::Vector3d& sensorOrigin) {
    if (!sensorOrigin.allFinite()) throw std::invalid_argument("insertScan: sensor origin is not finite");
    const octomap::point3d origin(float(sensorOrigin.x()), float(sensorOrigin.y()), float(sensorOrigin.z()));
    octomap::KeySet groundHits, obstacleHits, rayEnds;
    std::vector<octomap::point3d> ends;

    // Endpoints: one ray per endpoint voxel (what octomap calls a discretized update).
    auto collect = [&](const PointCloudView& pts, octomap::KeySet& hits) {
        for (std::size_t i = 0; i < pts.size(); ++i) {
            octomap::point3d p(pts.x(i), pts.y(i), pts.z(i));
            if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) continue;
            const octomap::point3d d = p - origin;
            const double range = d.norm();
            const bool hit = range <= options_.maxRange;
            if (!hit) p = origin + d * float(options_.maxRange / range);
            octomap::OcTreeKey key;
            if (!ground_->coordToKeyChecked(p, key)) continue;  // beyond the tree's extent
            if (hit) hits.insert(key);
            if (rayEnds.insert(key).second) ends.push_back(p);
        }
    };
    collect(ground, groundHits);
    collect(obstacles, obstacleHits);

    octomap::KeySet freeCells;
    octomap::KeyRay ray;
    for (const auto& end : ends) {
        if (!ground_->computeRayKeys(origin, end, ray)) continue;
        for (const auto& k : ray)
            if (!groundHits.count(k) && !obstacleHits.count(k)) freeCells.insert(k);
    }
    for (const auto& k : freeCells) {
        // Ground does not move: a ground voxel is never lowered by misses. Rays to distant ground
        // graze the road near their end and would otherwise erode it scan after scan.
        const octomap::OcTreeNode* g = ground_->search(k);
        if (!(g && ground_->isNodeOccupied(g))) ground_->updateNode(k, false, true);
        obstacles_->updateNode(k, false, true);
    }
    for (const auto& k : groundHits) ground_->updateNode(k, true, true);
    for (const auto& k : obstacleHits) {
        obstacles_->updateNode(k, true, true);
        everObstacle_->keys.insert(k);
    }
    ground_->updateInnerOccupancy();
    obstacles_->updateInnerOccupancy();

    if (!path_.empty()) stats_.pathLength += (sensorOrigin - path_.back()).norm();
    path_.push_back(sensorOrigin);
    ++stats_.scans;
    stats_.groundPoints += ground.size();
    stats_.obstaclePoints += obstacles.size();
    stats_.rays += ends.size();
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
    tree->updateInnerOccupancy();
    return tree;
}

TopDownGrid TraversabilityMap::topDown() const {
    const double res = options_.resolution;
    std::unordered_map<std::int64_t, Column> columns;
    double lo[2] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    double hi[2] = {-lo[0], -lo[1]};
    auto extend = [&](double x, double y) {
        lo[0] = std::min(lo[0], x), lo[1] = std::min(lo[1], y);
        hi[0] = std::max(hi[0], x), hi[1] = std::max(hi[1], y);
    };
    auto column = [&](double x, double y) -> Column& {
        extend(x, y);
        return columns[columnKey(std::int64_t(std::floor(x / res)), std::int64_t(std::floor(y / res)))];
    };
    forEachOccupiedVoxel(*ground_, [&](double x, double y, double z) {
        Column& c = column(x, y);
        c.minGround = std::min(c.minGround, float(z));
    });
    forEachOccupiedVoxel(*obstacles_, [&](double x, double y, double z) {
        Column& c = column(x, y);
        c.minObstacle = std::min(c.minObstacle, float(z));
    });
    for (const auto& p : path_) extend(p.x(), p.y());

    TopDownGrid g;
    g.cell = res;
    if (!std::isfinite(lo[0])) return g;
    const int margin = 5;  // cells around the content
    const std::int64_t c0 = std::int64_t(std::floor(lo[0] / res)) - margin, c1 = std::int64_t(std::floor(hi[0] / res)) + margin;
    const std::int64_t r0 = std::int64_t(std::floor(lo[1] / res)) - margin, r1 = std::int64_t(std::floor(hi[1] / res)) + margin;
    g.minX = double(c0) * res;
    g.maxY = double(r1 + 1) * res;
    g.width = int(c1 - c0 + 1);
    g.height = int(r1 - r0 + 1);
    g.cells.assign(std::size_t(g.width) * std::size_t(g.height), CellClass::Unknown);
    for (const auto& [key, c] : columns) {
        const std::int64_t ix = key >> 32, iy = std::int32_t(key & 0xffffffff);
        const bool hasGround = std::isfinite(c.minGround);
        const float reference = hasGround ? c.minGround : c.minObstacle;
        const bool blocked = c.minObstacle <= reference + float(options_.clearance);
        const std::size_t row = std::size_t(r1 - iy), col = std::size_t(ix - c0);
        g.cells[row * std::size_t(g.width) + col] = blocked ? CellClass::Obstacle : CellClass::Traversable;
    }
    return g;
}

MapStats TraversabilityMap::stats() const {
    MapStats s = stats_;
    s.groundVoxels = countVoxels(*ground_, true);
    s.obstacleVoxels = countVoxels(*obstacles_, true);
    s.freeVoxels = countVoxels(*obstacles_, false);
    s.clearedObstacleVoxels = 0;
    for (const auto& k : everObstacle_->keys) {
        const octomap::OcTreeNode* n = obstacles_->search(k);
        if (n && !obstacles_->isNodeOccupied(n)) ++s.clearedObstacleVoxels;
    }
    forEachOccupiedVoxel(*ground_, [&](double x, double y, double z) {
        if (occupiedAt(*obstacles_, x, y, z)) ++s.groundUnderObstacle;
    });
    const TopDownGrid g = topDown();
    for (CellClass c : g.cells) {
        if (c == CellClass::Traversable) ++s.cellsTraversable;
        else if (c == CellClass::Obstacle) ++s.cellsObstacle;
        else ++s.cellsUnknown;
    }
    return s;
}

void writeTopDownPng(const std::string& path, const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath) {
    if (grid.width <= 0 || grid.height <= 0) throw std::runtime_error(path + ": empty map, no picture to draw");
    ::mrpt::img::CImage img(grid.width, grid.height, ::mrpt::img::CH_RGB);
    for (int r = 0; r < grid.height; ++r)
        for (int c = 0; c < grid.width; ++c) {
            const Rgb rgb = colourOf(grid.cells[std::size_t(r) * std::size_t(grid.width) + std::size_t(c)]);
            img.setPixel(c, r, static_cast<unsigned int>(::mrpt::img::TColor(rgb.r, rgb.g, rgb.b)));
        }
    drawPath(img, grid, drivenPath);
    const std::string tmp = tempPath(path);
    if (!img.saveToFile(tmp)) {
        std::remove(tmp.c_str());
        throw std::runtime_error(path + ": cannot write the PNG");
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        std::remove(tmp.c_str());
        throw std::runtime_error(path + ": cannot rename the temporary file into place");
    }
}

std::vector<std::string> TraversabilityMap::write(const std::string& prefix) const {
    if (empty()) throw std::logic_error("TraversabilityMap::write: no scan was inserted");
    const std::vector<std::string> paths = {prefix + "_ground.bt", prefix + "_obstacles.bt",
                                            prefix + "_traversability.ot", prefix + "_traversability.png"};
    std::ostringstream groundBt, obstaclesBt, colouredOt;
    if (!ground_->writeBinaryConst(groundBt) || !obstacles_->writeBinaryConst(obstaclesBt) ||
        !colouredTree()->write(colouredOt))
        throw std::runtime_error(prefix + ": OctoMap serialisation failed");
    const std::string blobs[3] = {groundBt.str(), obstaclesBt.str(), colouredOt.str()};

    // Everything to temporary files first; rename only when all of them are complete.
    std::vector<std::string> temps;
    auto removeTemps = [&] {
        for (const auto& t : temps) std::remove(t.c_str());
    };
    try {
        for (int i = 0; i < 3; ++i) {
            temps.push_back(tempPath(paths[std::size_t(i)]));
            writeBytes(temps.back(), blobs[i]);
        }
        temps.push_back(tempPath(paths[3]));
        writeTopDownPng(temps.back(), topDown(), path_);
    } catch (...) {
        removeTemps();
        throw;
    }
    for (std::size_t i = 0; i < paths.size(); ++i) {
        if (std::rename(temps[i].c_str(), paths[i].c_str()) != 0) {
            for (std::size_t j = 0; j < i; ++j) std::remove(paths[j].c_str());
            for (std::size_t j = i; j < temps.size(); ++j) std::remove(temps[j].c_str());
            throw std::runtime_error(paths[i] + ": cannot rename the temporary file into place");
        }
    }
    return paths;
}

}  // namespace gseg::map
