// TraversabilityMap on a simulated drive with exact poses and exact labels: a flat road that
// turns into a 10 % ramp, a box, a wall, and a car that leaves after the first scans.
#include <gseg/io/ply.hpp>
#include <gseg/io/atomic_file.hpp>
#include <gseg/io/bytes.hpp>
#include <gseg/map/scan_update.hpp>
#include <gseg/map/map_colours.hpp>
#include <gseg/map/top_down_picture.hpp>
#include <gseg/map/traversability_map.hpp>
#include <gseg/map/world_scan.hpp>
#include <support/child.hpp>
#include <support/lidar_sim.hpp>
#include <support/map_files.hpp>
#include <support/scenes.hpp>
#include <support/paths.hpp>

#include "voxel_keys.hpp"

#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/math/CMatrixF.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/opengl/COctoMapVoxels.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/poses/CPose3D.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <unistd.h>

namespace {

/// `<build>/tests/octomap_builder/<name>`, emptied and created.
std::string tempDir(const std::string& name) { return gseg::test::freshDir("octomap_builder", name).string(); }

using gseg::map::ColumnClass;
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

/// One scan of the drive in the world frame: ground and obstacle x, y, z triples and the origin.
struct DriveScan {
    std::vector<float> ground, obstacles;
    Eigen::Vector3d origin;
    gseg::PointCloudView groundView() const { return gseg::PointCloudView(ground.data(), ground.size() / 3); }
    gseg::PointCloudView obstaclesView() const { return gseg::PointCloudView(obstacles.data(), obstacles.size() / 3); }
};

/// Drives from x = 0 to x = 30 in 2 m steps; the car is there for the first 3 scans.
std::vector<DriveScan> driveScans() {
    std::vector<DriveScan> out;
    for (int k = 0; k <= 15; ++k) {
        DriveScan d;
        const double x = 2.0 * k;
        d.origin = Eigen::Vector3d(x, 0.0, roadZ(x) + kSensorHeight);
        const auto scan = gseg::test::simulate(sceneFrom(d.origin, k < 3), lidar());
        for (std::size_t i = 0; i < scan.size(); ++i) {
            auto& pts = scan.truth[i] == Truth::Ground ? d.ground : d.obstacles;
            for (int a = 0; a < 3; ++a) pts.push_back(scan.xyz[3 * i + std::size_t(a)] + float(d.origin[a]));
        }
        out.push_back(std::move(d));
    }
    return out;
}

const std::vector<DriveScan>& theScans() {
    static const std::vector<DriveScan> scans = driveScans();
    return scans;
}

TraversabilityMap drive(const gseg::map::TraversabilityOptions& options = {}) {
    TraversabilityMap map(options);
    for (const auto& d : theScans()) map.insertScan(d.groundView(), d.obstaclesView(), d.origin);
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
    EXPECT_EQ(m.topDown().at(15.0, 2.7), ColumnClass::Traversable);
}

TEST(OctomapBuilder, TopDownGridAndPngHaveTheExpectedClasses) {
    const auto& m = theDrive();
    const auto grid = m.topDown();
    struct Probe {
        double x, y;
        ColumnClass want;
    };
    const Probe probes[] = {{6.0, 1.5, ColumnClass::Traversable}, {26.0, -1.5, ColumnClass::Traversable},
                            {10.5, -3.1, ColumnClass::Obstacle},  {20.0, -8.1, ColumnClass::Obstacle},
                            {20.0, -20.0, ColumnClass::Unknown}};  // behind the wall: never seen
    for (const auto& p : probes) EXPECT_EQ(grid.at(p.x, p.y), p.want) << "at " << p.x << ", " << p.y;

    const std::string dir = tempDir("drive");
    const auto written = m.write(dir + "/drive");
    ASSERT_EQ(written, TraversabilityMap::outputPaths(dir + "/drive"));
    ASSERT_EQ(written.size(), gseg::map::TraversabilityMap::outputPaths("x").size());
    ASSERT_EQ(written.size(), 17u);
    mrpt::img::CImage png;
    ASSERT_TRUE(png.loadFromFile(dir + "/drive_traversability.png"));
    const auto layout = gseg::map::pictureLayout(grid, m.path());
    ASSERT_EQ(layout.cellsPerPixel, 1);
    ASSERT_EQ(int(png.getWidth()), layout.width);
    ASSERT_EQ(int(png.getHeight()), layout.height);
    mrpt::math::CMatrixFloat R, G, B;  // [0, 1]
    png.getAsRGBMatrices(R, G, B);
    if (png.getChannelsOrder() == "BGR") std::swap(R, B);  // MRPT 2.5.8 hands back the stored order
    for (const auto& p : probes) {
        int c = 0, r = 0;
        ASSERT_TRUE(layout.toPixel(p.x, p.y, c, r));
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
    EXPECT_EQ(node->getColor().r, gseg::map::colourOf(ColumnClass::Obstacle).r);
    std::filesystem::remove_all(dir);
}

TEST(OctomapBuilder, PictureHasXRightYUpAndUnknownApartFromThePage) {
    // The costmap PGM's convention (map_server, RViz): world x to the right, y up (smaller rows).
    const auto& m = theDrive();
    const auto grid = m.topDown();
    const auto l = gseg::map::pictureLayout(grid, m.path());
    int c5 = 0, r5 = 0, c25 = 0, r25 = 0, cLeft = 0, rLeft = 0, cRight = 0, rRight = 0;
    ASSERT_TRUE(l.toPixel(5, 0, c5, r5) && l.toPixel(25, 0, c25, r25));
    ASSERT_TRUE(l.toPixel(10, 3, cLeft, rLeft) && l.toPixel(10, -3, cRight, rRight));
    EXPECT_GT(c25, c5);          // further along x: further right
    EXPECT_EQ(r25, r5);
    EXPECT_LT(rLeft, rRight);    // +y: higher up
    EXPECT_EQ(cLeft, cRight);
    EXPECT_NEAR(double(c25 - c5), 20.0 * l.pixelsPerMetre(), l.pixelsPerCell);
    // The map sits inside the page, between a title band and a legend band.
    EXPECT_GT(l.mapTop, 40);
    EXPECT_GT(l.height - (l.mapTop + l.mapHeight), 100);
    const auto unknown = gseg::map::colourOf(ColumnClass::Unknown), page = gseg::map::backgroundColour();
    EXPECT_GT(std::abs(int(unknown.r) - int(page.r)) + std::abs(int(unknown.g) - int(page.g)) + std::abs(int(unknown.b) - int(page.b)), 100);
    const std::string dir = tempDir("orient");
    m.write(dir + "/o");
    mrpt::img::CImage png;
    ASSERT_TRUE(png.loadFromFile(dir + "/o_traversability.png"));
    mrpt::math::CMatrixFloat R, G, B;
    png.getAsRGBMatrices(R, G, B);
    if (png.getChannelsOrder() == "BGR") std::swap(R, B);
    auto is = [&](int row, int col, gseg::map::Rgb c) {
        return std::lround(255 * R(row, col)) == c.r && std::lround(255 * G(row, col)) == c.g && std::lround(255 * B(row, col)) == c.b;
    };
    EXPECT_TRUE(is(l.mapTop - 2, l.mapLeft + l.mapWidth / 2, page));  // just above the map: the page
    // One map truth: the class layer's picture is the costmap PGM, cell for cell, unturned.
    EXPECT_TRUE(gseg::test::classPictureShowsCostmap(dir + "/o_layer_class.png", dir + "/o_costmap.pgm"));
    int c = 0, r = 0;
    ASSERT_TRUE(l.toPixel(20.0, -20.0, c, r));  // behind the wall: never seen
    EXPECT_TRUE(is(r, c, unknown));
    // The legend band names every colour of the map: each appears there as a swatch.
    for (const ColumnClass k : {ColumnClass::Traversable, ColumnClass::Obstacle, ColumnClass::Unknown}) {
        bool found = false;
        for (int row = l.mapTop + l.mapHeight + 1; row < l.height && !found; ++row)
            for (int col = 0; col < 40 && !found; ++col) found = is(row, col, gseg::map::colourOf(k));
        EXPECT_TRUE(found) << "no legend swatch for class " << int(k);
    }
    std::filesystem::remove_all(dir);
}

TEST(OctomapBuilder, PlyAndSceneHoldTheOccupiedVoxelsAndThePath) {
    const auto& m = theDrive();
    const std::string dir = tempDir("views");
    m.write(dir + "/v");
    const auto s = m.stats();
    const std::size_t shown = s.groundVoxels - s.groundUnderObstacle + s.obstacleVoxels;
    // PLY: one vertex per occupied voxel, label 1 ground / 0 obstacle, at the voxel centres.
    const std::vector<float> xyz = gseg::io::readPly(dir + "/v_traversability.ply");
    const std::vector<double> label = gseg::io::readPlyProperty(dir + "/v_traversability.ply", "label");
    const std::vector<double> red = gseg::io::readPlyProperty(dir + "/v_traversability.ply", "red");
    ASSERT_EQ(label.size(), shown);
    ASSERT_EQ(xyz.size(), 4 * shown);
    std::size_t ground = 0;
    for (std::size_t i = 0; i < label.size(); ++i) {
        const double x = xyz[4 * i], y = xyz[4 * i + 1], z = xyz[4 * i + 2];
        ground += label[i] == 1;
        ASSERT_TRUE(label[i] == 0 || label[i] == 1);
        EXPECT_EQ(red[i], label[i] == 1 ? gseg::map::colourOf(ColumnClass::Traversable).r : gseg::map::colourOf(ColumnClass::Obstacle).r);
        EXPECT_TRUE(occupied(label[i] == 1 ? m.groundTree() : m.obstacleTree(), x, y, z)) << x << " " << y << " " << z;
    }
    EXPECT_EQ(ground, s.groundVoxels - s.groundUnderObstacle);
    // .3Dscene: MRPT's loader reads it; the same voxels as boxes, and the path as a line.
    mrpt::opengl::COpenGLScene scene;
    ASSERT_TRUE(scene.loadFromFile(dir + "/v_traversability.3Dscene"));
    const auto voxels = scene.getByClass<mrpt::opengl::COctoMapVoxels>();
    ASSERT_TRUE(voxels);
    ASSERT_EQ(voxels->getVoxelSetCount(), 2u);
    EXPECT_EQ(voxels->getVoxelCount(0), ground);
    EXPECT_EQ(voxels->getVoxelCount(1), shown - ground);
    const auto path = scene.getByClass<mrpt::opengl::CSetOfLines>();
    ASSERT_TRUE(path);
    ASSERT_EQ(path->getLineCount(), m.path().size() - 1);
    double x0, y0, z0, x1, y1, z1;
    path->getLineByIndex(0, x0, y0, z0, x1, y1, z1);
    EXPECT_NEAR(x0, m.path()[0].x(), 1e-6);
    EXPECT_NEAR(x1, m.path()[1].x(), 1e-6);
    std::filesystem::remove_all(dir);
}

TEST(OctomapBuilder, GroundNeverOverwritesAnObstacle) {
    // Same voxel: obstacle hits in scan 1, ground hits in scan 2 from the same place.
    TraversabilityMap m;
    const float obstacle[3] = {5.1f, 0.1f, 0.1f}, ground[3] = {5.1f, 0.1f, 0.1f};
    m.insertScan(gseg::PointCloudView(), gseg::PointCloudView(obstacle, 1), Eigen::Vector3d(0, 0, 1.8));
    m.insertScan(gseg::PointCloudView(ground, 1), gseg::PointCloudView(), Eigen::Vector3d(0, 0, 1.8));
    EXPECT_TRUE(occupied(m.obstacleTree(), 5.1, 0.1, 0.1));
    EXPECT_EQ(m.topDown().at(5.1, 0.1), ColumnClass::Obstacle);
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

/// The simple reference integration (the map layer before sorted batch updates): per scan, a
/// KeySet of the voxels OcTree::computeRayKeys() crosses, then one OcTree::updateNode() per voxel.
class ReferenceMap {
public:
    explicit ReferenceMap(const gseg::map::TraversabilityOptions& o) : o_(o), ground(o.resolution), obstacles(o.resolution) {
        for (octomap::OcTree* t : {&ground, &obstacles}) {
            t->setProbHit(o.probHit), t->setProbMiss(o.probMiss), t->setOccupancyThres(o.occupancyThreshold);
            t->setClampingThresMin(o.clampMin), t->setClampingThresMax(o.clampMax);
        }
    }

    void insert(const DriveScan& d) {
        const octomap::point3d origin(float(d.origin.x()), float(d.origin.y()), float(d.origin.z()));
        octomap::KeySet groundHits, obstacleHits, rayEnds, freeCells;
        std::vector<octomap::point3d> ends;
        auto collect = [&](const std::vector<float>& pts, octomap::KeySet& hits) {
            for (std::size_t i = 0; i + 2 < pts.size(); i += 3) {
                octomap::point3d p(pts[i], pts[i + 1], pts[i + 2]);
                const octomap::point3d dir = p - origin;
                const double range = dir.norm();
                if (range > o_.maxRange) p = origin + dir * float(o_.maxRange / range);
                octomap::OcTreeKey key;
                if (!ground.coordToKeyChecked(p, key)) continue;
                if (range <= o_.maxRange) hits.insert(key);
                if (rayEnds.insert(key).second) ends.push_back(p);
            }
        };
        collect(d.ground, groundHits);
        collect(d.obstacles, obstacleHits);
        octomap::KeyRay ray;
        for (const auto& end : ends) {
            ground.computeRayKeys(origin, end, ray);
            for (const auto& k : ray)
                if (!groundHits.count(k) && !obstacleHits.count(k)) freeCells.insert(k);
        }
        for (const auto& k : freeCells) {
            const octomap::OcTreeNode* g = ground.search(k);
            if (!(g && ground.isNodeOccupied(g))) ground.updateNode(k, false, true);
            obstacles.updateNode(k, false, true);
        }
        for (const auto& k : groundHits) ground.updateNode(k, true, true);
        for (const auto& k : obstacleHits) obstacles.updateNode(k, true, true);
        ground.updateInnerOccupancy();
        obstacles.updateInnerOccupancy();
    }

    gseg::map::TraversabilityOptions o_;
    octomap::OcTree ground, obstacles;
};

/// Every voxel of `reference` (unpruned) has exactly the same log-odds in `fast`, and `fast` has
/// no other voxel.
void expectSameVoxels(const octomap::OcTree& reference, const octomap::OcTree& fast, const char* what) {
    std::size_t voxels = 0, differ = 0;
    for (auto it = reference.begin_leafs(); it != reference.end_leafs(); ++it, ++voxels) {
        ASSERT_EQ(it.getDepth(), 16u) << what;
        const octomap::OcTreeNode* n = fast.search(it.getKey());
        if (!n || n->getLogOdds() != it->getLogOdds()) ++differ;
    }
    std::size_t fastVoxels = 0;
    for (auto it = fast.begin_leafs(); it != fast.end_leafs(); ++it) fastVoxels += std::size_t(1) << (3 * (16 - it.getDepth()));
    EXPECT_EQ(differ, 0u) << what << ": voxels with another value";
    EXPECT_EQ(fastVoxels, voxels) << what;
    EXPECT_GT(voxels, 10000u) << what;
}

std::string fileBytes(const std::string& path) { return gseg::test::readText(path); }

TEST(OctomapBuilder, FastPathEqualsASimpleReferenceIntegration) {
    gseg::map::TraversabilityOptions shortRays;  // rays cut at 12 m, voxels off the 0.2 m grid
    shortRays.resolution = 0.15, shortRays.maxRange = 12;
    for (const auto& o : {gseg::map::TraversabilityOptions(), shortRays}) {
        SCOPED_TRACE("resolution " + std::to_string(o.resolution) + ", maxRange " + std::to_string(o.maxRange));
        ReferenceMap ref(o);
        for (const auto& d : theScans()) ref.insert(d);
        const TraversabilityMap fast = drive(o);
        expectSameVoxels(ref.ground, fast.groundTree(), "ground");
        expectSameVoxels(ref.obstacles, fast.obstacleTree(), "obstacles");
        EXPECT_LT(double(fast.obstacleTree().size()), 0.8 * double(ref.obstacles.size())) << "pruning saves memory";
        // The .bt files are byte for byte what OctoMap writes for the reference trees.
        const std::string dir = tempDir("ref");
        fast.write(dir + "/fast");
        std::ostringstream groundBt, obstaclesBt;
        ref.ground.writeBinaryConst(groundBt);
        ref.obstacles.writeBinaryConst(obstaclesBt);
        EXPECT_TRUE(fileBytes(dir + "/fast_ground.bt") == groundBt.str());
        EXPECT_TRUE(fileBytes(dir + "/fast_obstacles.bt") == obstaclesBt.str());
        // The .ot is what ColorOcTree::write() writes for the coloured tree built voxel by voxel.
        std::ostringstream colouredOt;
        ASSERT_TRUE(fast.colouredTree()->write(colouredOt));
        EXPECT_GT(colouredOt.str().size(), 10000u);
        EXPECT_TRUE(fileBytes(dir + "/fast_traversability.ot") == colouredOt.str());
        std::filesystem::remove_all(dir);
    }
}

/// castScan()'s free voxels against OctoMap's own computeRayKeys() for the same rays: random
/// directions, rays along an axis or a diagonal (from a voxel's centre: ties between the axes), negative coordinates,
/// points beyond maxRange (cut there), and rays of more voxels than the caster walks at once
/// (4096: 1 cm voxels, 50 m rays).
TEST(OctomapBuilder, RayCastingGivesExactlyTheVoxelsOfComputeRayKeys) {
    std::mt19937 rng(35);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    for (const double resolution : {0.2, 0.15, 0.01}) {
        gseg::map::TraversabilityOptions o;
        o.resolution = resolution, o.maxRange = 50;
        SCOPED_TRACE("resolution " + std::to_string(resolution));
        const octomap::OcTree geometry(resolution);
        // Off the grid, at negative coordinates, and at a voxel's centre (diagonal rays tie there).
        const Eigen::Vector3d centre(geometry.keyToCoord(32770), geometry.keyToCoord(32765), geometry.keyToCoord(32778));
        // A few voxels from the extent's lower and upper ends (the caster's window around the
        // sensor then reaches past the ends of the key range; points beyond the extent are skipped).
        const Eigen::Vector3d low(geometry.keyToCoord(5) + 0.01, geometry.keyToCoord(9) - 0.02, geometry.keyToCoord(3) + 0.03);
        const Eigen::Vector3d high(geometry.keyToCoord(65530) + 0.01, geometry.keyToCoord(65528), geometry.keyToCoord(65533) - 0.03);
        for (const Eigen::Vector3d& origin : {Eigen::Vector3d(0.03, -0.07, 1.73), Eigen::Vector3d(-123.45, -0.2, -7.9), centre, low, high}) {
            const bool nearTheEnds = origin == low || origin == high;
            const octomap::point3d from(float(origin.x()), float(origin.y()), float(origin.z()));
            std::vector<float> pts;
            auto add = [&](float dx, float dy, float dz) { pts.insert(pts.end(), {from.x() + dx, from.y() + dy, from.z() + dz}); };
            for (int i = 0; i < (resolution < 0.1 ? 60 : 600); ++i) add(60 * u(rng), 60 * u(rng), 10 * u(rng));
            for (const float r : {3.3f, 49.9f, 70.f})  // along each axis, both ways, and the diagonals
                for (int sx = -1; sx <= 1; ++sx)
                    for (int sy = -1; sy <= 1; ++sy)
                        for (int sz = -1; sz <= 1; ++sz) add(r * float(sx), r * float(sy), r * float(sz));
            const gseg::map::ScanUpdate cast = gseg::map::castScan(gseg::PointCloudView(pts.data(), pts.size() / 3), {}, origin, o);
            // The reference: every ray as OctoMap casts it, one per endpoint voxel (its first point).
            octomap::KeySet ends, hits, free;
            octomap::KeyRay ray;
            std::size_t longest = 0;
            for (std::size_t i = 0; i < pts.size(); i += 3) {
                octomap::point3d p(pts[i], pts[i + 1], pts[i + 2]);
                const octomap::point3d d = p - from;
                const double range = d.norm();
                if (range > o.maxRange) p = from + d * float(o.maxRange / range);
                octomap::OcTreeKey key;
                if (nearTheEnds && !geometry.coordToKeyChecked(p, key)) continue;
                ASSERT_TRUE(geometry.coordToKeyChecked(p, key));
                if (range <= o.maxRange) hits.insert(key);
                if (!ends.insert(key).second) continue;
                ASSERT_TRUE(geometry.computeRayKeys(from, p, ray));
                longest = std::max(longest, ray.size());
                free.insert(ray.begin(), ray.end());
            }
            std::vector<std::uint64_t> expected;
            for (const octomap::OcTreeKey& k : free)
                if (!hits.count(k)) expected.push_back(gseg::map::detail::mortonCode(k));
            std::sort(expected.begin(), expected.end());
            EXPECT_EQ(cast.rays, ends.size());
            EXPECT_EQ(cast.free.voxels(), expected.size());
            EXPECT_TRUE(cast.free.codes() == expected) << "the free voxels differ from computeRayKeys()'s";
            EXPECT_TRUE(cast.free == gseg::map::VoxelBricks::fromCodes(expected));
            if (resolution < 0.1) {
                EXPECT_GT(longest, 4096u) << "rays longer than one batch of the caster";
            }
        }
    }
}

TEST(OctomapBuilder, ScanUpdatesAreValuesIndependentOfTheMap) {
    const gseg::map::TraversabilityOptions o;
    std::vector<std::string> bytes;
    for (const auto& d : theScans()) {
        const auto u = gseg::map::castScan(d.groundView(), d.obstaclesView(), d.origin, o);
        EXPECT_TRUE(std::is_sorted(u.free.bricks.begin(), u.free.bricks.end()));
        EXPECT_TRUE(std::adjacent_find(u.free.bricks.begin(), u.free.bricks.end()) == u.free.bricks.end()) << "no brick twice";
        EXPECT_EQ(u.free.words.size(), 8 * u.free.bricks.size());
        for (std::size_t b = 0; b < u.free.bricks.size(); ++b)
            EXPECT_TRUE(std::any_of(u.free.words.begin() + std::ptrdiff_t(8 * b), u.free.words.begin() + std::ptrdiff_t(8 * b + 8),
                                    [](std::uint64_t w) { return w != 0; }))
                << "no empty brick";
        EXPECT_EQ(u, gseg::map::castScan(d.groundView(), d.obstaclesView(), d.origin, o)) << "deterministic";
        bytes.push_back(gseg::map::serializeScanUpdate(u));
        EXPECT_EQ(gseg::map::deserializeScanUpdate(bytes.back()), u) << "serialisation round trip";
        // About 3 bytes a voxel code, 4 + 8 per nonzero word a free brick, 42 a ground cell and 25
        // a terrain sample (#31).
        std::size_t freeWords = 0;
        for (std::uint64_t w : u.free.words) freeWords += w != 0;
        EXPECT_LT(bytes.back().size(), 4 * u.free.bricks.size() + 8 * freeWords + 3 * (u.groundHits.size() + u.obstacleHits.size()) +
                                           42 * u.groundCells.size() + 25 * u.terrain.size() + 64);
        EXPECT_LT(bytes.back().size(), 3 * u.free.voxels()) << "smaller than the free voxels' codes";
        EXPECT_FALSE(u.terrain.empty());
    }
    // Cast in reverse order, sent as bytes, applied in scan order: the same files as inserting.
    std::vector<std::string> reversed(bytes.size());
    for (std::size_t k = bytes.size(); k-- > 0;) {
        const auto& d = theScans()[k];
        reversed[k] = gseg::map::serializeScanUpdate(gseg::map::castScan(d.groundView(), d.obstaclesView(), d.origin, o));
    }
    TraversabilityMap fromBytes(o);
    for (const auto& b : reversed) fromBytes.apply(gseg::map::deserializeScanUpdate(b));
    const std::string dir = tempDir("bytes");
    fromBytes.write(dir + "/a");
    theDrive().write(dir + "/b");
    for (const char* f : {"_ground.bt", "_obstacles.bt", "_traversability.ot", "_traversability.png", "_traversability.ply",
                          "_traversability.3Dscene", "_costmap.pgm", "_layers.tif", "_layer_elevation.png", "_layer_slope.png", "_layer_step.png",
                          "_layer_roughness.png", "_layer_clearance.png", "_layer_class.png", "_layer_cost.png"})
        EXPECT_TRUE(fileBytes(dir + "/a" + f) == fileBytes(dir + "/b" + f)) << f;
    std::string yaml = fileBytes(dir + "/a_costmap.yaml");  // names its own PGM
    yaml.replace(yaml.find("a_costmap.pgm"), 1, "b");
    EXPECT_EQ(yaml, fileBytes(dir + "/b_costmap.yaml"));
    std::filesystem::remove_all(dir);
    // Damaged bytes are an error, not a garbage update.
    std::string cut = bytes[0].substr(0, bytes[0].size() / 2), bad = bytes[0];
    bad[0] = 'X';
    EXPECT_THROW(gseg::map::deserializeScanUpdate(cut), std::runtime_error);
    EXPECT_THROW(gseg::map::deserializeScanUpdate(bad), std::runtime_error);
    EXPECT_THROW(gseg::map::deserializeScanUpdate(bytes[0] + "x"), std::runtime_error);
}

/// A scan update's free bricks from another process that break the format are refused, not applied.
TEST(OctomapBuilder, MalformedFreeBricksAreRefused) {
    auto bytesWith = [](const std::function<void(gseg::io::ByteWriter&)>& freeBricks) {
        gseg::io::ByteWriter out;
        out.raw("GSU4", 4).f64(0).f64(0).f64(0).varint(0).varint(0).varint(0).varint(0);
        freeBricks(out);
        out.varint(0).varint(0).varint(0).varint(0);  // no hits, ground cells or terrain samples
        return out.take();
    };
    const auto fine = gseg::map::deserializeScanUpdate(bytesWith([](auto& o) { o.varint(2).varint(5).u8(0x81).u64(3).u64(1ULL << 63).varint(7).u8(2).u64(9); }));
    EXPECT_EQ(fine.free.bricks, (std::vector<std::uint64_t>{5, 12}));
    EXPECT_EQ(fine.free.codes(), (std::vector<std::uint64_t>{5 * 512, 5 * 512 + 1, 5 * 512 + 511, 12 * 512 + 64, 12 * 512 + 67}));
    for (const auto& bad : std::vector<std::function<void(gseg::io::ByteWriter&)>>{
             [](auto& o) { o.varint(2).varint(5).u8(1).u64(3).varint(0).u8(1).u64(1); },  // the same brick twice
             [](auto& o) { o.varint(1).varint(5).u8(0); },                                // an empty brick
             [](auto& o) { o.varint(1).varint(5).u8(1).u64(0); },                         // an empty word
             [](auto& o) { o.varint(1).varint(1ULL << 39).u8(1).u64(1); },                // beyond the 48-bit codes
             [](auto& o) { o.varint(2).varint((1ULL << 39) - 1).u8(1).u64(1).varint(1).u8(1).u64(1); },
             [](auto& o) { o.varint(1000).varint(5).u8(1).u64(1); },                     // more bricks than bytes
         })
        EXPECT_THROW(gseg::map::deserializeScanUpdate(bytesWith(bad)), std::runtime_error);
    // The versions before (free voxels as codes): a code beyond 48 bits, or a list that wraps, is refused too.
    for (const std::uint64_t second : {1ULL << 48, ~0ULL}) {
        gseg::io::ByteWriter old;
        old.raw("GSU3", 4).f64(0).f64(0).f64(0).varint(0).varint(0).varint(0).varint(0);
        old.varint(2).varint(5).varint(second).varint(0).varint(0).varint(0).varint(0);
        EXPECT_THROW(gseg::map::deserializeScanUpdate(old.take()), std::runtime_error) << second;
    }
}

TEST(OctomapBuilder, NoOccupiedVoxelStillWritesReadableMaps) {
    // Every point beyond maxRange (#9 item 3: ColorOcTree crashed on an empty tree).
    gseg::map::TraversabilityOptions o;
    o.maxRange = 5;
    TraversabilityMap m(o);
    const float far[6] = {20, 0, 0, 0, 30, -1};
    m.insertScan(gseg::PointCloudView(far, 1), gseg::PointCloudView(far + 3, 1), Eigen::Vector3d(0, 0, 1.8));
    const auto s = m.stats();
    EXPECT_EQ(s.groundVoxels + s.obstacleVoxels, 0u);
    EXPECT_GT(s.freeVoxels, 20u);
    const std::string dir = tempDir("empty");
    ASSERT_EQ(m.write(dir + "/e").size(), 17u);
    EXPECT_TRUE(gseg::io::readPly(dir + "/e_traversability.ply").empty());
    mrpt::opengl::COpenGLScene scene;
    EXPECT_TRUE(scene.loadFromFile(dir + "/e_traversability.3Dscene"));
    std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(dir + "/e_traversability.ot"));
    ASSERT_NE(dynamic_cast<octomap::ColorOcTree*>(any.get()), nullptr);
    EXPECT_EQ(any->size(), 0u);
    mrpt::img::CImage png;
    EXPECT_TRUE(png.loadFromFile(dir + "/e_traversability.png"));
    std::filesystem::remove_all(dir);
}

TEST(OctomapBuilder, SensorOutsideTheExtentIsAnErrorAndFarPointsAreCounted) {
    TraversabilityMap m;  // 0.2 m: +-6553.6 m
    const float p[3] = {500000.5f, 5000000.5f, 100.0f};
    try {
        m.insertScan(gseg::PointCloudView(p, 1), {}, Eigen::Vector3d(500000, 5000000, 101.8));  // UTM
        FAIL() << "no throw";
    } catch (const std::out_of_range& e) {
        EXPECT_NE(std::string(e.what()).find("outside the map's extent of +-6553.6"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(m.empty());
    // Near the edge: a point 20 m away but outside the extent, a NaN point, and one inside.
    const float mixed[9] = {6560, 0, 0, NAN, 0, 0, 6545, 0, 0};
    m.insertScan(gseg::PointCloudView(mixed, 3), {}, Eigen::Vector3d(6540, 0, 1.8));
    EXPECT_EQ(m.stats().pointsSkipped, 2u);
    EXPECT_EQ(m.stats().groundVoxels, 1u);
}

TEST(OctomapBuilder, TopDownPictureOfAPathKilometresLongStaysSmall) {
    // Two scans 6 km apart (#9 item 9: the dense grid took 205 s and 4 GB).
    TraversabilityMap m;
    const float a[3] = {1, 0, 0}, b[3] = {4241, 4243, 0};
    m.insertScan(gseg::PointCloudView(a, 1), {}, Eigen::Vector3d(0, 0, 1.8));
    m.insertScan(gseg::PointCloudView(b, 1), {}, Eigen::Vector3d(4243, 4243, 1.8));
    const auto grid = m.topDown();
    EXPECT_EQ(grid.count(ColumnClass::Traversable), 2u);
    const auto layout = gseg::map::pictureLayout(grid, m.path());
    EXPECT_EQ(layout.cellsPerPixel, 6);  // 21226 cells a side in at most 4096 pixels
    EXPECT_LE(std::max(layout.width, layout.height), 4096);
    const std::string dir = tempDir("far");
    m.write(dir + "/f");
    mrpt::img::CImage png;
    ASSERT_TRUE(png.loadFromFile(dir + "/f_traversability.png"));
    EXPECT_EQ(int(png.getWidth()), layout.width);
    std::filesystem::remove_all(dir);
}

TEST(OctomapBuilder, TopDownPictureOfASmallMapIsEnlarged) {
    TraversabilityMap m;
    const float a[3] = {2, 1, 0};
    m.insertScan(gseg::PointCloudView(a, 1), {}, Eigen::Vector3d(0, 0, 1.8));
    const auto layout = gseg::map::pictureLayout(m.topDown(), m.path());
    EXPECT_EQ(layout.pixelsPerCell, 8);  // 21 cells a side: at most 8 pixels a cell
    EXPECT_EQ(layout.mapHeight, 8 * int(layout.cellsHigh));
    int c0 = 0, r0 = 0, c1 = 0, r1 = 0;
    ASSERT_TRUE(layout.toPixel(0.1, 0.1, c0, r0) && layout.toPixel(0.3, 0.1, c1, r1));
    EXPECT_EQ(c1 - c0, 8);  // one cell further along x: 8 pixels to the right
    EXPECT_EQ(r1, r0);
}

TEST(OctomapBuilder, TopDownGridIndexesNegativeCellsAndTileBorders) {
    gseg::map::TopDownGrid g(0.5);
    struct Case {
        double x, y;
        std::int64_t ix, iy;
    };
    const Case cases[] = {{0.0, 0.0, 0, 0},      {-0.01, 0.0, -1, 0},   {-0.5, -0.5, -1, -1}, {-0.51, 31.99, -2, 63},
                          {32.0, -32.0, 64, -64}, {-32.01, 0.2, -65, 0}, {1e3, -1e3, 2000, -2000}};
    for (const auto& c : cases) {
        EXPECT_EQ(g.cellIndex(c.x), c.ix) << c.x;
        EXPECT_EQ(g.cellIndex(c.y), c.iy) << c.y;
        g.set(c.ix, c.iy, ColumnClass::Obstacle);
        EXPECT_EQ(g.at(c.x, c.y), ColumnClass::Obstacle) << c.x << ", " << c.y;
    }
    EXPECT_EQ(g.count(ColumnClass::Obstacle), 7u);
    EXPECT_EQ(g.at(-0.4, 31.9), ColumnClass::Unknown);
    g.set(-1, 0, ColumnClass::Traversable);
    EXPECT_EQ(g.count(ColumnClass::Obstacle), 6u);
    EXPECT_EQ(g.count(ColumnClass::Traversable), 1u);
    EXPECT_EQ(g.minX(), -65);
    EXPECT_EQ(g.maxY(), 63);
}

TEST(OctomapBuilder, AbsurdResolutionsAreRejected) {
    for (double r : {0.0011, 0.0, -0.2, 11.0, 1e9}) {
        gseg::map::TraversabilityOptions o;
        o.resolution = r;
        EXPECT_THROW(o.validate(), std::invalid_argument) << r;
    }
    gseg::map::TraversabilityOptions o;
    o.resolution = 0.01, o.maxRange = 100;  // rays of 10000 voxels
    try {
        o.validate();
        FAIL() << "no throw";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("10000 voxels"), std::string::npos) << e.what();
    }
    o.maxRange = 50;
    EXPECT_NO_THROW(o.validate());
}

TEST(OctomapBuilder, FailedRenameLeavesThePreviousOutputsAsTheyWere) {
    // #9 item 9: a failed final rename deleted the previous run's outputs.
    const std::string dir = tempDir("rename");
    const std::vector<std::string> paths = {dir + "/a", dir + "/b", dir + "/c"};
    for (const auto& p : paths) std::ofstream(p) << "previous " << p;
    {
        gseg::io::AtomicFileSet files(paths);
        for (std::size_t i = 0; i < 3; ++i) files[i].write("new", 3);
        std::filesystem::remove(files[2].temporaryPath());  // the third rename fails
        EXPECT_THROW(files.commit(), std::runtime_error);
    }
    for (const auto& p : paths) EXPECT_EQ(fileBytes(p), "previous " + p);
    // The same through the map: the last target is a folder, so the first three must stay.
    const auto& m = theDrive();
    m.write(dir + "/m");
    const std::string before = fileBytes(dir + "/m_ground.bt");
    std::filesystem::remove(dir + "/m_traversability.png");
    std::filesystem::create_directories(dir + "/m_traversability.png/x");
    TraversabilityMap other;
    const float pt[3] = {3, 0, 0};
    other.insertScan(gseg::PointCloudView(pt, 1), {}, Eigen::Vector3d(0, 0, 1.8));
    EXPECT_THROW(other.write(dir + "/m"), std::runtime_error);
    EXPECT_EQ(fileBytes(dir + "/m_ground.bt"), before);
    EXPECT_TRUE(std::filesystem::exists(dir + "/m_obstacles.bt"));
    std::size_t entries = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir)) entries += e.path().filename().string()[0] == '.';
    EXPECT_EQ(entries, 0u) << "temporary or backup files left behind";
    std::filesystem::remove_all(dir);
}

}  // namespace

TEST(OctomapBuilder, ReflectionsBelowTheRoadBecomeNeitherGroundNorObstacles) {
    // A scan over flat ground with 2,000 mirror reflections 1-3 m under the road: segmentToWorld
    // leaves them out of both classes, so no obstacle voxel appears under the road.
    auto n = gseg::test::scene("reflections");
    auto pc = mrpt::maps::CSimplePointsMap::Create();
    for (std::size_t i = 0; i < n.scan.size(); ++i) pc->insertPoint(n.scan.xyz[3 * i], n.scan.xyz[3 * i + 1], n.scan.xyz[3 * i + 2]);
    mrpt::obs::CObservationPointCloud obs;
    obs.pointcloud = pc;
    obs.sensorLabel = "LIDAR";
    gseg::mrpt::LoadedConfig fixed;
    fixed.params.distToGround = n.sensorHeight;
    gseg::mrpt::ScanSegmenter seg(fixed);
    const gseg::map::WorldScan w = gseg::map::segmentToWorld(obs, mrpt::poses::CPose3D(), seg);
    EXPECT_GE(w.notes.reflections, 1900u);
    EXPECT_EQ(w.ground.size() / 3 + w.obstacles.size() / 3 + w.notes.reflections, n.scan.size());
    for (std::size_t i = 2; i < w.obstacles.size(); i += 3) EXPECT_GT(w.obstacles[i], -1.73f - 1.0f) << i / 3;
    gseg::map::TraversabilityMap map;
    map.apply(gseg::map::castScan(w.groundView(), w.obstaclesView(), w.sensorOrigin, map.options()));
    EXPECT_GT(map.stats().groundVoxels, 1000u);
    // With distToGround: auto the same (reflections do not move the estimate either).
    gseg::mrpt::LoadedConfig automatic;
    automatic.distToGroundAuto = true;
    gseg::mrpt::ScanSegmenter autoSeg(automatic);
    const gseg::map::WorldScan a = gseg::map::segmentToWorld(obs, mrpt::poses::CPose3D(), autoSeg);
    EXPECT_GE(a.notes.reflections, 1900u);
    EXPECT_TRUE(a.notes.heightNote.empty()) << a.notes.heightNote;
}
