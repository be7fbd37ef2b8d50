#include <gseg/map/terrain_layers.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace gseg::map {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

/// Column key parts: OctoMap key x, y (cell index + 32768).
int keyX(std::uint32_t cell) { return int(cell >> 16); }
int keyY(std::uint32_t cell) { return int(cell & 0xffffu); }
/// The map cell index of a column key part (negative left of / below the origin).
std::int64_t cellOf(int key) { return std::int64_t(key) - 32768; }
std::uint32_t columnKey(std::int64_t ix, std::int64_t iy) { return (std::uint32_t(ix + 32768) << 16) | std::uint32_t(iy + 32768); }

/// The layers' order in the tiles: the table of terrain_layers.hpp, then the scratch layers of the
/// computation (dropped at the end).
enum Layer : std::size_t { kElevation, kSlope, kStep, kRoughness, kClearance, kClass, kCost, kSource, kOutputLayers,
                           kLowZ = kOutputLayers, kHighZ, kOffX, kOffY, kRise, kClassBefore, kAllLayers };

using Cursor = LayerTiles::Cursor;

/// Calls f(ix, iy) for every cell of the tiles in `tiles` (tile coordinates) that lies in the box.
template <class F>
void forEachCell(const LayerTiles& t, const std::vector<std::pair<std::int64_t, std::int64_t>>& tiles, F&& f) {
    const int n = LayerTiles::kTile;
    for (const auto& [tx, ty] : tiles)
        for (std::int64_t iy = std::max(ty * n, t.minY()); iy < std::min((ty + 1) * n, t.maxY() + 1); ++iy)
            for (std::int64_t ix = std::max(tx * n, t.minX()); ix < std::min((tx + 1) * n, t.maxX() + 1); ++ix) f(ix, iy);
}

