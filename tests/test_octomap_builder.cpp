// TraversabilityMap on a simulated drive with exact poses and exact labels: a flat road that
// turns into a 10 % ramp, a box, a wall, and a car that leaves after the first scans.
#include <gseg/map/traversability_map.hpp>
#include <support/lidar_sim.hpp>

#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>
#include <mrpt/math/CMatrixF.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <filesystem>
#include <unistd.h>

namespace {

using gseg::map::CellClass;
using gseg::map::TraversabilityMap;
using gseg::test::Truth;

constexpr double kRoadZ = 0.1;       // [m] flat road height (a voxel centre at 0.2 m)
constexpr double kRampX = 20.0;      // [m] the ramp starts here
constexpr double kRampDeg = 5.7106;  // atan(0.1): 10 % grade
constexpr double kSensorHeight = 1.8;

double roadZ(double x) { return x < kRampX ? kRoadZ : kRoadZ + 0.1 * (x - kRampX); }

/// A world-frame box.
struct WorldBox {
    double lo[3], hi[3];
};
const WorldBox kBox{{10.0, -4.0, kRoadZ}, {11.0, -3.0, kRoadZ + 1.5}};   // static, left of the road
const WorldBox kWall{{0.0, -8.2, kRoadZ}, {40.0, -8.0, kRoadZ + 3.0}};   // along the road
const WorldBox kCar{{14.0, 2.5, kRoadZ + 0.2}, {16.0, 4.0, kRoadZ + 1.6}};  // leaves after scan 2

/// The scene seen from a sensor at `o` (the simulator puts the sensor at its origin).
gseg::test::Scene sceneFrom(const Eigen::Vector3d& o, bool withCar) {
    gseg::test::Scene s;
    s.addRamp(o.z() - kRoadZ, kRampX - o.x(), kRampDeg, Truth::Ground);
    auto add = [&](const WorldBox& b) {
        s.addBox(b.lo[0] - o.x(), b.lo[1] - o.y(), b.lo[2] - o.z(), b.hi[0] - o.x(), b.hi[1] - o.y(), b.hi[2] - o.z());
    };
    add(kBox);
    add(kWall);
    if (withCar) add(kCar);
    return s;
}

gseg::test::Lidar lidar() {
    gseg::test::Lidar l;
    l.beams = 32, l.minElevationDeg = -25, l.maxElevationDeg = 5, l.azimuthStepDeg = 0.5, l.maxRange = 40;
    l.noiseSigma = 0.005;
    return l;
}

/// Drives from x = 0 to x = 30 in 2 m steps; the car is there for the first 3 scans.
TraversabilityMap drive() {
    TraversabilityMap map;
    for (int k = 0; k <= 15; ++k) {
        const double x = 2.0 * k;
        const Eigen::Vector3d origin(x, 0.0, roadZ(x) + kSensorHeight);
        const auto scan = gseg::test::simulate(sceneFrom(origin, k < 3), lidar());
        std::vector<float> ground, obstacles;
        for (std::size_t i = 0; i < scan.size(); ++i) {
            auto& out = scan.truth[i] == Truth::Ground ? ground : obstacles;
            for (int a = 0; a < 3; ++a) out.push_back(scan.xyz[3 * i + std::size_t(a)] + float(origin[a]));
        }
        map.insertScan(gseg::PointCloudView(ground.data(), ground.size() / 3),
                       gseg::PointCloudView(obstacles.data(), obstacles.size() / 3), origin);
    }
    return map;
}

const TraversabilityMap& theDrive() {
    static const TraversabilityMap map = drive();
    return map;
}

bool occupied(const octomap::OcTree& t, double x, double y, double z) {
    const auto* n = t.search(x, y, z);
    return n && t.isNodeOccupied(n);
}
bool knownFree(const octomap::OcTree& t, double x, double y, double z) {
    const auto* n = t.search(x, y, z);
    return n && !t.isNodeOccupied(n);
}

TEST(OctomapBuilder, RoadVoxelsAreGroundOnFlatAndRamp) {
    const auto& m = theDrive();
    for (double x : {4.0, 9.0, 17.0, 24.0, 28.0, 32.0}) {
        for (double y : {-2.0, 0.5, 2.0}) {
            SCOPED_TRACE("x " + std::to_string(x) + " y " + std::to_string(y));
            EXPECT_TRUE(occupied(m.groundTree(), x, y, roadZ(x))) << "road voxel not ground";
            EXPECT_FALSE(occupied(m.obstacleTree(), x, y, roadZ(x))) << "road voxel marked obstacle";
            EXPECT_FALSE(occupied(m.groundTree(), x, y, roadZ(x) + 1.0)) << "ground 1 m above the road";
        }
    }
}

TEST(OctomapBuilder, BoxAndWallAreObstacles) {
    const auto& m = theDrive();
    // Faces seen from the road: the box's +y face and the wall's +y face.
    EXPECT_TRUE(occupied(m.obstacleTree(), 10.5, -3.1, 0.9));
    for (double x : {5.0, 15.0, 25.0}) EXPECT_TRUE(occupied(m.obstacleTree(), x, -8.1, 1.5)) << "wall at x " << x;
    EXPECT_FALSE(occupied(m.groundTree(), 10.5, -3.1, 0.9));
}

TEST(OctomapBuilder, SpaceBetweenSensorAndHitsIsFree) {
    const auto& m = theDrive();
    // In front of the box and the wall, at sensor-ish height: crossed by many rays.
    EXPECT_TRUE(knownFree(m.obstacleTree(), 10.5, -1.5, 1.0));
    EXPECT_TRUE(knownFree(m.obstacleTree(), 15.0, -6.0, 1.5));
    EXPECT_TRUE(knownFree(m.groundTree(), 15.0, -6.0, 1.5));
}

TEST(OctomapBuilder, CarThatDroveAwayLeavesNoGhost) {
    const auto& m = theDrive();
    const auto s = m.stats();
    EXPECT_GT(s.clearedObstacleVoxels, 0u);
    for (double z : {0.5, 0.9, 1.3}) EXPECT_FALSE(occupied(m.obstacleTree(), 15.0, 2.6, z)) << "ghost at z " << z;
    EXPECT_EQ(m.topDown().at(15.0, 2.7), CellClass::Traversable);
}

TEST(OctomapBuilder, TopDownGridAndPngHaveTheExpectedClasses) {
    const auto& m = theDrive();
    const auto grid = m.topDown();
    struct Probe {
        double x, y;
        CellClass want;
    };
    const Probe probes[] = {{6.0, 1.5, CellClass::Traversable}, {26.0, -1.5, CellClass::Traversable},
                            {10.5, -3.1, CellClass::Obstacle},  {20.0, -8.1, CellClass::Obstacle},
                            {20.0, -20.0, CellClass::Unknown}};  // behind the wall: never seen
    for (const auto& p : probes) EXPECT_EQ(grid.at(p.x, p.y), p.want) << "at " << p.x << ", " << p.y;

    const std::string dir = std::filesystem::temp_directory_path() / ("gseg_builder_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const auto written = m.write(dir + "/drive");
    ASSERT_EQ(written.size(), 4u);
    mrpt::img::CImage png;
    ASSERT_TRUE(png.loadFromFile(dir + "/drive_traversability.png"));
    ASSERT_EQ(int(png.getWidth()), grid.width);
    ASSERT_EQ(int(png.getHeight()), grid.height);
    mrpt::math::CMatrixFloat R, G, B;  // [0, 1]
    png.getAsRGBMatrices(R, G, B);
    if (png.getChannelsOrder() == "BGR") std::swap(R, B);  // MRPT 2.5.8 hands back the stored order
    for (const auto& p : probes) {
        int c = 0, r = 0;
        ASSERT_TRUE(grid.toPixel(p.x, p.y, c, r));
        const auto want = gseg::map::colourOf(p.want);
        EXPECT_EQ(std::lround(255 * R(r, c)), want.r) << "pixel of " << p.x << ", " << p.y;
        EXPECT_EQ(std::lround(255 * G(r, c)), want.g);
        EXPECT_EQ(std::lround(255 * B(r, c)), want.b);
    }
    // The files read back with liboctomap.
    octomap::OcTree ground(dir + "/drive_ground.bt");
    EXPECT_TRUE(occupied(ground, 9.0, 0.5, roadZ(9.0)));
    std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(dir + "/drive_traversability.ot"));
    auto* colour = dynamic_cast<octomap::ColorOcTree*>(any.get());
    ASSERT_NE(colour, nullptr);
    const auto* node = colour->search(10.5, -3.1, 0.9);
    ASSERT_NE(node, nullptr);
    EXPECT_EQ(node->getColor().r, gseg::map::colourOf(CellClass::Obstacle).r);
    std::filesystem::remove_all(dir);
}

TEST(OctomapBuilder, GroundNeverOverwritesAnObstacle) {
    // Same voxel: obstacle hits in scan 1, ground hits in scan 2 from the same place.
    TraversabilityMap m;
    const float obstacle[3] = {5.1f, 0.1f, 0.1f}, ground[3] = {5.1f, 0.1f, 0.1f};
    m.insertScan(gseg::PointCloudView(), gseg::PointCloudView(obstacle, 1), Eigen::Vector3d(0, 0, 1.8));
    m.insertScan(gseg::PointCloudView(ground, 1), gseg::PointCloudView(), Eigen::Vector3d(0, 0, 1.8));
    EXPECT_TRUE(occupied(m.obstacleTree(), 5.1, 0.1, 0.1));
    EXPECT_EQ(m.topDown().at(5.1, 0.1), CellClass::Obstacle);
    EXPECT_EQ(m.stats().groundUnderObstacle, 1u);
}

TEST(OctomapBuilder, InvalidOptionsAndEmptyMapAreErrors) {
    gseg::map::TraversabilityOptions o;
    o.resolution = 0;
    EXPECT_THROW(TraversabilityMap{o}, std::invalid_argument);
    o = {};
    o.probMiss = 0.6;
    EXPECT_THROW(TraversabilityMap{o}, std::invalid_argument);
    TraversabilityMap m;
    EXPECT_THROW(m.write("/tmp/never"), std::logic_error);
    EXPECT_THROW(m.insertScan({}, {}, Eigen::Vector3d(NAN, 0, 0)), std::invalid_argument);
}

}  // namespace
