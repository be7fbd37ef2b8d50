// The 2.5D layers and the costmap of gseg::map::TraversabilityMap on simulated drives with exact
// answers (tests/support/lidar_sim: ground and obstacle points split by the simulator's truth,
// so these test the map, not the segmenter), the costmap read back by MRPT, and the ScanUpdate's
// ground cells through its byte form.
#include <gseg/io/ros_map.hpp>
#include <gseg/map/layer_file.hpp>
#include <gseg/io/bytes.hpp>
#include <gseg/map/scan_update.hpp>
#include <gseg/map/terrain_layers.hpp>
#include <gseg/map/traversability_map.hpp>

#include <support/child.hpp>
#include <support/lidar_sim.hpp>

#include <mrpt/maps/COccupancyGridMap2D.h>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <vector>

namespace {

using gseg::map::LayerGrid;
using gseg::map::TraversabilityMap;
using gseg::map::TraversabilityOptions;
using gseg::test::Box;
using gseg::test::Lidar;
using gseg::test::Scene;
using gseg::test::Truth;

constexpr double kSensorHeight = 1.8;  ///< [m] above the ground under the sensor
constexpr double kPi = 3.14159265358979323846;

using gseg::test::World;

/// Sensor positions along x at `step` metres from x0, kSensorHeight above the ground.
std::vector<Eigen::Vector3d> straightDrive(const World& w, double x0, int scans, double step) {
    std::vector<Eigen::Vector3d> s;
    for (int k = 0; k < scans; ++k) {
        const double x = x0 + step * k;
        s.emplace_back(x, 0.0, w.ground(x, 0.0) + kSensorHeight);
    }
    return s;
}

/// Drives through the world and builds the map from the simulator's exact ground / obstacle split.
TraversabilityMap drive(const World& w, const std::vector<Eigen::Vector3d>& sensors, const TraversabilityOptions& o = {},
                        Lidar lidar = Lidar::hdl64()) {
    TraversabilityMap map(o);
    lidar.maxRange = 40;
    for (std::size_t k = 0; k < sensors.size(); ++k) {
        const Eigen::Vector3d s = sensors[k];
        lidar.seed = 7 + std::uint32_t(k);
        const gseg::test::SimScan scan = gseg::test::simulateInWorld(w, int(k), s.x(), s.y(), s.z(), lidar);
        std::vector<float> ground, obstacles;
        for (std::size_t i = 0; i < scan.size(); ++i) {
            auto& to = scan.truth[i] == Truth::Ground ? ground : obstacles;
            for (int a = 0; a < 3; ++a) to.push_back(scan.xyz[3 * i + a]);
        }
        map.insertScan(gseg::PointCloudView(ground.data(), ground.size() / 3),
                       gseg::PointCloudView(obstacles.data(), obstacles.size() / 3), s);
    }
    return map;
}

/// Value of a layer at the cell holding world (x, y); NaN outside the grid.
float at(const LayerGrid& g, const std::string& layer, double x, double y) {
    const long long cx = g.cellX(x), cy = g.cellY(y);
    if (!g.inside(cx, cy)) return std::nanf("");
    return g.layer(layer).values[g.index(int(cx), int(cy))];
}

constexpr float kTraversable = 1, kBlocked = 2;

/// Small cubes filling `fraction` of the volume [lo, hi] at random (a seeded generator): foliage.
std::vector<Box> porousVolume(const double lo[3], const double hi[3], double cube, double fraction, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double volume = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    const int n = int(fraction * volume / (cube * cube * cube));
    std::vector<Box> out;
    for (int i = 0; i < n; ++i) {
        Box b;
        for (int a = 0; a < 3; ++a) {
            b.lo[a] = lo[a] + u(rng) * (hi[a] - lo[a] - cube);
            b.hi[a] = b.lo[a] + cube;
        }
        out.push_back(b);
    }
    return out;
}

TEST(TerrainLayers, RampsOfTenAndTwentyDegreesHaveTheirSlope) {
    for (const double degrees : {10.0, 20.0}) {
        World w;
        const double t = std::tan(degrees * kPi / 180.0);
        w.ground = [t](double x, double) { return x > 8.0 ? (x - 8.0) * t : 0.0; };
        const LayerGrid g = drive(w, straightDrive(w, 0.0, 6, 0.5)).layers();
        int checked = 0;
        for (double x = 9.1; x < 12.0; x += 0.2)
            for (double y = -1.9; y < 2.0; y += 0.2) {
                const float s = at(g, "slope", x, y);
                if (std::isnan(s)) continue;
                ++checked;
                EXPECT_NEAR(s, degrees, 1.0) << degrees << " deg ramp at (" << x << ", " << y << ")";
                if (degrees == 10.0) {
                    EXPECT_EQ(at(g, "class", x, y), kTraversable) << x << ", " << y;
                }
            }
        EXPECT_GT(checked, 100) << degrees;
        EXPECT_NEAR(at(g, "slope", 4.1, 1.1), 0.0, 1.0);  // the flat part
    }
}

/// A 15 deg ramp rising along x from x = 8 m, each 0.2 m cell of it raised or lowered by up to 4 cm
/// (uniform, from a hash of the cell: a rough track, the same in every scan).
World roughRamp() {
    World w;
    w.ground = [](double x, double y) {
        std::uint64_t h = std::uint64_t(std::int64_t(std::floor(x / 0.2))) * 0x9E3779B97F4A7C15ULL ^
                          (std::uint64_t(std::int64_t(std::floor(y / 0.2))) + 0x632BE59BD9B4E019ULL) * 0xC2B2AE3D27D4EB4FULL;
        h ^= h >> 29, h *= 0xBF58476D1CE4E5B9ULL, h ^= h >> 32;
        const double bump = 0.04 * (double(h >> 11) / double(1ULL << 53) * 2 - 1);
        return (x > 8.0 ? (x - 8.0) * std::tan(15.0 * kPi / 180.0) : 0.0) + bump;
    };
    return w;
}

TEST(TerrainLayers, RoughRampWithinTheSlopeLimitIsTraversableAtTheRobotsScale) {
    // The plane through 3 x 3 cells (0.6 m) of the rough 15 deg track tilts beyond 20 deg in places;
    // through the cells within slopeRadius (0.5 m) the bumps average out. With slopeRadius 0 (the
    // 3 x 3 plane alone, the rule before) those cells are blocked.
    const World w = roughRamp();
    const auto sensors = straightDrive(w, 0.0, 4, 0.5);
    TraversabilityOptions narrowOnly;
    narrowOnly.slopeRadius = 0;
    const LayerGrid g = drive(w, sensors).layers(), narrow = drive(w, sensors, narrowOnly).layers();
    int cells = 0, traversable = 0, narrowBlocked = 0;
    for (double x = 9.1; x < 14.0; x += 0.2)
        for (double y = -1.9; y < 2.0; y += 0.2) {
            if (std::isnan(at(g, "class", x, y))) continue;
            ++cells;
            traversable += at(g, "class", x, y) == kTraversable;
            if (at(narrow, "class", x, y) == kBlocked) {
                ++narrowBlocked;
                EXPECT_GT(at(narrow, "slope", x, y), 20.0f) << "blocked by its 3 x 3 slope alone at (" << x << ", " << y << ")";
                EXPECT_NEAR(at(g, "slope", x, y), 15.0, 4.0) << "judged over 0.5 m: the track's slope at (" << x << ", " << y << ")";
            } else {
                EXPECT_EQ(at(g, "slope", x, y), at(narrow, "slope", x, y)) << "judged again only where the 3 x 3 plane is too steep";
            }
        }
    ASSERT_GT(cells, 300);
    EXPECT_GT(narrowBlocked, 3) << "the bumps must tilt some 3 x 3 planes beyond 20 deg, or this tests nothing";
    EXPECT_EQ(traversable, cells) << cells - traversable << " of " << cells << " cells of the 15 deg track blocked";
}

TEST(TerrainLayers, NextToAnObstacleTheSlopeIsJudgedOverThreeByThreeCells) {
    // The rough track with a post (0.2 m square, 1.5 m high) on it: within slopeRadius of the post's
    // voxels every cell keeps its 3 x 3 plane's slope (beside a bush or a wall's foot the ground the
    // segmenter leaves is not judged at a wider scale); away from it some cells are judged again.
    World w = roughRamp();
    Box post;
    post.lo[0] = 11.0, post.lo[1] = 0.4, post.hi[0] = 11.2, post.hi[1] = 0.6;
    post.lo[2] = w.ground(11.1, 0.5) - 0.1, post.hi[2] = w.ground(11.1, 0.5) + 1.5;
    w.boxes.push_back(post);
    const auto sensors = straightDrive(w, 0.0, 4, 0.5);
    TraversabilityOptions narrowOnly;
    narrowOnly.slopeRadius = 0;
    const LayerGrid g = drive(w, sensors).layers(), narrow = drive(w, sensors, narrowOnly).layers();
    int near = 0, widenedAway = 0;
    for (double x = 9.1; x < 14.0; x += 0.2)
        for (double y = -1.9; y < 2.0; y += 0.2) {
            const float s = at(g, "slope", x, y), s3 = at(narrow, "slope", x, y);
            if (std::isnan(s)) continue;
            if (std::hypot(x - 11.1, y - 0.5) < 0.55) {
                ++near;
                EXPECT_EQ(s, s3) << "beside the post at (" << x << ", " << y << ")";
            } else {
                widenedAway += s < s3;
            }
        }
    EXPECT_GT(near, 3);
    EXPECT_GT(widenedAway, 3);
}

TEST(TerrainLayers, KerbOfFifteenCentimetresIsAStepOfFifteen) {
    World w;
    w.ground = [](double x, double) { return x >= 10.0 ? 0.15 : 0.0; };  // on a cell boundary (0.2 m cells)
    const LayerGrid g = drive(w, straightDrive(w, 0.0, 6, 0.5)).layers();
    int checked = 0;
    for (double y = -1.9; y < 2.0; y += 0.2) {
        const float below = at(g, "step", 9.9, y), above = at(g, "step", 10.1, y);
        if (std::isnan(below) || std::isnan(above)) continue;
        ++checked;
        EXPECT_NEAR(below, 0.15, 0.03) << y;
        EXPECT_NEAR(above, 0.15, 0.03) << y;
        EXPECT_NEAR(at(g, "elevation", 10.5, y), 0.15, 0.01) << y;
        EXPECT_EQ(at(g, "class", 10.1, y), kTraversable) << "a car climbs a 15 cm kerb (maxStep 0.25 m), y " << y;
    }
    EXPECT_GT(checked, 15);
}

TEST(TerrainLayers, DitchHalfAMetreDeepCannotBeCrossed) {
    World w;
    w.ground = [](double x, double) { return x >= 12.0 && x < 14.0 ? -0.5 : 0.0; };
    const LayerGrid g = drive(w, straightDrive(w, 0.0, 6, 0.5)).layers();
    int crossings = 0;
    for (double y = -1.9; y < 2.0; y += 0.2) {
        bool blocked = false, seen = false;
        for (double x = 11.5; x < 14.6; x += 0.2) {
            blocked |= at(g, "class", x, y) == kBlocked;
            seen |= !std::isnan(at(g, "class", x, y));
        }
        if (!seen) continue;
        ++crossings;
        EXPECT_TRUE(blocked) << "a path across the ditch at y " << y;
        float step = 0;
        for (double x = 11.5; x < 14.6; x += 0.2)
            if (at(g, "step", x, y) > step) step = at(g, "step", x, y);
        EXPECT_GT(step, 0.25) << "the ditch's far wall (the bottom is hidden): beyond maxStep, y " << y;
    }
    EXPECT_GT(crossings, 15);
}

TEST(TerrainLayers, UnderACanopyFromTwoAndAHalfMetresIsTraversable) {
    World w;
    Box canopy;
    canopy.lo[0] = 10, canopy.lo[1] = -2, canopy.lo[2] = 2.5;
    canopy.hi[0] = 14, canopy.hi[1] = 2, canopy.hi[2] = 4.5;
    canopy.scatter = 0.3;
    w.boxes.push_back(canopy);
    Box trunk;
    trunk.lo[0] = 11.9, trunk.lo[1] = 2.5, trunk.lo[2] = 0;
    trunk.hi[0] = 12.1, trunk.hi[1] = 2.7, trunk.hi[2] = 2.5;
    w.boxes.push_back(trunk);
    const LayerGrid g = drive(w, straightDrive(w, 0.0, 6, 0.5), {}, Lidar::hdl32()).layers();  // up to +15 deg: sees the canopy
    int checked = 0, underSeenCanopy = 0;
    for (double x = 10.1; x < 13.6; x += 0.2)  // (the canopy's far edge, seen only through its scatter, left out)
        for (double y = -1.9; y < 2.0; y += 0.2) {
            if (std::isnan(at(g, "elevation", x, y))) continue;
            ++checked;
            EXPECT_EQ(at(g, "class", x, y), kTraversable) << x << ", " << y;
            const float c = at(g, "clearance", x, y);
            if (std::isinf(c)) continue;  // no canopy point above this cell (the beams' rings are sparse up there)
            ++underSeenCanopy;
            EXPECT_NEAR(c, 2.5, 0.2) << x << ", " << y;  // to the bottom of the 0.2 m voxel
        }
    EXPECT_GT(checked, 100);
    EXPECT_GT(underSeenCanopy, 50);
}

TEST(TerrainLayers, HedgeAndChainLinkFenceSeenThroughStayObstacles) {
    World w;
    // A chain-link fence along the road at y = 4: 3 cm wires every 10 cm, both ways, 1.5 m high.
    for (double x = 2.0; x < 30.0; x += 0.1) {
        Box b;
        b.lo[0] = x, b.lo[1] = 4.0, b.lo[2] = 0.0, b.hi[0] = x + 0.03, b.hi[1] = 4.03, b.hi[2] = 1.5;
        w.boxes.push_back(b);
    }
    for (double z = 0.05; z < 1.5; z += 0.1) {
        Box b;
        b.lo[0] = 2.0, b.lo[1] = 4.0, b.lo[2] = z, b.hi[0] = 30.0, b.hi[1] = 4.03, b.hi[2] = z + 0.03;
        w.boxes.push_back(b);
    }
    // A hedge at y in [-5, -4]: 8 cm leaf clusters filling a quarter of the volume, 1.2 m high.
    const double lo[3] = {2.0, -5.0, 0.0}, hi[3] = {30.0, -4.0, 1.2};
    for (const Box& b : porousVolume(lo, hi, 0.08, 0.25, 11)) w.boxes.push_back(b);
    const LayerGrid g = drive(w, straightDrive(w, 0.0, 16, 1.0)).layers();
    int fence = 0, hedge = 0;
    for (double x = 6.1; x < 24.0; x += 0.2) {
        bool fenceBlocked = false, hedgeBlocked = false;
        for (double y = 3.7; y < 4.4; y += 0.2) fenceBlocked |= at(g, "class", x, y) == kBlocked;
        for (double y = -5.1; y < -3.8; y += 0.2) hedgeBlocked |= at(g, "class", x, y) == kBlocked;
        fence += fenceBlocked, hedge += hedgeBlocked;
        EXPECT_TRUE(fenceBlocked) << "the fence at x " << x;
        EXPECT_TRUE(hedgeBlocked) << "the hedge at x " << x;
        for (double y = -3.3; y < 3.4; y += 0.2)
            if (!std::isnan(at(g, "class", x, y))) {
                EXPECT_EQ(at(g, "class", x, y), kTraversable) << "the road at " << x << ", " << y;
            }
    }
    EXPECT_GT(fence + hedge, 150);
    // Beyond the fence the ground was seen through it.
    EXPECT_FALSE(std::isnan(at(g, "elevation", 12.1, 5.1)));
}

TEST(TerrainLayers, CarThatDrivesAwayIsCleared) {
    World w;
    Box wall;  // far behind: rays at every height cross where the car stood
    wall.lo[0] = 30, wall.lo[1] = -10, wall.lo[2] = 0, wall.hi[0] = 31, wall.hi[1] = 10, wall.hi[2] = 4;
    w.boxes.push_back(wall);
    w.boxesOfScan = [](int k) {
        std::vector<Box> car;
        if (k >= 3) return car;
        Scene s;
        s.addCar(12.0, 1.0, 0.0);
        return s.boxes;
    };
    const auto sensors = straightDrive(w, 0.0, 24, 0.25);
    const LayerGrid g = drive(w, sensors).layers();
    int checked = 0;
    for (double x = 12.1; x < 16.4; x += 0.2)
        for (double y = 1.1; y < 2.8; y += 0.2) {
            const float c = at(g, "class", x, y);
            if (std::isnan(c)) continue;
            ++checked;
            EXPECT_EQ(c, kTraversable) << "where the car stood: " << x << ", " << y;
        }
    EXPECT_GT(checked, 40);
}

TEST(TerrainLayers, LongFlatRoadSeenAtGrazingAnglesStaysTraversable) {
    World w;
    const LayerGrid g = drive(w, straightDrive(w, 0.0, 30, 2.0)).layers();
    std::size_t known = 0;
    const auto& cls = g.layer("class").values;
    const auto& elevation = g.layer("elevation").values;
    for (std::size_t i = 0; i < cls.size(); ++i) {
        if (std::isnan(cls[i])) continue;
        ++known;
        ASSERT_EQ(cls[i], kTraversable) << "cell " << i << " at elevation " << elevation[i] << ", slope "
                                        << g.layer("slope").values[i] << ", step " << g.layer("step").values[i] << ", roughness "
                                        << g.layer("roughness").values[i] << ", clearance " << g.layer("clearance").values[i];
        ASSERT_NEAR(elevation[i], 0.0, 0.01);
    }
    EXPECT_GT(known, 20000u);
}

TEST(TerrainLayers, CostmapReadsBackInMrptCellForCell) {
    World w;
    w.ground = [](double x, double) { return x >= 12.0 && x < 14.0 ? -0.5 : 0.0; };
    Box box;
    box.lo[0] = 8, box.lo[1] = -3, box.lo[2] = 0, box.hi[0] = 9, box.hi[1] = -2, box.hi[2] = 1.5;
    w.boxes.push_back(box);
    const TraversabilityMap map = drive(w, straightDrive(w, 0.0, 4, 1.0));
    const std::string dir = gseg::test::freshDir("traversability_layers", "costmap").string();
    map.write(dir + "/d");
    const LayerGrid g = map.layers();
    const gseg::io::RosMap m = gseg::io::readRosMap(dir + "/d_costmap.yaml");
    ASSERT_EQ(m.width, g.width());
    ASSERT_EQ(m.height, g.height());
    mrpt::maps::COccupancyGridMap2D grid;
    ASSERT_TRUE(grid.loadFromROSMapServerYAML(dir + "/d_costmap.yaml"));
    ASSERT_EQ(int(grid.getSizeX()), g.width());
    ASSERT_EQ(int(grid.getSizeY()), g.height());
    EXPECT_NEAR(grid.getResolution(), g.resolution(), 1e-6);
    EXPECT_NEAR(grid.getXMin(), g.originX(), 1e-5);  // MRPT keeps floats
    EXPECT_NEAR(grid.getYMin(), g.originY(), 1e-5);
    std::size_t counts[3] = {0, 0, 0};
    const auto& cls = g.layer("class").values;
    for (int cy = 0; cy < g.height(); ++cy)
        for (int cx = 0; cx < g.width(); ++cx) {
            const float c = cls[g.index(cx, cy)];
            const float p = grid.getCell(cx, cy);  // MRPT: probability of free space
            const int k = c == kTraversable ? 1 : c == kBlocked ? 2 : 0;
            ++counts[k];
            if (k == 1) {
                EXPECT_GT(p, 0.9f) << cx << "," << cy;
            } else if (k == 2) {
                EXPECT_LT(p, 0.1f) << cx << "," << cy;
            } else {
                EXPECT_NEAR(p, 0.5f, 0.05f) << cx << "," << cy;
            }
        }
    EXPECT_GT(counts[1], 1000u);
    EXPECT_GT(counts[2], 20u);
    EXPECT_GT(counts[0], 10u);
    // The GeoTIFF holds the same layers.
    const LayerGrid back = gseg::map::readLayersGeoTiff(dir + "/d_layers.tif");
    ASSERT_EQ(back.layers().size(), gseg::map::terrainLayerNames().size());
    for (std::size_t i = 0; i < back.layers().size(); ++i) {
        EXPECT_EQ(back.layers()[i].name, gseg::map::terrainLayerNames()[i]);
        const auto& a = back.layers()[i].values;
        const auto& b = g.layer(back.layers()[i].name).values;
        ASSERT_EQ(a.size(), b.size());
        for (std::size_t k = 0; k < a.size(); ++k)
            ASSERT_TRUE((std::isnan(a[k]) && std::isnan(b[k])) || a[k] == b[k]) << back.layers()[i].name << " cell " << k;
    }
}

/// A scan update as the versions before "GSU4" wrote it (free voxels as codes): 1 without the ground
/// cells and terrain samples, 2 without the terrain samples, 3 with both.
std::string olderScanUpdateBytes(const gseg::map::ScanUpdate& u, int version) {
    gseg::io::ByteWriter out;
    out.raw(("GSU" + std::to_string(version)).c_str(), 4);
    for (int a = 0; a < 3; ++a) out.f64(u.origin[a]);
    for (std::uint64_t v : {u.groundPoints, u.obstaclePoints, u.rays, u.pointsSkipped}) out.varint(v);
    const std::vector<std::uint64_t> free = u.free.codes();
    for (const auto* list : {&free, &u.groundHits, &u.obstacleHits}) {
        out.varint(list->size());
        std::uint64_t prev = 0;
        for (std::uint64_t c : *list) out.varint(c - prev), prev = c;
    }
    if (version >= 2) {
        out.varint(u.groundCells.size());
        std::uint64_t prev = 0;
        for (const auto& c : u.groundCells) {
            out.varint(c.cell - prev), prev = c.cell;
            out.varint(c.count).f64(c.sumZ).f64(c.sumZ2).f64(c.sumX).f64(c.sumY).f32(c.minZ).f32(c.maxZ);
        }
    }
    if (version >= 3) {
        out.varint(u.terrain.size());
        for (const auto& t : u.terrain)
            out.u64((std::uint64_t(std::uint32_t(t.ix)) << 32) | std::uint32_t(t.iy)).varint(t.groundCount).f64(t.groundSumZ).f32(t.lowZ).f32(t.highZ);
    }
    return out.take();
}

TEST(TerrainLayers, ScanUpdateCarriesGroundCellsThroughItsBytes) {
    const std::vector<float> ground = {1.01f, 2.05f, -0.02f, 1.07f, 2.11f, 0.02f, 5.5f, -3.3f, 0.3f},
                             obstacles = {4.0f, 0.5f, 1.0f};
    TraversabilityOptions o;
    const gseg::map::ScanUpdate u = gseg::map::castScan(gseg::PointCloudView(ground.data(), 3),
                                                        gseg::PointCloudView(obstacles.data(), 1), Eigen::Vector3d(0, 0, 1.8), o);
    ASSERT_EQ(u.groundCells.size(), 2u);  // two points share the cell (1.0-1.2, 2.0-2.2)
    const auto& shared = u.groundCells[0].count == 2 ? u.groundCells[0] : u.groundCells[1];
    EXPECT_EQ(shared.count, 2u);
    EXPECT_NEAR(shared.sumZ, -0.02 + 0.02, 1e-6);
    EXPECT_FLOAT_EQ(shared.minZ, -0.02f);
    EXPECT_FLOAT_EQ(shared.maxZ, 0.02f);
    const std::string bytes = gseg::map::serializeScanUpdate(u);
    EXPECT_EQ(bytes.substr(0, 4), "GSU4");
    EXPECT_TRUE(gseg::map::deserializeScanUpdate(bytes) == u);
    EXPECT_FALSE(u.terrain.empty());  // the terrain model's samples (#31) travel too
    EXPECT_GT(u.free.voxels(), 100u);
    // Versions 3 (free voxels as codes), 2 (no terrain samples) and 1 (no ground cells either) are
    // still read; a cut list is refused.
    EXPECT_TRUE(gseg::map::deserializeScanUpdate(olderScanUpdateBytes(u, 3)) == u);
    gseg::map::ScanUpdate v2 = u;
    v2.terrain.clear();
    EXPECT_TRUE(gseg::map::deserializeScanUpdate(olderScanUpdateBytes(u, 2)) == v2);
    gseg::map::ScanUpdate v1 = v2;
    v1.groundCells.clear();
    EXPECT_TRUE(gseg::map::deserializeScanUpdate(olderScanUpdateBytes(u, 1)) == v1);
    EXPECT_THROW(gseg::map::deserializeScanUpdate(bytes.substr(0, bytes.size() - 3)), std::runtime_error);
}

TEST(TerrainLayers, RobotLimitsAreValidated) {
    TraversabilityOptions o;
    o.maxGroundRise = 0.3;  // below 1 m x tan(20 deg): a ramp within the slope limit would be refused
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o = {};
    o.obstacleClearProbability = 0.6;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o = {};
    o.maxSlope = 95;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o = {};
    o.slopeRadius = -0.1;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o.slopeRadius = 0;  // the 3 x 3 plane alone
    EXPECT_NO_THROW(o.validate());
    o.resolution = 0.01, o.slopeRadius = 1;  // a disc of 100 cells' radius
    EXPECT_THROW(o.validate(), std::invalid_argument);
    o = {};
    o.set("maxStep", "0.1");
    EXPECT_EQ(o.maxStep, 0.1);
    EXPECT_EQ(TraversabilityOptions::describe("maxSlope").first, "deg");
}

}  // namespace