/// Gap filling (terrain_layers.hpp): judged against the classes before any gap is filled, so the
/// result does not depend on the order cells are visited. A filled cell lies within maxGapWidth
/// (at most 50 cells) of a traversable one: the tiles with data and their 8 neighbours hold them all.
void fillGaps(LayerTiles& g, const TraversabilityOptions& o, const ObstacleColumns& obstacles, const RayFreeQuery& rayFree) {
    static_assert(LayerTiles::kTile > 51, "a gap's cells lie in the tiles next to its ends");
    const auto allocated = g.tileList();
    {  // the classes before, tile by tile (a tile's cells of one layer are contiguous)
        Cursor from(g, kClass), to(g, kClassBefore);
        for (const auto& [tx, ty] : allocated) {
            const float* src = &from.at(tx * LayerTiles::kTile, ty * LayerTiles::kTile);
            std::copy(src, src + LayerTiles::kTile * LayerTiles::kTile, &to.at(tx * LayerTiles::kTile, ty * LayerTiles::kTile));
        }
    }
    std::vector<std::pair<std::int64_t, std::int64_t>> candidates;
    for (const auto& [tx, ty] : allocated)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) candidates.emplace_back(tx + dx, ty + dy);
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    Cursor before(g, kClassBefore), elevation(g, kElevation), here(g, kClassBefore);
    const double res = o.resolution, tanMax = std::tan(o.maxSlope * kPi / 180.0);
    const int dirs[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
    const float trav = float(ColumnClass::Traversable);
    struct Fill {
        std::int64_t ix, iy;
        float z, slopeDeg;
    };
    std::vector<Fill> fills;
    forEachCell(g, candidates, [&](std::int64_t cx, std::int64_t cy) {
        if (!std::isnan(here.get(cx, cy))) return;
        double bestWidth = std::numeric_limits<double>::infinity();
        float bestZ = 0, bestSlope = 0;
        for (const auto& d : dirs) {
            const double stepLen = res * std::hypot(double(d[0]), double(d[1]));
            const int reach = int(std::floor(o.gapWidth() / stepLen + 1e-9)) + 1;
            int dist[2] = {0, 0};
            float z[2] = {0, 0};
            for (int side = 0; side < 2; ++side) {
                const int sx = side ? -d[0] : d[0], sy = side ? -d[1] : d[1];
                for (int k = 1; k <= reach; ++k) {
                    const std::int64_t x = cx + k * sx, y = cy + k * sy;
                    const float c = before.get(x, y);  // NaN outside the box and the tiles, as unknown
                    if (std::isnan(c)) continue;
                    if (c == trav) dist[side] = k, z[side] = elevation.get(x, y);
                    break;  // the first known cell ends the search: an obstacle stops it
                }
            }
            if (!dist[0] || !dist[1]) continue;
            const double width = (dist[0] + dist[1] - 1) * stepLen, span = (dist[0] + dist[1]) * stepLen;
            if (width > o.gapWidth() + 1e-9 || width >= bestWidth) continue;
            const double dz = std::abs(double(z[0]) - double(z[1]));
            if (dz > o.maxStep || dz > tanMax * span) continue;
            bestWidth = width;
            bestZ = float((double(z[0]) * dist[1] + double(z[1]) * dist[0]) / (dist[0] + dist[1]));
            bestSlope = float(std::atan(dz / span) * 180.0 / kPi);
        }
        if (!std::isfinite(bestWidth)) return;
        const std::uint32_t column = columnKey(cx, cy);
        // A ray passed over the interpolated ground within the robot's height, none went below it.
        if (!rayFree(column, bestZ, bestZ + float(o.clearance))) return;
        if (rayFree(column, bestZ - float(o.clearance), bestZ - float(o.maxStep))) return;
        // Nothing stands in it: no obstacle voxel reaches higher than minObstacleHeight over that
        // ground (its top, not its centre: the cell has no ground of its own to measure from). A
        // column that returned something higher (a crown, a bush's top, a bridge) is not a gap:
        // its ground was hidden, and whether what stood there reaches down no ray could say.
        if (const auto col = obstacles.find(column); col != obstacles.end())
            for (float z : col->second)
                if (z + float(res / 2) > bestZ + o.minObstacleHeight) return;
        fills.push_back({cx, cy, bestZ, bestSlope});
    });
    for (const Fill& f : fills) {
        g.at(kElevation, f.ix, f.iy) = f.z, g.at(kSlope, f.ix, f.iy) = f.slopeDeg, g.at(kClass, f.ix, f.iy) = trav;
        g.at(kSource, f.ix, f.iy) = 2, g.at(kClearance, f.ix, f.iy) = std::numeric_limits<float>::infinity();
        g.at(kCost, f.ix, f.iy) = float(std::min(99.0, std::floor(99.0 * f.slopeDeg / o.maxSlope)));
    }
}

}  // namespace

struct GroundCells::Tile {
    std::array<GroundCellSums, 256> cells;  ///< 16 x 16, x-major; count 0: no ground seen
};

GroundCells::GroundCells() = default;
GroundCells::~GroundCells() = default;

void GroundCells::add(const std::vector<GroundCellSample>& samples) {
    std::uint32_t lastKey = 0;
    Tile* tile = nullptr;  // the last sample's tile
    for (const GroundCellSample& s : samples) {
        if (s.count == 0) continue;  // says nothing (a cell is known by its points)
        const std::uint32_t key = ((s.cell >> 20) << 12) | ((s.cell & 0xffffu) >> 4);
        if (!tile || key != lastKey) {
            auto& t = tiles_[key];
            if (!t) t = std::make_unique<Tile>();
            tile = t.get(), lastKey = key;
        }
        GroundCellSums& c = tile->cells[((s.cell >> 16 & 15u) << 4) | (s.cell & 15u)];
        if (c.count == 0) c.minZ = s.minZ, c.maxZ = s.maxZ;
        c.count += s.count, c.sumZ += s.sumZ, c.sumZ2 += s.sumZ2, c.sumX += s.sumX, c.sumY += s.sumY;
        c.minZ = std::min(c.minZ, s.minZ), c.maxZ = std::max(c.maxZ, s.maxZ);
    }
}

