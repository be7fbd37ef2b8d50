// rawlog-octomap end to end: a simulated drive with a mounted sensor (poses in the rawlog or a TUM
// file), the real SemanticKITTI sequence 00 through kitti2rawlog, and bad input.
#include <gseg/map/poses.hpp>
#include <support/lidar_sim.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRobotPose.h>
#include <mrpt/serialization/CArchive.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace fs = std::filesystem;
using gseg::test::Truth;

namespace {

constexpr double kRoadZ = 0.1;
const mrpt::poses::CPose3D kMount(0.5, 0.0, 1.8, 0, 0, 0);  // sensor 1.8 m above the vehicle origin

struct ToolRun {
    int status = 0;
    std::string out, err;
};

ToolRun runTool(const std::string& name, const std::string& args, const std::string& dir) {
    ToolRun r;
    r.status = std::system((gseg::test::tool(name) + " " + args + " > " + dir + "/out.txt 2> " + dir + "/err.txt").c_str());
    std::ifstream o(dir + "/out.txt"), e(dir + "/err.txt");
    r.out.assign(std::istreambuf_iterator<char>(o), {});
    r.err.assign(std::istreambuf_iterator<char>(e), {});
    return r;
}

std::string tempDir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("gseg_r2o_" + std::to_string(::getpid()) + "_" + name);
    fs::remove_all(d);
    fs::create_directories(d);
    return d.string();
}

bool occupied(const octomap::OcTree& t, double x, double y, double z) {
    const auto* n = t.search(x, y, z);
    return n && t.isNodeOccupied(n);
}

std::vector<std::string> mapFiles(const std::string& prefix) {
    std::vector<std::string> out;
    for (const char* s : {"_ground.bt", "_obstacles.bt", "_traversability.ot", "_traversability.png"})
        if (fs::exists(prefix + s)) out.push_back(prefix + s);
    return out;
}

/// Vehicle at x = 3k on the road (z = kRoadZ); the scans are in the sensor frame.
mrpt::poses::CPose3D vehiclePose(int k) { return mrpt::poses::CPose3D(3.0 * k, 0, kRoadZ, 0, 0, 0); }

/// Writes 8 scans of a road with a box and a wall; with `poses`, a CObservationRobotPose before each.
/// With `presegmented`, each scan is written as rawlog-gseg writes it: a `LIDAR_ground` and a
/// `LIDAR_obstacles` CObservationPointCloud, split by the simulator's exact truth.
void writeDrive(const std::string& path, bool poses, bool presegmented = false) {
    mrpt::io::CFileGZOutputStream f(path);
    auto out = mrpt::serialization::archiveFrom(f);
    gseg::test::Lidar lidar;
    lidar.beams = 32, lidar.minElevationDeg = -25, lidar.maxElevationDeg = 5, lidar.azimuthStepDeg = 0.5, lidar.maxRange = 40;
    for (int k = 0; k < 8; ++k) {
        const auto sensor = vehiclePose(k) + kMount;
        gseg::test::Scene s;
        s.addFlatGround(sensor.z() - kRoadZ);
        auto box = [&](double x0, double y0, double z0, double x1, double y1, double z1) {
            s.addBox(x0 - sensor.x(), y0 - sensor.y(), z0 - sensor.z(), x1 - sensor.x(), y1 - sensor.y(), z1 - sensor.z());
        };
        box(10, -4, kRoadZ, 11, -3, kRoadZ + 1.5);
        box(0, -8.2, kRoadZ, 40, -8, kRoadZ + 3);
        const auto scan = gseg::test::simulate(s, lidar);
        const auto t = mrpt::Clock::fromDouble(100.0 + 0.1 * k);
        if (poses) {
            mrpt::obs::CObservationRobotPose p;
            p.pose.mean = vehiclePose(k);
            p.timestamp = t;
            out << p;
        }
        auto write = [&](const std::string& label, int want) {  // want: -1 all, 1 ground, 0 obstacles
            auto pc = mrpt::maps::CSimplePointsMap::Create();
            for (std::size_t i = 0; i < scan.size(); ++i)
                if (want < 0 || (scan.truth[i] == Truth::Ground) == (want == 1))
                    pc->insertPoint(scan.xyz[3 * i], scan.xyz[3 * i + 1], scan.xyz[3 * i + 2]);
            mrpt::obs::CObservationPointCloud obs;
            obs.pointcloud = pc;
            obs.sensorPose = kMount;
            obs.sensorLabel = label;
            obs.timestamp = t;
            out << obs;
        };
        if (presegmented) {
            write("LIDAR_ground", 1);
            write("LIDAR_obstacles", 0);
        } else {
            write("LIDAR", -1);
        }
    }
}

void expectDriveMap(const std::string& prefix) {
    ASSERT_EQ(mapFiles(prefix).size(), 4u);
    octomap::OcTree ground(prefix + "_ground.bt"), obstacles(prefix + "_obstacles.bt");
    for (double x : {5.0, 9.0, 14.0, 20.0}) {
        EXPECT_TRUE(occupied(ground, x, 1.5, kRoadZ)) << "road at x " << x;
        EXPECT_FALSE(occupied(obstacles, x, 1.5, kRoadZ)) << "road at x " << x;
        // Where the road would land if the 1.8 m mounting were ignored:
        EXPECT_FALSE(occupied(ground, x, 1.5, kRoadZ - 1.8));
    }
    EXPECT_TRUE(occupied(obstacles, 10.5, -3.1, 0.9)) << "box face";
    EXPECT_TRUE(occupied(obstacles, 15.0, -8.1, 1.5)) << "wall";
    const auto* between = obstacles.search(10.5, -1.5, 1.0);
    ASSERT_NE(between, nullptr);
    EXPECT_FALSE(obstacles.isNodeOccupied(between)) << "space between sensor and box";
}

