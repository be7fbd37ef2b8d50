#include <gseg/map/terrain_layers.hpp>

#include <algorithm>
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

/// Gap filling (terrain_layers.hpp): judged against the classes before any gap is filled, so the
/// result does not depend on the order cells are visited.
template <class ColumnOf>
void fillGaps(LayerGrid& g, const TraversabilityOptions& o, ColumnOf columnOf, const ObstacleColumns& obstacles,
              const RayFreeQuery& rayFree) {
    auto& elevation = g.find("elevation")->values;
    auto& slope = g.find("slope")->values;
    auto& cls = g.find("class")->values;
    auto& cost = g.find("cost")->values;
    auto& source = g.find("source")->values;
    auto& clearance = g.find("clearance")->values;
    const std::vector<float> before = cls;
    const double res = o.resolution, tanMax = std::tan(o.maxSlope * kPi / 180.0);
    const int dirs[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
    const float trav = float(ColumnClass::Traversable);
    struct Fill {
        std::size_t i;
        float z, slopeDeg, clearance;
    };
    std::vector<Fill> fills;
    for (int cy = 0; cy < g.height(); ++cy)
        for (int cx = 0; cx < g.width(); ++cx) {
            const std::size_t i = g.index(cx, cy);
            if (!std::isnan(before[i])) continue;
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
                        const int x = cx + k * sx, y = cy + k * sy;
                        if (!g.inside(x, y)) break;
                        const float c = before[g.index(x, y)];
                        if (std::isnan(c)) continue;
                        if (c == trav) dist[side] = k, z[side] = elevation[g.index(x, y)];
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
            if (!std::isfinite(bestWidth)) continue;
            const std::uint32_t column = columnOf(cx, cy);
            // A ray passed over the interpolated ground within the robot's height, none went below it.
            if (!rayFree(column, bestZ, bestZ + float(o.clearance))) continue;
            if (rayFree(column, bestZ - float(o.clearance), bestZ - float(o.maxStep))) continue;
            // Nothing stands in it: no obstacle voxel between minObstacleHeight and clearance above.
            float lowest = std::numeric_limits<float>::infinity();
            if (const auto col = obstacles.find(column); col != obstacles.end())
                for (float z : col->second)
                    if (z > bestZ + o.minObstacleHeight) lowest = std::min(lowest, z - float(res / 2));
            if (lowest - bestZ < o.clearance) continue;
            fills.push_back({i, bestZ, bestSlope, lowest - bestZ});
        }
    for (const Fill& f : fills) {
        elevation[f.i] = f.z, slope[f.i] = f.slopeDeg, cls[f.i] = trav, source[f.i] = 2, clearance[f.i] = f.clearance;
        cost[f.i] = float(std::min(99.0, std::floor(99.0 * f.slopeDeg / o.maxSlope)));
    }
}

}  // namespace

void GroundCells::add(const std::vector<GroundCellSample>& samples) {
    for (const GroundCellSample& s : samples) {
        auto [it, added] = cells_.try_emplace(s.cell);
        GroundCellSums& c = it->second;
        if (added) c.minZ = s.minZ, c.maxZ = s.maxZ;
        c.count += s.count, c.sumZ += s.sumZ, c.sumZ2 += s.sumZ2, c.sumX += s.sumX, c.sumY += s.sumY;
        c.minZ = std::min(c.minZ, s.minZ), c.maxZ = std::max(c.maxZ, s.maxZ);
    }
}

const std::vector<std::string>& terrainLayerNames() {
    static const std::vector<std::string> names{"elevation", "slope", "step", "roughness", "clearance", "class", "cost", "source"};
    return names;
}