void GroundCells::forEach(const std::function<void(std::uint32_t, const GroundCellSums&)>& f) const {
    for (const auto& [key, tile] : tiles_)
        for (std::uint32_t i = 0; i < 256; ++i)
            if (tile->cells[i].count)
                f((((key >> 12) << 4 | i >> 4) << 16) | ((key & 0xfffu) << 4 | (i & 15u)), tile->cells[i]);
}

const std::vector<std::string>& terrainLayerNames() {
    static const std::vector<std::string> names{"elevation", "slope", "step", "roughness", "clearance", "class", "cost", "source"};
    return names;
}

LayerTiles terrainLayerTiles(const GroundCells& ground, const ObstacleColumns& obstacles, const TraversabilityOptions& o,
                             double emptyX, double emptyY, const gseg::TerrainModel* terrain, const RayFreeQuery& rayFree) {
    o.validate();
    const auto minPoints = std::uint64_t(o.minGroundPoints);
    int lo[2] = {std::numeric_limits<int>::max(), std::numeric_limits<int>::max()}, hi[2] = {-1, -1};
    auto extend = [&](std::uint32_t cell) {
        lo[0] = std::min(lo[0], keyX(cell)), hi[0] = std::max(hi[0], keyX(cell));
        lo[1] = std::min(lo[1], keyY(cell)), hi[1] = std::max(hi[1], keyY(cell));
    };
    ground.forEach([&](std::uint32_t cell, const GroundCellSums& sums) {
        if (sums.count >= minPoints) extend(cell);
    });
    for (const auto& [cell, zs] : obstacles)
        if (!zs.empty()) extend(cell);
    // The terrain model's cells (the map's columns: key = cell index + 32768).
    struct Modelled {
        std::uint32_t cell;
        float z;  ///< [m] modelled ground
    };
    std::vector<Modelled> modelled;
    if (terrain)
        terrain->forEachModelled([&](std::int32_t ix, std::int32_t iy, const gseg::TerrainCell& c) {
            const std::int64_t kx = std::int64_t(ix) + 32768, ky = std::int64_t(iy) + 32768;
            if (kx < 0 || ky < 0 || kx > 0xffff || ky > 0xffff) return;  // outside the map's extent
            modelled.push_back({(std::uint32_t(kx) << 16) | std::uint32_t(ky), c.elevation});
            extend(modelled.back().cell);
        });
    const double res = o.resolution;
    if (hi[0] < 0) {  // nothing seen: one unknown cell
        lo[0] = hi[0] = int(std::floor(emptyX / res)) + 32768;
        lo[1] = hi[1] = int(std::floor(emptyY / res)) + 32768;
    }
    std::vector<LayerTiles::Info> info{
            {"elevation", "m", "mean height of the ground points (map frame z)"},
            {"slope", "deg", "slope of the least-squares plane through the ground-point centroids of the cell and its 8 neighbours (steeper than maxSlope with no obstacle within slopeRadius: of the cells within slopeRadius)"},
            {"step", "m", "largest height difference between a ground point of the cell and one of a neighbouring cell, up or down"},
            {"roughness", "m", "standard deviation of the ground point heights in the cell"},
            {"clearance", "m", "free height above the ground up to the lowest obstacle (inf: none)"},
            {"class", "-", "1 traversable, 2 not traversable, NaN unknown"},
            {"cost", "-", "0-99 traversable (99 = at a robot limit), 100 not traversable, NaN unknown"},
            {"source", "-", "ground from: 0 the scans' ground points, 1 the drive's terrain model, 2 interpolated across a gap"},
            {"lowZ", "m", ""}, {"highZ", "m", ""}, {"offX", "m", ""}, {"offY", "m", ""}, {"rise", "m", ""}, {"classBefore", "-", ""}};
    LayerTiles g(res, info);
    g.setBox(cellOf(lo[0]), cellOf(lo[1]), cellOf(hi[0]), cellOf(hi[1]));
    // The cell centres exactly as a dense grid from the box's corner computes them (same bytes).
    const double originX = (lo[0] - 32768) * res, originY = (lo[1] - 32768) * res;
    auto centreX = [&](std::int64_t ix) { return originX + (int(ix - cellOf(lo[0])) + 0.5) * res; };
    auto centreY = [&](std::int64_t iy) { return originY + (int(iy - cellOf(lo[1])) + 0.5) * res; };
    Cursor elevation(g, kElevation), slope(g, kSlope), step(g, kStep), roughness(g, kRoughness), clearance(g, kClearance);
    Cursor cls(g, kClass), cost(g, kCost), source(g, kSource), lowZ(g, kLowZ), highZ(g, kHighZ), offX(g, kOffX), offY(g, kOffY);
    Cursor rise(g, kRise);

    ground.forEach([&](std::uint32_t cell, const GroundCellSums& s) {
        if (s.count < minPoints) return;
        const double n = double(s.count), mean = s.sumZ / n;
        const std::int64_t ix = cellOf(keyX(cell)), iy = cellOf(keyY(cell));
        elevation.at(ix, iy) = float(mean);
        lowZ.at(ix, iy) = s.minZ, highZ.at(ix, iy) = s.maxZ;
        offX.at(ix, iy) = float(s.sumX / n - centreX(ix)), offY.at(ix, iy) = float(s.sumY / n - centreY(iy));
        roughness.at(ix, iy) = float(std::sqrt(std::max(0.0, s.sumZ2 / n - mean * mean)));
        source.at(ix, iy) = 0;
    });
    // The drive's terrain model where the scans' ground points are too few: its elevation, no
    // spread (roughness 0; the step rule sees the modelled height).
    for (const Modelled& m : modelled) {
        const std::int64_t ix = cellOf(keyX(m.cell)), iy = cellOf(keyY(m.cell));
        if (!std::isnan(elevation.at(ix, iy))) continue;
        elevation.at(ix, iy) = m.z, lowZ.at(ix, iy) = highZ.at(ix, iy) = m.z, roughness.at(ix, iy) = 0, source.at(ix, iy) = 1;
        offX.at(ix, iy) = offY.at(ix, iy) = 0;
    }
    // Obstacle-only columns get their tile too (their class).
    for (const auto& [cell, zs] : obstacles)
        if (!zs.empty()) g.touch(cellOf(keyX(cell)), cellOf(keyY(cell)));
    if (g.tiles() == 0) g.touch(cellOf(lo[0]), cellOf(lo[1]));  // nothing seen: the one unknown cell
    const auto tiles = g.tileList();

    // Slope and step from the 3 x 3 neighbourhood of each cell with an elevation. Where that plane
    // is steeper than maxSlope and no obstacle voxel lower than `clearance` above the cell's ground
    // stands within slopeRadius, the slope is that of the plane through the cells within
    // slopeRadius: on rough ground the 3 x 3 plane (0.6 m at 0.2 m cells) follows bumps of a few
    // centimetres, a car's wheels do not; next to an obstacle (a bush's top the segmenter called
    // ground, the foot of a wall) the 3 x 3 plane judges.
    Cursor nElevation(g, kElevation), nLowZ(g, kLowZ), nHighZ(g, kHighZ), nOffX(g, kOffX), nOffY(g, kOffY);
    struct Plane {  // least-squares z = a + b x + c y through (x, y, z) points
        double sxx = 0, sxy = 0, syy = 0, sxz = 0, syz = 0, sx = 0, sy = 0, sz = 0, m = 0;
        void add(double x, double y, double z) { sxx += x * x, sxy += x * y, syy += y * y, sxz += x * z, syz += y * z, sx += x, sy += y, sz += z, ++m; }
        /// [deg] its inclination; NaN with fewer than 3 points or (nearly) on a line.
        float slopeDegrees(double res) const {
            if (m < 3) return kNaN;
            // Centred normal equations.
            const double cxx = sxx - sx * sx / m, cxy = sxy - sx * sy / m, cyy = syy - sy * sy / m;
            const double cxz = sxz - sx * sz / m, cyz = syz - sy * sz / m;
            const double det = cxx * cyy - cxy * cxy;
            if (!(det > 0.25 * res * res * res * res)) return kNaN;
            const double b = (cxz * cyy - cyz * cxy) / det, c = (cyz * cxx - cxz * cxy) / det;
            return float(std::atan(std::hypot(b, c)) * 180.0 / kPi);
        }
    };
    std::vector<std::pair<int, int>> slopeDisc;  // the cells within slopeRadius; none below 2 cells (the 3 x 3 alone)
    if (const int n = int(std::floor(o.slopeRadius / res + 1e-9)); n >= 2)
        for (int dy = -n; dy <= n; ++dy)
            for (int dx = -n; dx <= n; ++dx)
                if ((dx * dx + dy * dy) * res * res <= o.slopeRadius * o.slopeRadius * (1 + 1e-9)) slopeDisc.emplace_back(dx, dy);
    auto obstacleWithin = [&](std::int64_t cx, std::int64_t cy, float below) {
        for (const auto& [dx, dy] : slopeDisc) {
            const auto col = obstacles.find(columnKey(cx + dx, cy + dy));
            if (col != obstacles.end())
                for (float z : col->second)
                    if (z < below) return true;
        }
        return false;
    };
    forEachCell(g, tiles, [&](std::int64_t cx, std::int64_t cy) {
        const float z0 = elevation.get(cx, cy);
        if (std::isnan(z0)) return;
        Plane near;
        double jump = 0;
        const float low0 = lowZ.get(cx, cy), high0 = highZ.get(cx, cy);
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const float z = nElevation.get(cx + dx, cy + dy);  // NaN outside the box and the tiles
                if (std::isnan(z)) continue;
                near.add(dx * res + nOffX.get(cx + dx, cy + dy), dy * res + nOffY.get(cx + dx, cy + dy), z);
                if (dx != 0 || dy != 0)
                    jump = std::max({jump, double(nHighZ.get(cx + dx, cy + dy)) - double(low0), double(high0) - double(nLowZ.get(cx + dx, cy + dy))});
            }
        step.at(cx, cy) = float(jump);
        const float s = near.slopeDegrees(res);
        if (std::isnan(s)) return;
        slope.at(cx, cy) = s;
        if (!(s > o.maxSlope) || slopeDisc.empty() || obstacleWithin(cx, cy, z0 + float(o.clearance))) return;
        Plane wide;
        for (const auto& [dx, dy] : slopeDisc)
            if (const float z = nElevation.get(cx + dx, cy + dy); !std::isnan(z))
                wide.add(dx * res + nOffX.get(cx + dx, cy + dy), dy * res + nOffY.get(cx + dx, cy + dy), z);
        if (const float w = wide.slopeDegrees(res); !std::isnan(w)) slope.at(cx, cy) = w;
    });

    // Rise above the lowest elevation within groundRiseRadius (a disc of cell centres).
    const int rr = int(std::ceil(o.groundRiseRadius / res));
    forEachCell(g, tiles, [&](std::int64_t cx, std::int64_t cy) {
        const float z0 = elevation.get(cx, cy);
        if (std::isnan(z0)) return;
        float lowest = z0;
        for (int dy = -rr; dy <= rr; ++dy)
            for (int dx = -rr; dx <= rr; ++dx)
                if ((dx * dx + dy * dy) * res * res <= o.groundRiseRadius * o.groundRiseRadius * (1 + 1e-9)) {
                    const float z = nElevation.get(cx + dx, cy + dy);
                    if (z < lowest) lowest = z;  // NaN compares false
                }
        rise.at(cx, cy) = z0 - lowest;
    });

    // Clearance and class.
    const int r = std::max(1, int(std::lround(1.0 / res)));
    std::vector<float> near;
    forEachCell(g, tiles, [&](std::int64_t cx, std::int64_t cy) {
        const auto col = obstacles.find(columnKey(cx, cy));
        const std::vector<float>* zs = col == obstacles.end() ? nullptr : &col->second;
        const float z0 = elevation.get(cx, cy);
        if (!std::isnan(z0)) {
            float lowest = std::numeric_limits<float>::infinity();
            if (zs)
                for (float z : *zs)
                    if (z > z0 + o.minObstacleHeight) lowest = std::min(lowest, z - float(res / 2));
            const float free = lowest - z0;
            clearance.at(cx, cy) = free;
            const float stepHere = step.get(cx, cy), roughHere = roughness.get(cx, cy), slopeHere = slope.get(cx, cy);
            const bool ok = free >= o.clearance && stepHere <= o.maxStep && roughHere <= o.maxRoughness &&
                            rise.get(cx, cy) <= o.maxGroundRise &&
                            !(slopeHere > o.maxSlope);  // no slope (too few neighbours): not judged by it
            cls.at(cx, cy) = float(ok ? ColumnClass::Traversable : ColumnClass::Obstacle);
            // Modelled ground is free only where a ray crossed the layer just above the obstacle
            // height and left it free: ground seen through a low slot (under a car's body or a
            // ledge whose top no ray reached) stays unknown.
            if (ok && source.get(cx, cy) == 1 && rayFree &&
                !rayFree(columnKey(cx, cy), z0 + float(o.minObstacleHeight), z0 + float(o.minObstacleHeight + 2 * res))) {
                cls.at(cx, cy) = kNaN;
                return;
            }
            if (ok) {
                double worst = std::max(stepHere / o.maxStep, roughHere / o.maxRoughness);
                if (!std::isnan(slopeHere)) worst = std::max(worst, slopeHere / o.maxSlope);
                cost.at(cx, cy) = float(std::min(99.0, std::floor(99.0 * worst)));
            } else {
                cost.at(cx, cy) = 100;
            }
            return;
        }
        if (!zs || zs->empty()) return;
        near.clear();
        for (int dy = -r; dy <= r; ++dy)
            for (int dx = -r; dx <= r; ++dx)
                if (const float z = nElevation.get(cx + dx, cy + dy); !std::isnan(z)) near.push_back(z);
        float ref = 0;
        if (!near.empty()) {
            std::nth_element(near.begin(), near.begin() + std::ptrdiff_t(near.size() / 2), near.end());
            ref = near[near.size() / 2];
        } else {
            ref = *std::min_element(zs->begin(), zs->end()) - float(res / 2);
        }
        bool blocked = false;
        float lowest = std::numeric_limits<float>::infinity();
        for (float z : *zs)
            if (z > ref + o.minObstacleHeight) {
                lowest = std::min(lowest, z - float(res / 2));
                blocked |= z < ref + o.clearance;
            }
        if (blocked) cls.at(cx, cy) = float(ColumnClass::Obstacle), cost.at(cx, cy) = 100, clearance.at(cx, cy) = std::max(0.0f, lowest - ref);
    });
    if (o.fillGaps && rayFree) fillGaps(g, o, obstacles, rayFree);
    g.keepLayers(kOutputLayers);
    return g;
}

LayerGrid terrainLayers(const GroundCells& ground, const ObstacleColumns& obstacles, const TraversabilityOptions& o,
                        double emptyX, double emptyY, const gseg::TerrainModel* terrain, const RayFreeQuery& rayFree) {
    return terrainLayerTiles(ground, obstacles, o, emptyX, emptyY, terrain, rayFree).dense();
}

gseg::io::RosMap costmapOf(const LayerGrid& layers) {
    using gseg::io::RosMap;
    RosMap m = RosMap::unknown(layers.width(), layers.height(), layers.resolution(), layers.originX(), layers.originY());
    const auto& cls = layers.layer("class").values;
    for (int cy = 0; cy < layers.height(); ++cy)
        for (int cx = 0; cx < layers.width(); ++cx) {
            const float c = cls[layers.index(cx, cy)];
            if (c == float(ColumnClass::Traversable)) m.value(cx, cy) = RosMap::kFree;
            else if (c == float(ColumnClass::Obstacle)) m.value(cx, cy) = RosMap::kOccupied;
        }
    return m;
}

}  // namespace gseg::map
