// rawlog-octomap end to end: a simulated drive with a mounted sensor (poses in the rawlog or a TUM
// file, raw scans or rawlog-gseg's pairs), the real SemanticKITTI sequence 00 through kitti2rawlog
// (and rawlog-gseg), threads, progress, skipped scans, failing early, and bad input.
#include <gseg/io/ros_map.hpp>
#include <gseg/ordered_pipeline.hpp>
#include <gseg/map/poses.hpp>
#include <gseg/map/traversability_map.hpp>
#include <support/child.hpp>
#include <support/lidar_sim.hpp>
#include <support/map_files.hpp>
#include <support/sim_drive.hpp>
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
#include <iostream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using gseg::test::Truth;

namespace {

using gseg::test::Drive;
using gseg::test::kMount;
using gseg::test::kRoadZ;
using gseg::test::vehiclePose;
using gseg::test::writeDrive;

using gseg::test::runTool;
using gseg::test::ToolRun;

std::string tempDir(const std::string& name) { return gseg::test::freshDir("rawlog_octomap", name).string(); }

/// tempDir(name) holding the simulated drive (drive.rawlog) and gseg.yaml with the mounting's
/// height (distToGround: 1.8).
std::string driveDir(const std::string& name) {
    const std::string dir = tempDir(name);
    writeDrive(dir + "/drive.rawlog");
    std::ofstream(dir + "/gseg.yaml") << "distToGround: 1.8\n";
    return dir;
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

/// The four map files of two runs are the same bytes.
void expectSameMaps(const std::string& one, const std::string& two) {
    for (const char* f : {"_ground.bt", "_obstacles.bt", "_traversability.ot", "_traversability.png"}) {
        const std::string a = gseg::test::readText(one + f);
        EXPECT_GT(a.size(), 100u) << one << f;
        EXPECT_TRUE(a == gseg::test::readText(two + f)) << two << f << " differs from " << one << f;
    }
}

/// stderr lines that are not progress (nor the line saying the maps are being written).
std::vector<std::string> messageLines(const std::string& err) {
    std::vector<std::string> out;
    std::size_t from = 0;
    while (from < err.size()) {
        const std::size_t to = std::min(err.find('\n', from), err.size());
        const std::string line = err.substr(from, to - from);
        if (!line.empty() && line.find("scans/s") == std::string::npos && line.rfind("rawlog-octomap: writing ", 0) != 0)
            out.push_back(line);
        from = to + 1;
    }
    return out;
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

TEST(RawlogOctomapTool, SimulatedDriveWithPosesInTheRawlog) {
    const std::string dir = driveDir("sim");
    const ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/drive.rawlog -o " + dir + "/m -c " + dir + "/gseg.yaml", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("voxels (0.20 m)"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("8 scans (0 from _ground/_obstacles pairs"), std::string::npos) << r.out;
    for (const char* phase : {"read ", "segmentation ", "transform ", "ray casting ", "map update ", "writing "})
        EXPECT_NE(r.out.find(phase), std::string::npos) << "time of " << phase << " in: " << r.out;
    expectDriveMap(dir + "/m");
    // One map truth (#33): the summary's costmap counts are the PGM's pixels, and it names the files.
    const gseg::io::RosMap costmap = gseg::io::readRosMap(dir + "/m_costmap.yaml");
    std::size_t free = 0, occupiedCells = 0, unknown = 0;
    for (int cy = 0; cy < costmap.height; ++cy)
        for (int cx = 0; cx < costmap.width; ++cx) {
            const gseg::io::RosCell c = costmap.at(cx, cy);
            ++(c == gseg::io::RosCell::Free ? free : c == gseg::io::RosCell::Occupied ? occupiedCells : unknown);
        }
    EXPECT_GT(free, 0u);
    EXPECT_GT(occupiedCells, 0u);
    const std::string counts = "costmap " + dir + "/m_costmap.pgm + " + dir + "/m_costmap.yaml: " + std::to_string(free) + " free (";
    EXPECT_NE(r.out.find(counts), std::string::npos) << "wanted '" << counts << "' in: " << r.out;
    EXPECT_NE(r.out.find(std::to_string(occupiedCells) + " occupied ("), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(std::to_string(unknown) + " unknown cells\n"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("voxel columns (_traversability.png, not the costmap): "), std::string::npos) << r.out;
    // The class layer's picture is the costmap, cell for cell, in the PGM's orientation.
    EXPECT_TRUE(gseg::test::classPictureShowsCostmap(dir + "/m_layer_class.png", dir + "/m_costmap.pgm"));
    // Every file is written, named in "wrote" lines; the writing has a line of its own while it lasts.
    const auto files = gseg::map::TraversabilityMap::outputPaths(dir + "/m");
    EXPECT_EQ(files.size(), 17u);
    for (const std::string& f : files) {
        EXPECT_TRUE(fs::exists(f)) << f;
        EXPECT_NE(r.out.find("wrote " + f + "\n"), std::string::npos) << f << " in: " << r.out;
    }
    EXPECT_NE(r.err.find("rawlog-octomap: writing 17 map files (" + dir + "/m_*) ...\n"), std::string::npos) << r.err;
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, HelpNamesEveryFileWritten) {
    const gseg::test::CommandResult r = gseg::test::runToolCommand("rawlog-octomap", "--help");
    ASSERT_EQ(r.status, 0) << r.output;
    std::string help = r.output;  // TCLAP wraps the text: join its lines
    for (std::size_t at; (at = help.find("\n")) != std::string::npos;) {
        std::size_t end = at + 1;
        while (end < help.size() && help[end] == ' ') ++end;
        help.replace(at, end - at, " ");
    }
    for (const std::string& f : gseg::map::TraversabilityMap::outputPaths("PREFIX"))
        EXPECT_NE(help.find(f), std::string::npos) << f << " not named in: " << r.output;
    EXPECT_EQ(help.find("four"), std::string::npos) << r.output;
}

TEST(RawlogOctomapTool, PresegmentedGroundAndObstacleObservationsAreUsedAsTheyAre) {
    const std::string dir = tempDir("preseg");
    // A wrong sensor height: had the tool segmented these scans again, the road would be lost.
    std::ofstream(dir + "/gseg.yaml") << "distToGround: 9.0\n";
    for (const auto layout : {Drive::Pair, Drive::RawAndPair}) {  // rawlog-gseg with and without --replace
        Drive d;
        d.layout = layout;
        writeDrive(dir + "/drive.rawlog", d);
        const ToolRun r = runTool("rawlog-octomap", "-w -i " + dir + "/drive.rawlog -o " + dir + "/m -c " + dir + "/gseg.yaml", dir);
        ASSERT_EQ(r.status, 0) << r.err;
        const std::string raw = layout == Drive::Pair ? "0" : "8";
        EXPECT_NE(r.out.find("8 scans (8 from _ground/_obstacles pairs, " + raw + " raw scans not segmented again"),
                  std::string::npos) << r.out;
        expectDriveMap(dir + "/m");
    }
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, SimulatedDriveWithTumPoses) {
    const std::string dir = tempDir("tum");
    Drive d;
    d.poses = false;
    writeDrive(dir + "/drive.rawlog", d);
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

TEST(RawlogOctomapTool, KittiSequence00ThroughKitti2rawlog) {
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

TEST(RawlogOctomapTool, Drive00ClassPictureIsTheCostmapCellForCell) {
    // One map truth (#33) on real data: the ten labelled scans of SemanticKITTI drive 00.
    const std::string poses = gseg::test::sharedData("semantickitti-drives/sequences/00/poses.txt");
    if (poses.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti-drives/sequences/00/poses.txt");
    const std::string dir = tempDir("drive00");
    ToolRun r = runTool("kitti2rawlog", "-i " + fs::path(poses).parent_path().string() + " -o " + dir + "/d.rawlog", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    r = runTool("rawlog-octomap", "-i " + dir + "/d.rawlog -o " + dir + "/d -c " + std::string(GSEG_SOURCE_DIR) + "/config/kitti_hdl64.yaml", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const auto verdict = gseg::test::classPictureShowsCostmap(dir + "/d_layer_class.png", dir + "/d_costmap.pgm");
    EXPECT_TRUE(verdict);
    std::cout << "drive 00: " << verdict.message() << "\n";
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, BadInputIsAClearErrorAndNoMapFiles) {
    const std::string dir = tempDir("bad");
    Drive noPoses;
    noPoses.poses = false;
    writeDrive(dir + "/noposes.rawlog", noPoses);
    struct Case {
        std::string args, expect;
    };
    std::ofstream(dir + "/few.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n";
    std::ofstream(dir + "/calib.txt") << "Tr: 0 -1 0 0 0 0 -1 0 1 0 0 0\n";
    std::ofstream(dir + "/late.tum") << "500.0 0 0 0 0 0 0 1\n501.0 1 0 0 0 0 0 1\n";
    // #9 item 9: --resolution 0.0011 was accepted and ran for minutes.
    for (const char* bad : {"--resolution 0.0011", "--resolution 0.01 --max-range 80", "--threads -1", "--origin 1,2"}) {
        const ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/noposes.rawlog -o " + dir + "/m " + bad, dir);
        EXPECT_EQ(r.status, 2) << bad << ": " << r.err;
        EXPECT_EQ(messageLines(r.err).size(), 1u) << r.err;
    }
    std::ofstream(dir + "/garbage.rawlog") << "this is not a rawlog at all, just some text to fail on";
    const Case cases[] = {
        {"-i " + dir + "/noposes.rawlog", "no poses"},
        {"-i " + dir + "/noposes.rawlog --poses " + dir + "/few.txt", "2 poses, but scan 2"},
        {"-i " + dir + "/noposes.rawlog --poses " + dir + "/late.tum", "no pose within"},
        {"-i " + dir + "/garbage.rawlog", "garbage.rawlog"},
        {"-i " + dir + "/missing.rawlog", "missing.rawlog"},
    };
    for (const auto& c : cases) {
        const ToolRun r = runTool("rawlog-octomap", c.args + " -o " + dir + "/m", dir);
        EXPECT_NE(r.status, 0) << c.args;
        const auto lines = messageLines(r.err);
        ASSERT_EQ(lines.size(), 1u) << "one line: " << r.err;
        EXPECT_EQ(lines[0].rfind("rawlog-octomap: ", 0), 0u) << r.err;
        EXPECT_NE(lines[0].find(c.expect), std::string::npos) << "wanted '" << c.expect << "' in: " << r.err;
        EXPECT_TRUE(mapFiles(dir + "/m").empty()) << c.args;
    }
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, ChainKitti2rawlogRawlogGsegRawlogOctomapSegmentsEachScanOnce) {
    const std::string poses = gseg::test::sharedData("semantickitti/sequences/00/poses.txt");
    if (poses.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/00/poses.txt");
    const std::string dir = tempDir("chain"), config = std::string(GSEG_SOURCE_DIR) + "/config/kitti_hdl64.yaml";
    ToolRun r = runTool("kitti2rawlog", fs::path(poses).parent_path().string() + " -o " + dir + "/seq00.rawlog", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    r = runTool("rawlog-gseg", "-i " + dir + "/seq00.rawlog -o " + dir + "/split.rawlog -c " + config, dir);  // no --replace
    ASSERT_EQ(r.status, 0) << r.err;
    r = runTool("rawlog-octomap", "-i " + dir + "/split.rawlog -o " + dir + "/m", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("6 scans (6 from _ground/_obstacles pairs, 6 raw scans not segmented again, 0 skipped)"),
              std::string::npos) << r.out;
    EXPECT_NE(r.out.find("segmentation 0.00,"), std::string::npos) << "nothing segmented again: " << r.out;
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, SameMapsWithAnyNumberOfThreads) {
    const std::string dir = driveDir("threads");
    for (const char* threads : {"0", "1", "3"}) {
        const ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/drive.rawlog -o " + dir + "/t" + threads + " -c " + dir +
                                                        "/gseg.yaml --threads " + threads, dir);
        ASSERT_EQ(r.status, 0) << r.err;
    }
    expectSameMaps(dir + "/t0", dir + "/t1");
    expectSameMaps(dir + "/t0", dir + "/t3");
    fs::remove_all(dir);
}

// The default worker count is the cores the process may use (taskset, cpusets, mpirun's binding
// of a rank to a core), not the machine's: two threads bound to one core only take turns.
TEST(RawlogOctomapTool, DefaultWorkersAreTheCoresTheProcessMayUse) {
    if (std::system("taskset -c 0 true > /dev/null 2>&1") != 0) GTEST_SKIP() << "taskset (util-linux) is not available";
    const std::string dir = driveDir("affinity");
    const std::string args = "-i " + dir + "/drive.rawlog -c " + dir + "/gseg.yaml -o " + dir;
    const ToolRun one = runTool("rawlog-octomap", args + "/one", dir, "", "taskset -c 0 ");
    ASSERT_EQ(one.status, 0) << one.err;
    EXPECT_NE(one.out.find("(summed over 1 worker thread(s))"), std::string::npos) << one.out;
    // Given explicitly, --threads wins; the maps are the same.
    const ToolRun three = runTool("rawlog-octomap", args + "/three --threads 3", dir, "", "taskset -c 0 ");
    ASSERT_EQ(three.status, 0) << three.err;
    EXPECT_NE(three.out.find("(summed over 3 worker thread(s))"), std::string::npos) << three.out;
    expectSameMaps(dir + "/one", dir + "/three");
    fs::remove_all(dir);
}

// The drive's sensor is 1.8 m up: a distToGround of 2.5 is said once (scan 0), on one or two ranks.
TEST(RawlogOctomapTool, AFixedHeightThatTheFirstScanContradictsIsSaid) {
    const std::string dir = tempDir("height");
    writeDrive(dir + "/drive.rawlog");
    std::ofstream(dir + "/wrong.yaml") << "distToGround: 2.5\n";
    std::ofstream(dir + "/right.yaml") << "distToGround: 1.8\n";
    const std::string args = "-i " + dir + "/drive.rawlog -o " + dir;
    const ToolRun wrong = runTool("rawlog-octomap", args + "/w -c " + dir + "/wrong.yaml", dir);
    ASSERT_EQ(wrong.status, 0) << wrong.err;
    EXPECT_NE(wrong.err.find("scan 0 ("), std::string::npos) << wrong.err;
    EXPECT_NE(wrong.err.find("the ground lies 1.80 m below the sensor"), std::string::npos) << wrong.err;
    EXPECT_EQ(wrong.err.find("the ground lies"), wrong.err.rfind("the ground lies")) << "once: " << wrong.err;
    const ToolRun right = runTool("rawlog-octomap", args + "/r -c " + dir + "/right.yaml", dir);
    ASSERT_EQ(right.status, 0) << right.err;
    EXPECT_EQ(right.err.find("the ground lies"), std::string::npos) << right.err;
    std::string whyNot;
    if (const std::string mpirun = gseg::test::mpirun(2, whyNot); !mpirun.empty()) {
        const ToolRun two = runTool("rawlog-octomap", args + "/w2 -c " + dir + "/wrong.yaml --threads 0 --rank0-maps-only",
                                    dir, "", mpirun);
        ASSERT_EQ(two.status, 0) << two.err;
        EXPECT_NE(two.err.find("the ground lies 1.80 m below the sensor"), std::string::npos)
            << "said by rank 0 for rank 1: " << two.err;
    }
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, ProgressShowsScansPerSecondAndTimeLeft) {
    const std::string dir = driveDir("progress");
    const ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/drive.rawlog -o " + dir + "/m -c " + dir + "/gseg.yaml", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    // Not a terminal: plain lines (the first scan, then every 10 s, then the end), no carriage returns.
    EXPECT_NE(r.err.find("rawlog-octomap: 1 scans, "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(" left"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("rawlog-octomap: 8 scans, "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(" in all"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, AScanThatCannotBeSegmentedIsSkippedNamedAndCounted) {
    const std::string dir = tempDir("skip");
    Drive d;
    d.emptyScan = 3;
    writeDrive(dir + "/drive.rawlog", d);
    std::ofstream(dir + "/gseg.yaml") << "distToGround: 1.8\n";
    const ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/drive.rawlog -o " + dir + "/m -c " + dir + "/gseg.yaml", dir);
    EXPECT_EQ(r.status, 3) << "the exit code says a scan was skipped (maps written)";
    EXPECT_NE(r.err.find("skipped scan 3 ('LIDAR' at rawlog entry 7"), std::string::npos) << r.err;
    EXPECT_NE(r.out.find("8 scans (0 from _ground/_obstacles pairs, 0 raw scans not segmented again, 1 skipped)"),
              std::string::npos) << r.out;
    expectDriveMap(dir + "/m");  // the other seven made the maps
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, NoOccupiedVoxelIsNoCrash) {
    // #9 item 3: SEGV in ColorOcTree when nothing ends up occupied.
    const std::string dir = driveDir("empty");
    // Every point beyond --max-range (the nearest is the road 1.8 m below the sensor).
    ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/drive.rawlog -o " + dir + "/m -c " + dir + "/gseg.yaml --max-range 1.5", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("voxels (0.20 m): 0 ground, 0 obstacle"), std::string::npos) << r.out;
    ASSERT_EQ(mapFiles(dir + "/m").size(), 4u);
    std::unique_ptr<octomap::AbstractOcTree> ot(octomap::AbstractOcTree::read(dir + "/m_traversability.ot"));
    ASSERT_NE(ot, nullptr);
    EXPECT_EQ(ot->size(), 0u);
    // Every point far above the sensor: a ceiling 60 m up.
    {
        mrpt::io::CFileGZOutputStream f(dir + "/high.rawlog");
        auto out = mrpt::serialization::archiveFrom(f);
        for (int k = 0; k < 3; ++k) {
            mrpt::obs::CObservationRobotPose p;
            p.pose.mean = vehiclePose(k);
            p.timestamp = mrpt::Clock::fromDouble(100.0 + 0.1 * k);
            out << p;
            auto pc = mrpt::maps::CSimplePointsMap::Create();
            for (int i = -20; i <= 20; ++i)
                for (int j = -20; j <= 20; ++j) pc->insertPoint(float(i), float(j), 60.f);
            mrpt::obs::CObservationPointCloud obs;
            obs.pointcloud = pc, obs.sensorPose = kMount, obs.sensorLabel = "LIDAR", obs.timestamp = p.timestamp;
            out << obs;
        }
    }
    r = runTool("rawlog-octomap", "-i " + dir + "/high.rawlog -o " + dir + "/h -c " + dir + "/gseg.yaml", dir);
    ASSERT_EQ(r.status, 0) << r.err;  // whatever the labels: every point is beyond the 50 m rays
    EXPECT_NE(r.out.find("voxels (0.20 m): 0 ground, 0 obstacle"), std::string::npos) << r.out;
    EXPECT_EQ(mapFiles(dir + "/h").size(), 4u);
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, PosesInUtmNeedAnOriginAndThenWork) {
    const std::string dir = tempDir("utm");
    Drive d;
    d.offset = Eigen::Vector3d(500000.0, 5000000.0, 250.0);
    writeDrive(dir + "/utm.rawlog", d);
    std::ofstream(dir + "/gseg.yaml") << "distToGround: 1.8\n";
    const std::string args = "-i " + dir + "/utm.rawlog -o " + dir + "/m -c " + dir + "/gseg.yaml";
    ToolRun r = runTool("rawlog-octomap", args, dir);
    EXPECT_EQ(r.status, 1);
    const auto lines = messageLines(r.err);
    ASSERT_EQ(lines.size(), 1u) << r.err;
    EXPECT_NE(lines[0].find("lies outside the map's extent of +-6553.6 m"), std::string::npos) << r.err;
    EXPECT_NE(lines[0].find("--origin first"), std::string::npos) << r.err;
    EXPECT_TRUE(mapFiles(dir + "/m").empty());
    r = runTool("rawlog-octomap", args + " --origin first", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    // The first sensor position (500000.5, 5000000, 251.9) in whole metres is the maps' origin.
    EXPECT_NE(r.out.find("map origin: (500001.000, 5000000.000, 252.000)"), std::string::npos) << r.out;
    octomap::OcTree ground(dir + "/m_ground.bt");
    for (double x : {5.0, 9.0, 14.0}) EXPECT_TRUE(occupied(ground, x - 1.0, 1.5, kRoadZ - 2.0)) << "road at x " << x;
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, AFileThatIsNoRawlogIsSaidToBeNone) {
    // Was "entry 0 is corrupt or truncated (Message: Exception while parsing typed object ...)".
    const std::string dir = tempDir("not_rawlog");
    std::ofstream(dir + "/x.rawlog") << "hello\n";
    const ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/x.rawlog -o " + dir + "/m", dir);
    EXPECT_EQ(r.status, 1) << r.err;
    EXPECT_EQ(r.err, "rawlog-octomap: " + dir + "/x.rawlog: not an MRPT rawlog (a rawlog is a stream of serialized MRPT "
                     "objects, optionally gzip-compressed; this file does not start with one)\n");
    EXPECT_FALSE(fs::exists(dir + "/m_ground.bt"));
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, FailsBeforeAnyWorkOnAnOutputFolderItCannotWrite) {
    const std::string dir = tempDir("early");
    writeDrive(dir + "/drive.rawlog");
    for (const std::string& prefix : {dir + "/missing/m", std::string("/proc/gseg_maps_test/m"), std::string("/proc/m")}) {
        const ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/drive.rawlog -o " + prefix, dir);
        EXPECT_EQ(r.status, 2) << prefix;  // bad usage
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line and no scan read: " << r.err;
        EXPECT_NE(r.err.find(prefix + "_ground.bt: "), std::string::npos) << r.err;
    }
    // An input as output is refused, and the input is left as it was.
    fs::copy_file(dir + "/drive.rawlog", dir + "/m_ground.bt");
    const std::string before = gseg::test::readText(dir + "/m_ground.bt");
    const ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/m_ground.bt -o " + dir + "/m", dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("is the input"), std::string::npos) << r.err;
    EXPECT_TRUE(gseg::test::readText(dir + "/m_ground.bt") == before);
    EXPECT_FALSE(fs::exists(dir + "/m_obstacles.bt"));
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, DiskFullIsAnErrorAndNoMapFiles) {
    // #9 item 6. The file size limit (EFBIG once the signal is ignored) stands in for a full disk.
    const std::string dir = driveDir("full");
    const ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/drive.rawlog -o " + dir + "/m -c " + dir + "/gseg.yaml", dir,
                              "ulimit -f 200; trap '' XFSZ;");
    EXPECT_EQ(r.status, 1) << r.err;
    EXPECT_NE(r.err.find("write failed after "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(" bytes (File too large)"), std::string::npos) << r.err;
    EXPECT_EQ(r.out.find("wrote"), std::string::npos) << r.out;
    EXPECT_TRUE(mapFiles(dir + "/m").empty());
    for (const auto& e : fs::directory_iterator(dir))
        EXPECT_NE(e.path().filename().string()[0], '.') << "left behind: " << e.path();
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, BenchTimesPlainOctomapAndItselfAlternately) {
    const std::string dir = driveDir("bench");
    const ToolRun r = runTool("rawlog-octomap", "-i " + dir + "/drive.rawlog -o " + dir + "/b -c " + dir +
                                                    "/gseg.yaml --max-range 15 --bench 2", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 2 + 4 + 2) << r.out;
    EXPECT_LT(r.out.find("1      plain OctoMap"), r.out.find("1      rawlog-octomap")) << r.out;
    EXPECT_LT(r.out.find("2      rawlog-octomap"), r.out.find("2      plain OctoMap")) << r.out;
    EXPECT_NE(r.out.find("x faster"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("ray casting"), std::string::npos) << r.out;
    EXPECT_TRUE(fs::exists(dir + "/b_bench_ground.bt") && fs::exists(dir + "/b_bench_plain.bt"));
    fs::remove_all(dir);
}

// #35: tools/bench_vs_octomap.sh (the README's Tools) makes the drive and times both side by side.
TEST(RawlogOctomapTool, BenchScriptMakesTheDriveAndTimesPlainOctomapBesideIt) {
    const std::string rel = "semantickitti/sequences/00";
    const std::string seq = gseg::test::sharedData(rel);
    if (seq.empty()) GTEST_SKIP() << gseg::test::missingDataMessage(rel);
    const std::string dir = tempDir("bench_script");
    fs::create_directories(dir + "/two/velodyne");  // the first two frames of sequence 00
    for (const char* f : {"000000.bin", "000001.bin"}) fs::create_symlink(seq + "/velodyne/" + f, dir + "/two/velodyne/" + f);
    fs::copy_file(seq + "/calib.txt", dir + "/two/calib.txt");
    for (const char* f : {"poses.txt", "times.txt"}) {
        std::ifstream in(seq + "/" + f);
        std::ofstream out(dir + "/two/" + f);
        std::string line;
        for (int i = 0; i < 2 && std::getline(in, line); ++i) out << line << "\n";
    }
    auto script = [&](const std::string& args) {
        const std::string command = "'" + std::string(GSEG_SOURCE_DIR) + "/tools/bench_vs_octomap.sh' -b '" + GSEG_BINARY_DIR +
                                    "' " + args + " > " + dir + "/out.txt 2> " + dir + "/err.txt";
        const int st = std::system(("bash -c \"" + command + "\"").c_str());
        return WIFEXITED(st) ? WEXITSTATUS(st) : 128;
    };
    ASSERT_EQ(script("-s " + dir + "/two -r 1 -n 1 -w " + dir + "/work"), 0) << gseg::test::readText(dir + "/err.txt");
    const std::string out = gseg::test::readText(dir + "/out.txt");
    EXPECT_TRUE(fs::exists(dir + "/work/two_x1.rawlog")) << out;
    EXPECT_NE(out.find("1      plain OctoMap"), std::string::npos) << out;
    EXPECT_NE(out.find("insertPointCloud"), std::string::npos) << out;
    EXPECT_NE(out.find("2 scans"), std::string::npos) << out;
    EXPECT_NE(out.find("x faster"), std::string::npos) << out;
    EXPECT_NE(out.find("load average before"), std::string::npos) << out;
    EXPECT_EQ(script("-s " + dir + "/two -q"), 2);
    EXPECT_NE(gseg::test::readText(dir + "/err.txt").find("usage: tools/bench_vs_octomap.sh"), std::string::npos);
    EXPECT_EQ(script("-s " + dir + "/none"), 2);
    EXPECT_NE(gseg::test::readText(dir + "/err.txt").find("not a KITTI sequence"), std::string::npos);
    fs::remove_all(dir);
}

// #12: the other ranks' threads are more workers of rank 0's pipeline; rank 0 alone maps, in order.
TEST(RawlogOctomapTool, TwoMpiRanksWriteTheMapsOfOneProcess) {
    GSEG_TEST_MPIRUN_OR_SKIP(mpirun, 2);
    const std::string dir = driveDir("mpi");
    const std::string args = "-i " + dir + "/drive.rawlog -c " + dir + "/gseg.yaml -o " + dir;
    const ToolRun one = runTool("rawlog-octomap", args + "/one --threads 1", dir);
    ASSERT_EQ(one.status, 0) << one.err;
    // --rank0-maps-only: rank 0 reads and maps, rank 1 does every scan's work.
    const ToolRun remote = runTool("rawlog-octomap", args + "/remote --threads 0 --rank0-maps-only", dir, "", mpirun);
    ASSERT_EQ(remote.status, 0) << remote.err;
    EXPECT_NE(remote.out.find("scans worked on: 0 on rank 0, 8 on rank 1"), std::string::npos) << remote.out;
    EXPECT_NE(remote.out.find("(summed over 1 worker thread(s) in 2 processes)"), std::string::npos) << remote.out;
    expectSameMaps(dir + "/one", dir + "/remote");
    // --threads 0: one rank per core, both ranks work; whoever is free takes the next scan.
    const ToolRun both = runTool("rawlog-octomap", args + "/both --threads 0 -v", dir, "", mpirun);
    ASSERT_EQ(both.status, 0) << both.err;
    EXPECT_NE(both.out.find("(summed over 2 worker thread(s) in 2 processes)"), std::string::npos) << both.out;
    // Rank 0 writes on two threads, which may use rank 1's core (mpirun binds each rank to one):
    // wherever this test may use two CPUs (under a narrower affinity mpirun may still bind rank 1
    // to another CPU, so the line is not ruled out there).
    const bool twoWriters = (both.out + both.err).find("rawlog-octomap: writing on 2 threads, ") != std::string::npos;
    if (gseg::usableCores() >= 2) {
        EXPECT_TRUE(twoWriters) << both.out << both.err;
    }
    EXPECT_NE(both.out.find("scans worked on: "), std::string::npos) << both.out;
    expectSameMaps(dir + "/one", dir + "/both");
    const auto voxels = [](const std::string& out) { return out.substr(out.find("voxels ("), out.find("map memory") - out.find("voxels (")); };
    EXPECT_EQ(voxels(both.out), voxels(one.out));
    EXPECT_EQ(messageLines(both.err).size(), 0u) << "progress only, from rank 0: " << both.err;
    fs::remove_all(dir);
}

// #35: ranks 0..3 each hold part of the voxels (bricks dealt by voxelOwner()) and apply their part of
// every scan in scan order; rank 0 merges them before writing: the files of one process, for 2 and
// 3 ranks, 1 to 3 threads each, and with rank 0 working on no scan.
TEST(RawlogOctomapTool, RanksHoldingPartsOfTheVoxelsWriteTheMapsOfOneProcess) {
    GSEG_TEST_MPIRUN_OR_SKIP(mpirun2, 2);
    GSEG_TEST_MPIRUN_OR_SKIP(mpirun3, 3);
    const std::string dir = driveDir("mpi_voxels");
    const std::string args = "-i " + dir + "/drive.rawlog -c " + dir + "/gseg.yaml -o " + dir;
    const ToolRun one = runTool("rawlog-octomap", args + "/one --threads 1", dir);
    ASSERT_EQ(one.status, 0) << one.err;
    EXPECT_EQ(one.out.find("voxel bricks held"), std::string::npos) << "one process holds every voxel: " << one.out;
    const std::size_t bricks = std::stoul(one.out.substr(one.out.find(" MB (") + 5));
    ASSERT_GT(bricks, 100u) << one.out;
    struct Case {
        const std::string& mpirun;
        int ranks;
        std::string options;
    };
    int run = 0;
    for (const Case& c : {Case{mpirun3, 3, "--threads 1"}, Case{mpirun2, 2, "--threads 3"}, Case{mpirun3, 3, "--threads 2 --rank0-maps-only"}}) {
        SCOPED_TRACE(std::to_string(c.ranks) + " ranks, " + c.options);
        const std::string name = "run" + std::to_string(++run);
        const ToolRun r = runTool("rawlog-octomap", args + "/" + name + " " + c.options, dir, "", c.mpirun);
        ASSERT_EQ(r.status, 0) << r.err;
        std::size_t files = 0;  // every file of one process's, byte for byte
        for (const auto& e : fs::directory_iterator(dir)) {
            const std::string f = e.path().filename().string();
            if (f.rfind("one_", 0) != 0) continue;
            ++files;
            std::string theirs = gseg::test::readText(dir + "/" + name + f.substr(3));
            for (std::size_t at; (at = theirs.find(name + "_")) != std::string::npos;) theirs.replace(at, name.size(), "one");  // the YAML names its PGM
            EXPECT_TRUE(gseg::test::readText(e.path().string()) == theirs) << f;
        }
        EXPECT_GE(files, 17u);
        // Every rank held and updated part of the voxels, the bricks of one process between them.
        const std::size_t at = r.out.find("voxel bricks held and updated: ");
        ASSERT_NE(at, std::string::npos) << r.out;
        std::istringstream held(r.out.substr(at + 31, r.out.find('\n', at) - at - 31));
        std::size_t sum = 0;
        for (int q = 0; q < c.ranks; ++q) {
            std::size_t n = 0;
            std::string on, rank, number;
            held >> n >> on >> rank >> number;
            EXPECT_EQ(number.substr(0, 1), std::to_string(q)) << r.out;
            EXPECT_GT(n, bricks / 8) << "rank " << q << " holds its share: " << r.out;
            sum += n;
        }
        EXPECT_EQ(sum, bricks) << r.out;
    }
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, KittiSequence00MapsAreTheSameBytesOnTwoRanks) {
    GSEG_TEST_MPIRUN_OR_SKIP(mpirun, 2);
    const std::string poses = gseg::test::sharedData("semantickitti/sequences/00/poses.txt");
    if (poses.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/00/poses.txt");
    const std::string dir = tempDir("mpi_kitti"), config = std::string(GSEG_SOURCE_DIR) + "/config/kitti_hdl64.yaml";
    ToolRun r = runTool("kitti2rawlog", fs::path(poses).parent_path().string() + " -o " + dir + "/seq00.rawlog", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string args = "-i " + dir + "/seq00.rawlog -c " + config + " --threads 1 -o " + dir;
    r = runTool("rawlog-octomap", args + "/one", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    r = runTool("rawlog-octomap", args + "/two", dir, "", mpirun);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("6 scans (0 from _ground/_obstacles pairs"), std::string::npos) << r.out;
    expectSameMaps(dir + "/one", dir + "/two");
    fs::remove_all(dir);
}

TEST(RawlogOctomapTool, UnderMpiASkippedOrFailingScanOnAnotherRankIsNamedAndNothingHangs) {
    GSEG_TEST_MPIRUN_OR_SKIP(mpirun, 2);
    const std::string dir = tempDir("mpi_bad");
    std::ofstream(dir + "/gseg.yaml") << "distToGround: 1.8\n";
    // A scan without points, worked on by rank 1: skipped and named as in one process, the others mapped.
    Drive empty;
    empty.emptyScan = 3;
    writeDrive(dir + "/empty.rawlog", empty);
    const std::string args = "-c " + dir + "/gseg.yaml --threads 0 --rank0-maps-only -i " + dir;
    const ToolRun one = runTool("rawlog-octomap", args + "/empty.rawlog -o " + dir + "/one", dir);
    const ToolRun two = runTool("rawlog-octomap", args + "/empty.rawlog -o " + dir + "/two", dir, "", mpirun);
    EXPECT_EQ(one.status, 3);
    EXPECT_EQ(two.status, 3) << "the exit code says a scan was skipped: " << two.err;
    EXPECT_NE(two.err.find("skipped scan 3 ('LIDAR' at rawlog entry 7"), std::string::npos) << two.err;
    EXPECT_NE(two.out.find("scans worked on: 0 on rank 0, 8 on rank 1"), std::string::npos) << two.out;
    expectSameMaps(dir + "/one", dir + "/two");
    // Every scan fails on rank 1 (a sensor outside the maps' extent): the first scan's error, one line, no maps.
    Drive utm;
    utm.offset = Eigen::Vector3d(500000.0, 5000000.0, 250.0);
    writeDrive(dir + "/utm.rawlog", utm);
    const ToolRun bad = runTool("rawlog-octomap", args + "/utm.rawlog -o " + dir + "/m", dir, "", mpirun);
    EXPECT_EQ(bad.status, 1) << bad.err;
    const auto lines = messageLines(bad.err);
    ASSERT_GE(lines.size(), 1u) << bad.err;
    EXPECT_EQ(lines[0].rfind("rawlog-octomap: scan 0 ('LIDAR' at rawlog entry 1", 0), 0u) << bad.err;
    EXPECT_NE(lines[0].find("--origin first"), std::string::npos) << bad.err;
    EXPECT_TRUE(mapFiles(dir + "/m").empty());
    // A bad argument: every rank refuses alike, exit 2, one message.
    const ToolRun usage = runTool("rawlog-octomap", args + "/utm.rawlog -o " + dir + "/m --resolution 0", dir, "", mpirun);
    EXPECT_EQ(usage.status, 2) << usage.err;
    const std::size_t first = usage.err.find("rawlog-octomap: --resolution needs a number > 0");
    EXPECT_NE(first, std::string::npos) << usage.err;
    EXPECT_EQ(first, usage.err.rfind("rawlog-octomap: --resolution")) << "from rank 0 only: " << usage.err;
    fs::remove_all(dir);
}

}  // namespace