LayerGrid terrainLayers(const GroundCells& ground, const ObstacleColumns& obstacles, const TraversabilityOptions& o,
                        double emptyX, double emptyY, const gseg::TerrainModel* terrain, const RayFreeQuery& rayFree) {
    o.validate();
    const auto minPoints = std::uint64_t(o.minGroundPoints);
    int lo[2] = {std::numeric_limits<int>::max(), std::numeric_limits<int>::max()}, hi[2] = {-1, -1};
    auto extend = [&](std::uint32_t cell) {
        lo[0] = std::min(lo[0], keyX(cell)), hi[0] = std::max(hi[0], keyX(cell));
        lo[1] = std::min(lo[1], keyY(cell)), hi[1] = std::max(hi[1], keyY(cell));
    };
    for (const auto& [cell, sums] : ground.cells())
        if (sums.count >= minPoints) extend(cell);
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
    LayerGrid g(hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, res, (lo[0] - 32768) * res, (lo[1] - 32768) * res);
    auto& elevation = g.add("elevation", "m", "mean height of the ground points (map frame z)").values;
    auto& slope = g.add("slope", "deg", "slope of the least-squares plane through the ground-point centroids of the cell and its 8 neighbours").values;
    auto& step = g.add("step", "m", "largest height difference between a ground point of the cell and one of a neighbouring cell, up or down").values;
    auto& roughness = g.add("roughness", "m", "standard deviation of the ground point heights in the cell").values;
    auto& clearance = g.add("clearance", "m", "free height above the ground up to the lowest obstacle (inf: none)").values;
    auto& cls = g.add("class", "-", "1 traversable, 2 not traversable, NaN unknown").values;
    auto& cost = g.add("cost", "-", "0-99 traversable (99 = at a robot limit), 100 not traversable, NaN unknown").values;
    auto& source = g.add("source", "-", "ground from: 0 the scans' ground points, 1 the drive's terrain model, 2 interpolated across a gap").values;
    const int w = g.width(), h = g.height();
    auto at = [&](std::uint32_t cell) { return g.index(keyX(cell) - lo[0], keyY(cell) - lo[1]); };
    auto columnKey = [&](int cx, int cy) { return (std::uint32_t(cx + lo[0]) << 16) | std::uint32_t(cy + lo[1]); };

    std::vector<float> lowZ(g.cells(), kNaN), highZ(g.cells(), kNaN), offX(g.cells(), 0.f), offY(g.cells(), 0.f);
    for (const auto& [cell, s] : ground.cells()) {
        if (s.count < minPoints) continue;
        const double n = double(s.count), mean = s.sumZ / n;
        const std::size_t i = at(cell);
        elevation[i] = float(mean);
        lowZ[i] = s.minZ, highZ[i] = s.maxZ;
        offX[i] = float(s.sumX / n - g.centreX(keyX(cell) - lo[0])), offY[i] = float(s.sumY / n - g.centreY(keyY(cell) - lo[1]));
        roughness[i] = float(std::sqrt(std::max(0.0, s.sumZ2 / n - mean * mean)));
        source[i] = 0;
    }
    // The drive's terrain model where the scans' ground points are too few: its elevation, no
    // spread (roughness 0; the step rule sees the modelled height).
    for (const Modelled& m : modelled) {
        const std::size_t i = at(m.cell);
        if (!std::isnan(elevation[i])) continue;
        elevation[i] = m.z, lowZ[i] = highZ[i] = m.z, roughness[i] = 0, source[i] = 1;
    }

    // Slope and step from the 3 x 3 neighbourhood of each cell with an elevation.
    for (int cy = 0; cy < h; ++cy)
        for (int cx = 0; cx < w; ++cx) {
            const std::size_t i = g.index(cx, cy);
            const float z0 = elevation[i];
            if (std::isnan(z0)) continue;
            double sxx = 0, sxy = 0, syy = 0, sxz = 0, syz = 0, sx = 0, sy = 0, sz = 0, m = 0, jump = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    if (!g.inside(cx + dx, cy + dy)) continue;
                    const std::size_t j = g.index(cx + dx, cy + dy);
                    const float z = elevation[j];
                    if (std::isnan(z)) continue;
                    const double x = dx * res + offX[j], y = dy * res + offY[j];
                    sxx += x * x, sxy += x * y, syy += y * y, sxz += x * z, syz += y * z, sx += x, sy += y, sz += z, ++m;
                    if (j != i) jump = std::max({jump, double(highZ[j]) - double(lowZ[i]), double(highZ[i]) - double(lowZ[j])});
                }
            step[i] = float(jump);
            if (m < 3) continue;
            // Centred normal equations of z = a + b x + c y.
            const double cxx = sxx - sx * sx / m, cxy = sxy - sx * sy / m, cyy = syy - sy * sy / m;
            const double cxz = sxz - sx * sz / m, cyz = syz - sy * sz / m;
            const double det = cxx * cyy - cxy * cxy;
            if (!(det > 0.25 * res * res * res * res)) continue;  // the centroids (nearly) on a line: no plane
            const double b = (cxz * cyy - cyz * cxy) / det, c = (cyz * cxx - cxz * cxy) / det;
            slope[i] = float(std::atan(std::hypot(b, c)) * 180.0 / kPi);
        }

    // Rise above the lowest elevation within groundRiseRadius (a disc of cell centres).
    std::vector<float> rise(g.cells(), kNaN);
    const int rr = int(std::ceil(o.groundRiseRadius / res));
    for (int cy = 0; cy < h; ++cy)
        for (int cx = 0; cx < w; ++cx) {
            const float z0 = elevation[g.index(cx, cy)];
            if (std::isnan(z0)) continue;
            float lowest = z0;
            for (int dy = -rr; dy <= rr; ++dy)
                for (int dx = -rr; dx <= rr; ++dx)
                    if ((dx * dx + dy * dy) * res * res <= o.groundRiseRadius * o.groundRiseRadius * (1 + 1e-9) &&
                        g.inside(cx + dx, cy + dy)) {
                        const float z = elevation[g.index(cx + dx, cy + dy)];
                        if (z < lowest) lowest = z;  // NaN compares false
                    }
            rise[g.index(cx, cy)] = z0 - lowest;
        }

    // Clearance and class.
    const int r = std::max(1, int(std::lround(1.0 / res)));
    std::vector<float> near;
    for (int cy = 0; cy < h; ++cy)
        for (int cx = 0; cx < w; ++cx) {
            const std::size_t i = g.index(cx, cy);
            const auto col = obstacles.find((std::uint32_t(cx + lo[0]) << 16) | std::uint32_t(cy + lo[1]));
            const std::vector<float>* zs = col == obstacles.end() ? nullptr : &col->second;
            const float z0 = elevation[i];
            if (!std::isnan(z0)) {
                float lowest = std::numeric_limits<float>::infinity();
                if (zs)
                    for (float z : *zs)
                        if (z > z0 + o.minObstacleHeight) lowest = std::min(lowest, z - float(res / 2));
                clearance[i] = lowest - z0;
                const bool ok = clearance[i] >= o.clearance && step[i] <= o.maxStep && roughness[i] <= o.maxRoughness &&
                                rise[i] <= o.maxGroundRise &&
                                !(slope[i] > o.maxSlope);  // no slope (too few neighbours): not judged by it
                cls[i] = float(ok ? ColumnClass::Traversable : ColumnClass::Obstacle);
                // Modelled ground is free only where a ray crossed the layer just above the obstacle
                // height and left it free: ground seen through a low slot (under a car's body or a
                // ledge whose top no ray reached) stays unknown.
                if (ok && source[i] == 1 && rayFree &&
                    !rayFree(columnKey(cx, cy), z0 + float(o.minObstacleHeight), z0 + float(o.minObstacleHeight + 2 * res))) {
                    cls[i] = kNaN;
                    continue;
                }
                if (ok) {
                    double worst = std::max(step[i] / o.maxStep, roughness[i] / o.maxRoughness);
                    if (!std::isnan(slope[i])) worst = std::max(worst, slope[i] / o.maxSlope);
                    cost[i] = float(std::min(99.0, std::floor(99.0 * worst)));
                } else {
                    cost[i] = 100;
                }
                continue;
            }
            if (!zs || zs->empty()) continue;
            near.clear();
            for (int dy = -r; dy <= r; ++dy)
                for (int dx = -r; dx <= r; ++dx)
                    if (g.inside(cx + dx, cy + dy) && !std::isnan(elevation[g.index(cx + dx, cy + dy)]))
                        near.push_back(elevation[g.index(cx + dx, cy + dy)]);
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
            if (blocked) cls[i] = float(ColumnClass::Obstacle), cost[i] = 100, clearance[i] = std::max(0.0f, lowest - ref);
        }
    if (o.fillGaps && rayFree) fillGaps(g, o, columnKey, obstacles, rayFree);
    return g;
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
