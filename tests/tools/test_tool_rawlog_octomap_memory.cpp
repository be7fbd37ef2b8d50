// rawlog-octomap's memory checks end to end (#18 point 2, #35): an option that cannot fit (under
// --max-memory and under `ulimit -v`) refused in one line, before any work, leaving nothing; a
// pose jump mapped in the memory of the ground seen, as tiles. The estimate itself:
// tests/map/test_memory_estimate.cpp.
#include <support/child.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

namespace fs = std::filesystem;

namespace {

// The tool: the six sequence-00 scans through kitti2rawlog.
class RawlogOctomapToolMemory : public ::testing::Test {
protected:
    void SetUp() override {
        const std::string seq = gseg::test::sharedData("semantickitti/sequences/00/poses.txt");
        if (seq.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/00/poses.txt");
        dir_ = gseg::test::freshDir("memory", ::testing::UnitTest::GetInstance()->current_test_info()->name());
        const auto r = gseg::test::runCommand("'" + gseg::test::tool("kitti2rawlog") + "' -q -i '" +
                                              fs::path(seq).parent_path().string() + "' -o '" + (dir_ / "seq00.rawlog").string() + "'");
        ASSERT_EQ(r.status, 0) << r.output;
    }
    /// rawlog-octomap on the drive with `args`, `limits` before it in sh; the seconds it took.
    gseg::test::CommandResult run(const std::string& args, const std::string& limits, double& seconds) {
        const auto t0 = std::chrono::steady_clock::now();
        auto r = gseg::test::runCommand("sh -c \"" + limits + "exec '" + gseg::test::tool("rawlog-octomap") + "' -i '" +
                                        (dir_ / "seq00.rawlog").string() + "' -o '" + (dir_ / "m").string() + "' -c '" +
                                        GSEG_SOURCE_DIR + "/config/kitti_hdl64.yaml' " + args + "\"");
        seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return r;
    }
    void expectNothingWritten() {
        EXPECT_EQ(gseg::test::entriesContaining(dir_.string(), "m_"), "") << "no map file";
        EXPECT_EQ(gseg::test::entriesContaining(dir_.string(), ".tmp"), "") << "no temporary";
    }
    fs::path dir_;
};

TEST_F(RawlogOctomapToolMemory, MaxMemoryRefusesBeforeAnyWorkNamingTheOptionsAndTheEstimate) {
    double seconds = 0;
    auto r = run("--resolution 0.1 --max-memory 150", "", seconds);
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_EQ(r.output.rfind("rawlog-octomap: --resolution 0.1 m needs about ", 0), 0u) << r.output;
    EXPECT_NE(r.output.find("MB for the maps and ray casting (estimated from scan 0 ('VELODYNE' at rawlog entry 2"),
              std::string::npos) << r.output;
    EXPECT_NE(r.output.find("124668 points, rays up to --max-range 50 m"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("more than --max-memory (150 MB); use a coarser --resolution or a shorter --max-range"),
              std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << "one line: " << r.output;
    EXPECT_LT(seconds, 30) << "before the work (the whole run takes longer)";
    expectNothingWritten();
    // Enough: the run goes on and writes the maps.
    r = run("--resolution 0.2 --max-memory 2G -q", "", seconds);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_TRUE(fs::exists(dir_ / "m_ground.bt"));
    // A size that is not one is bad usage.
    r = run("--max-memory 2X", "", seconds);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("--max-memory needs a size > 0 in MB, or with a unit (K, M, G, T: 2G), got '2X'"),
              std::string::npos) << r.output;
}

TEST_F(RawlogOctomapToolMemory, UnderUlimitVTheResolutionThatCannotFitIsRefusedNotKilled) {
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "ulimit -v and AddressSanitizer's shadow memory do not mix";
#else
    double seconds = 0;
    // Before: killed by the kernel after 73 s (24 GB machine), or under ulimit -v "std::bad_alloc".
    const auto r = run("--resolution 0.01", "ulimit -v 4000000; ", seconds);
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_EQ(r.output.rfind("rawlog-octomap: --resolution 0.01 m needs about ", 0), 0u) << r.output;
    EXPECT_NE(r.output.find("GB for the maps and ray casting"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("more than the address-space limit (ulimit -v) ("), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("or give --max-memory"), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << "one line: " << r.output;
    EXPECT_LT(seconds, 30);
    expectNothingWritten();
#endif
}

// #35: two scans 6 km apart diagonally (a GPS jump). Before the layers were sparse: grew to 18.6
// GB resident and was killed by the kernel after 147 s, writing nothing; then refused at the
// second scan. Now mapped under ulimit -v 4 GB: the layers in tiles where the scans saw the
// ground, the costmap as tiles and the layers as one COG (the box is about 21700 cells a side).
TEST_F(RawlogOctomapToolMemory, APoseJumpMapsInMemoryOfTheGroundSeenAsTiles) {
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "ulimit -v and AddressSanitizer's shadow memory do not mix";
#else
    const std::string seq = fs::path(gseg::test::sharedData("semantickitti/sequences/00/poses.txt")).parent_path().string();
    std::ofstream(dir_ / "jump.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 -4243 0 1 0 0 0 0 1 4243\n";  // camera frame: x right, z ahead
    auto r = gseg::test::runCommand("'" + gseg::test::tool("kitti2rawlog") + "' -q -i '" + seq + "' --first 0 --last 1 --poses '" +
                                    (dir_ / "jump.txt").string() + "' -o '" + (dir_ / "jump.rawlog").string() + "'");
    ASSERT_EQ(r.status, 0) << r.output;
    auto runJump = [&](const std::string& args, const std::string& limits, double& seconds) {
        const auto t0 = std::chrono::steady_clock::now();
        auto out = gseg::test::runCommand("sh -c \"" + limits + "exec '" + gseg::test::tool("rawlog-octomap") + "' -i '" +
                                          (dir_ / "jump.rawlog").string() + "' -o '" + (dir_ / "m").string() + "' -c '" +
                                          GSEG_SOURCE_DIR + "/config/kitti_hdl64.yaml' " + args + "\"");
        seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return out;
    };
    double seconds = 0;
    r = runJump("-q", "ulimit -v 4000000; ", seconds);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_LT(seconds, 120) << "not minutes of growing";
    EXPECT_TRUE(fs::exists(dir_ / "m_costmap_metadata.yaml"));
    EXPECT_TRUE(fs::exists(dir_ / "m_layers.tif"));
    EXPECT_FALSE(fs::exists(dir_ / "m_costmap.pgm")) << "a box of 21700 cells a side is written as tiles";
    EXPECT_NE(gseg::test::entriesContaining(dir_.string(), "m_costmap_"), "");
    EXPECT_EQ(gseg::test::entriesContaining(dir_.string(), ".tmp"), "") << "no temporary";
    // Forced to one grid of the box (--tiled-above beyond it): refused at the second scan, in one
    // line naming the box, the jump and the options to change.
    r = runJump("-q -w --tiled-above 100000", "ulimit -v 4000000; ", seconds);
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_EQ(r.output.rfind("rawlog-octomap: the scans up to scan 1 ('VELODYNE' at rawlog entry ", 0), 0u) << r.output;
    EXPECT_TRUE(std::regex_search(r.output, std::regex("cover 43[0-9][0-9] m x 43[0-9][0-9] m \\(x from -[0-9.]+ m, y from -[0-9.]+ m; [0-9]+ tiles")))
        << r.output;
    EXPECT_TRUE(std::regex_search(r.output, std::regex("the 2.5D layers need about [0-9]+ GB at --resolution 0.2 m, written as one grid of the box")))
        << r.output;
    EXPECT_NE(r.output.find("more than the address-space limit (ulimit -v) ("), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("the largest step between two scans is 6001 m (to scan 1): write the map as tiles (--tiles, or "
                            "--tiled-above below 100000 cells"), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << "one line: " << r.output;
    EXPECT_LT(seconds, 30) << "refused at once, not after growing for minutes";
    // The user's own limit is named as such.
    r = runJump("-q -w --tiled-above 100000 --max-memory 2G", "", seconds);
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("more than --max-memory (2.0 GB); the largest step"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("or give --max-memory"), std::string::npos) << r.output;
    // The same two scans 600 m apart: a box of 0.2 GB of layers, mapped.
    std::ofstream(dir_ / "jump.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 -424 0 1 0 0 0 0 1 424\n";
    r = gseg::test::runCommand("'" + gseg::test::tool("kitti2rawlog") + "' -q -w -i '" + seq + "' --first 0 --last 1 --poses '" +
                               (dir_ / "jump.txt").string() + "' -o '" + (dir_ / "jump.rawlog").string() + "'");
    ASSERT_EQ(r.status, 0) << r.output;
    r = runJump("-q -w --max-memory 2G", "", seconds);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_TRUE(fs::exists(dir_ / "m_layers.tif"));
    EXPECT_TRUE(fs::exists(dir_ / "m_costmap.pgm")) << "a box of about 3000 cells a side: one costmap";
#endif
}

}  // namespace