TEST(RawlogOctomap, SimulatedDriveWithPosesInTheRawlog) {
    const std::string dir = tempDir("sim");
    writeDrive(dir + "/drive.rawlog", true);
    std::ofstream(dir + "/gseg.yaml") << "distToGround: 1.8\n";
    const ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/drive.rawlog -o " + dir + "/m -c " + dir + "/gseg.yaml", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("voxels (0.20 m)"), std::string::npos) << r.out;
    expectDriveMap(dir + "/m");
    fs::remove_all(dir);
}

TEST(RawlogOctomap, PresegmentedGroundAndObstacleObservationsAreUsedAsTheyAre) {
    const std::string dir = tempDir("preseg");
    writeDrive(dir + "/drive.rawlog", true, true);
    // A wrong sensor height: had the tool segmented these scans again, the road would be lost.
    std::ofstream(dir + "/gseg.yaml") << "distToGround: 9.0\n";
    const ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/drive.rawlog -o " + dir + "/m -c " + dir + "/gseg.yaml", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("8 scans"), std::string::npos) << r.out;
    expectDriveMap(dir + "/m");
    fs::remove_all(dir);
}

TEST(RawlogOctomap, SimulatedDriveWithTumPoses) {
    const std::string dir = tempDir("tum");
    writeDrive(dir + "/drive.rawlog", false);
    std::ofstream tum(dir + "/poses.tum");
    for (int k = 0; k < 8; ++k) tum << std::to_string(100.0 + 0.1 * k) << " " << 3.0 * k << " 0 " << kRoadZ << " 0 0 0 1\n";
    tum.close();
    std::ofstream(dir + "/gseg.yaml") << "distToGround: 1.8\n";
    const ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/drive.rawlog -o " + dir + "/m --poses " + dir +
                                                    "/poses.tum -c " + dir + "/gseg.yaml", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    expectDriveMap(dir + "/m");
    fs::remove_all(dir);
}

TEST(RawlogOctomap, KittiSequence00ThroughKitti2rawlog) {
    const std::string poses = gseg::test::sharedData("semantickitti/sequences/00/poses.txt");
    if (poses.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/00/poses.txt");
    const std::string dir = tempDir("kitti");
    ToolRun r = runTool("kitti2rawlog", fs::path(poses).parent_path().string() + " -o " + dir + "/seq00.rawlog", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    r = runTool("rawlog-octomap", "-i " + dir + "/seq00.rawlog -o " + dir + "/seq00", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    ASSERT_EQ(mapFiles(dir + "/seq00").size(), 4u);

    octomap::OcTree ground(dir + "/seq00_ground.bt");
    std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(dir + "/seq00_traversability.ot"));
    ASSERT_NE(dynamic_cast<octomap::ColorOcTree*>(any.get()), nullptr);
    EXPECT_GT(any->size(), 1000u);
    // Ground voxels around each sensor position lie at road height (about 1.73 m below it).
    const auto velo = gseg::map::kittiToVelodyneFrame(gseg::map::readKittiPoses(poses),
                                                      gseg::map::readKittiCalibTr(fs::path(poses).parent_path() / "calib.txt"));
    for (std::size_t k = 0; k < velo.size(); ++k) {
        const Eigen::Vector3d p = velo[k].translation();
        std::vector<double> dz;
        for (auto it = ground.begin_leafs(); it != ground.end_leafs(); ++it) {
            if (!ground.isNodeOccupied(*it)) continue;
            const double dx = it.getX() - p.x(), dy = it.getY() - p.y();
            if (dx * dx + dy * dy < 8.0 * 8.0) dz.push_back(it.getZ() - p.z());
        }
        ASSERT_GT(dz.size(), 200u) << "few ground voxels near frame " << k;
        std::nth_element(dz.begin(), dz.begin() + long(dz.size() / 2), dz.end());
        EXPECT_NEAR(dz[dz.size() / 2], -1.73, 0.2) << "median ground height near frame " << k;
    }
    fs::remove_all(dir);
}

TEST(RawlogOctomap, BadInputIsAClearErrorAndNoMapFiles) {
    const std::string dir = tempDir("bad");
    writeDrive(dir + "/noposes.rawlog", false);
    struct Case {
        std::string args, expect;
    };
    std::ofstream(dir + "/few.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n";
    std::ofstream(dir + "/calib.txt") << "Tr: 0 -1 0 0 0 0 -1 0 1 0 0 0\n";
    std::ofstream(dir + "/late.tum") << "500.0 0 0 0 0 0 0 1\n501.0 1 0 0 0 0 0 1\n";
    std::ofstream(dir + "/garbage.rawlog") << "this is not a rawlog at all, just some text to fail on";
    const Case cases[] = {
        {"-i " + dir + "/noposes.rawlog", "no poses"},
        {"-i " + dir + "/noposes.rawlog --poses " + dir + "/few.txt", "2 poses for 8 scans"},
        {"-i " + dir + "/noposes.rawlog --poses " + dir + "/late.tum", "no pose within"},
        {"-i " + dir + "/garbage.rawlog", "garbage.rawlog"},
        {"-i " + dir + "/missing.rawlog", "missing.rawlog"},
    };
    for (const auto& c : cases) {
        const ToolRun r = runTool("rawlog-octomap", c.args + " -o " + dir + "/m", dir);
        EXPECT_NE(r.status, 0) << c.args;
        EXPECT_NE(r.err.find("rawlog-octomap: "), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(c.expect), std::string::npos) << "wanted '" << c.expect << "' in: " << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
        EXPECT_TRUE(mapFiles(dir + "/m").empty()) << c.args;
    }
    fs::remove_all(dir);
}

}  // namespace
