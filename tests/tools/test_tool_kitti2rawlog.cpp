// kitti2rawlog: real SemanticKITTI sequence 00 frames 0-5 and small synthetic sequences.
#include <gseg/io/kitti.hpp>
#include <gseg/map/poses.hpp>
#include <gseg/mrpt/rawlog_io.hpp>
#include <support/child.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRobotPose.h>
#include <mrpt/serialization/CArchive.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/inotify.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

using gseg::test::ToolRun;

/// Runs kitti2rawlog (gseg::test::runTool): `limits` goes before it in bash (e.g. "ulimit -f 64; trap '' XFSZ;").
ToolRun runKitti2rawlog(const std::string& args, const std::string& dir, const std::string& limits = "") {
    return gseg::test::runTool("kitti2rawlog", args, dir, limits);
}

std::string tempDir(const std::string& name) { return gseg::test::freshDir("kitti2rawlog", name).string(); }

/// The drive's t = 0 by default: 2011-09-26 00:00:00 UTC [s since the UNIX epoch].
constexpr double kBase = 1316995200.0;

/// One frame: odometry, pose, scan, in this order (odometry and pose only with poses).
struct Entry {
    mrpt::obs::CObservationOdometry::Ptr odometry;
    mrpt::obs::CObservationRobotPose::Ptr pose;
    mrpt::obs::CObservationPointCloud::Ptr scan;
};

std::vector<Entry> readBack(const std::string& rawlog) {
    std::vector<Entry> out;
    auto open = [&]() -> Entry& {
        if (out.empty() || out.back().scan) out.emplace_back();
        return out.back();
    };
    gseg::mrpt::forEachRawlogEntry(rawlog, [&](std::size_t, const auto& obj) {
        if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(obj)) {
            Entry& e = open();
            EXPECT_FALSE(e.odometry || e.pose) << "odometry comes first in a frame";
            e.odometry = o;
        } else if (auto p = std::dynamic_pointer_cast<mrpt::obs::CObservationRobotPose>(obj)) {
            Entry& e = open();
            EXPECT_TRUE(e.odometry && !e.pose) << "the pose follows the odometry";
            e.pose = p;
        } else if (auto s = std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(obj)) {
            open().scan = s;
        } else {
            ADD_FAILURE() << "unexpected object " << obj->GetRuntimeClass()->className;
        }
        return true;
    });
    return out;
}

/// The odometry is the pose in 2D, at the same time.
void expectOdometryIsThePose(const Entry& e) {
    ASSERT_TRUE(e.odometry && e.pose);
    EXPECT_NEAR(e.odometry->odometry.x(), e.pose->pose.mean.x(), 1e-9);
    EXPECT_NEAR(e.odometry->odometry.y(), e.pose->pose.mean.y(), 1e-9);
    EXPECT_NEAR(e.odometry->odometry.phi(), e.pose->pose.mean.yaw(), 1e-9);
    EXPECT_EQ(e.odometry->timestamp, e.pose->timestamp);
}

Eigen::Matrix4d matrixOf(const mrpt::poses::CPose3D& p) {
    Eigen::Matrix4d m;
    const auto h = p.getHomogeneousMatrixVal<mrpt::math::CMatrixDouble44>();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = h(r, c);
    return m;
}

/// A tiny sequence: `frames` scans of 3 points (or `points` pseudo-random ones), optional poses
/// (identity + 1 m steps).
std::string syntheticSequence(const std::string& name, int frames, int poseLines, bool times, std::size_t points = 0) {
    const std::string dir = tempDir(name);
    fs::create_directories(dir + "/velodyne");
    for (int k = 0; k < frames; ++k) {
        std::vector<float> pts = {1, 0, -1.7f, 0.5f, 2, 1, -1.7f, 0.2f, 5, 0, 0, 0.9f};
        std::uint32_t x = 12345u + std::uint32_t(k);
        for (std::size_t i = 0; i < 4 * points; ++i) pts.push_back(float((x = x * 1664525u + 1013904223u) >> 8) * 1e-5f);
        char n[32];
        std::snprintf(n, sizeof n, "/velodyne/%06d.bin", k);
        gseg::io::writeFileAtomic(dir + n, pts.data(), pts.size() * sizeof(float));
    }
    if (poseLines > 0) {
        std::ofstream p(dir + "/poses.txt");
        for (int k = 0; k < poseLines; ++k) p << "1 0 0 0 0 1 0 0 0 0 1 " << k << "\n";
        std::ofstream(dir + "/calib.txt") << "Tr: 0 -1 0 0 0 0 -1 0 1 0 0 0\n";
    }
    if (times) {
        std::ofstream t(dir + "/times.txt");
        for (int k = 0; k < frames; ++k) t << 0.5 * k << "\n";
    }
    return dir;
}

TEST(Kitti2RawlogTool, Sequence00WithPosesTimesAndSimplemap) {
    const std::string seq = gseg::test::sharedData("semantickitti/sequences/00/poses.txt");
    if (seq.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/00/poses.txt");
    const std::string seqDir = fs::path(seq).parent_path().string(), dir = tempDir("seq00");
    const ToolRun r = runKitti2rawlog(seqDir + " -o " + dir + "/seq00.rawlog --simplemap " + dir + "/seq00.simplemap", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const auto entries = readBack(dir + "/seq00.rawlog");
    ASSERT_EQ(entries.size(), 6u);
    const auto velo = gseg::map::kittiToVelodyneFrame(gseg::map::readKittiPoses(seqDir + "/poses.txt"),
                                                      gseg::map::readKittiCalibTr(seqDir + "/calib.txt"));
    const double times[6] = {0.0, 0.1037359, 0.2073381, 0, 0, 0};
    for (std::size_t k = 0; k < 6; ++k) {
        ASSERT_TRUE(entries[k].pose && entries[k].scan) << "frame " << k;
        char bin[64];
        std::snprintf(bin, sizeof bin, "/velodyne/%06zu.bin", k);
        EXPECT_EQ(entries[k].scan->pointcloud->size(), gseg::io::readKittiBin(seqDir + bin).size() / 4);
        EXPECT_TRUE(matrixOf(entries[k].pose->pose.mean).isApprox(velo[k].matrix(), 1e-6)) << "frame " << k;
        EXPECT_EQ(entries[k].pose->timestamp, entries[k].scan->timestamp);
        expectOdometryIsThePose(entries[k]);
        if (k < 3) {
            EXPECT_NEAR(mrpt::Clock::toDouble(entries[k].scan->timestamp), kBase + times[k], 1e-6);
        }
        EXPECT_TRUE(entries[k].scan->sensorPose == mrpt::poses::CPose3D());
    }
    mrpt::maps::CSimpleMap sm;
    mrpt::io::CFileGZInputStream f(dir + "/seq00.simplemap");
    mrpt::serialization::archiveFrom(f) >> sm;
    EXPECT_EQ(sm.size(), 6u);
    fs::remove_all(dir);
}

TEST(Kitti2RawlogTool, FrameRangeStartsTheWorldAtTheFirstScan) {
    const std::string seq = gseg::test::sharedData("semantickitti/sequences/00/poses.txt");
    if (seq.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/00/poses.txt");
    const std::string seqDir = fs::path(seq).parent_path().string(), dir = tempDir("range");
    const ToolRun r = runKitti2rawlog(seqDir + " -o " + dir + "/r.rawlog --first 2 --last 4", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const auto entries = readBack(dir + "/r.rawlog");
    ASSERT_EQ(entries.size(), 3u);
    const auto velo = gseg::map::kittiToVelodyneFrame(gseg::map::readKittiPoses(seqDir + "/poses.txt"),
                                                      gseg::map::readKittiCalibTr(seqDir + "/calib.txt"));
    EXPECT_TRUE(matrixOf(entries[0].pose->pose.mean).isApprox(Eigen::Matrix4d::Identity(), 1e-6));
    EXPECT_TRUE(matrixOf(entries[2].pose->pose.mean).isApprox((velo[2].inverse() * velo[4]).matrix(), 1e-6));
    fs::remove_all(dir);
}

TEST(Kitti2RawlogTool, WithoutTimesAndPosesWritesScansAt10Hz) {
    const std::string seq = syntheticSequence("bare", 3, 0, false), dir = tempDir("bare_out");
    const ToolRun r = runKitti2rawlog(seq + " -o " + dir + "/b.rawlog", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const auto entries = readBack(dir + "/b.rawlog");
    ASSERT_EQ(entries.size(), 3u);
    for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_FALSE(entries[k].pose || entries[k].odometry);
        EXPECT_NEAR(mrpt::Clock::toDouble(entries[k].scan->timestamp), kBase + 0.1 * double(k), 1e-6);
        EXPECT_EQ(entries[k].scan->pointcloud->size(), 3u);
    }
    fs::remove_all(seq), fs::remove_all(dir);
}

TEST(Kitti2RawlogTool, BadInputIsAClearErrorAndNoFile) {
    const std::string seq = syntheticSequence("few", 4, 2, true), dir = tempDir("few_out");
    ToolRun r = runKitti2rawlog(seq + " -o " + dir + "/f.rawlog", dir);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("fewer poses than scans"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir + "/f.rawlog"));
    r = runKitti2rawlog(dir + "/nowhere -o " + dir + "/g.rawlog", dir);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("kitti2rawlog: "), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir + "/g.rawlog"));
    for (const auto& e : fs::directory_iterator(dir))
        EXPECT_TRUE(e.path().filename() == "out.txt" || e.path().filename() == "err.txt") << "left behind: " << e.path();
    fs::remove_all(seq), fs::remove_all(dir);
}

void expectNothingLeftBehind(const std::string& dir) {
    for (const auto& e : fs::directory_iterator(dir))
        EXPECT_TRUE(e.path().filename() == "out.txt" || e.path().filename() == "err.txt") << "left behind: " << e.path();
}

TEST(Kitti2RawlogTool, BadPosesCalibrationAndTimesNameFileAndLine) {
    // #9 item 10: a scaled rotation, an all-zero Tr, NaN in times.txt.
    struct Case {
        const char* file;
        std::string text, expect;
    };
    const Case cases[] = {{"poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n2 0 0 1 0 2 0 0 0 0 2 0\n1 0 0 2 0 1 0 0 0 0 1 0\n",
                           "/poses.txt:2: the 3x3 part is not a rotation"},
                          {"calib.txt", "Tr: 0 0 0 0 0 0 0 0 0 0 0 0\n", "/calib.txt:1: the 3x3 part is not a rotation"},
                          {"times.txt", "0.0\nnan\n1.0\n", "/times.txt:2: 'nan' is not a finite number"},
                          // #18 point 6: beyond what an MRPT time stamp holds (1e13 s wrapped to 1970), or negative.
                          {"times.txt", "0.0\n1e13\n1e13\n", "/times.txt:2: time 10000000000000 s is outside 0 to"},
                          {"times.txt", "0.0\n0.1\n1e18\n", "/times.txt:3: time 1e+18 s is outside 0 to"},
                          {"times.txt", "0.0\n0.1\n1e30\n", "/times.txt:3: time 1e+30 s is outside 0 to"},
                          {"times.txt", "-5\n0.1\n0.2\n", "/times.txt:1: time -5 s is outside 0 to"}};
    for (const auto& c : cases) {
        const std::string seq = syntheticSequence("badfile", 3, 3, true), dir = tempDir("badfile_out");
        std::ofstream(seq + "/" + c.file) << c.text;
        const ToolRun r = runKitti2rawlog(seq + " -o " + dir + "/x.rawlog", dir);
        EXPECT_EQ(r.status, 1) << c.file;
        EXPECT_NE(r.err.find(c.expect), std::string::npos) << r.err;
        expectNothingLeftBehind(dir);
        fs::remove_all(seq), fs::remove_all(dir);
    }
}

// #18 point 6: the last time stamp (--start-time + times.txt) must be a date a time stamp holds.
TEST(Kitti2RawlogTool, ATimeStampAfterTheYear9999IsRefusedNamingTimesTxt) {
    const std::string seq = syntheticSequence("latetime", 3, 3, true), dir = tempDir("latetime_out");
    std::ofstream(seq + "/times.txt") << "0\n1\n1e9\n";
    ToolRun r = runKitti2rawlog(seq + " -o " + dir + "/x.rawlog --start-time 9999-01-01", dir);
    EXPECT_EQ(r.status, 1) << r.err;
    EXPECT_NE(r.err.find("/times.txt: the last frame's time stamp (--start-time + 1000000000 s) is after 9999-12-31"),
              std::string::npos) << r.err;
    expectNothingLeftBehind(dir);
    r = runKitti2rawlog(seq + " -o " + dir + "/x.rawlog --start-time 2011-09-26", dir);  // 1e9 s later: 2043
    EXPECT_EQ(r.status, 0) << r.err;
    fs::remove_all(seq), fs::remove_all(dir);
}

TEST(Kitti2RawlogTool, AnInputAsOutputIsRefusedBeforeAnythingIsWritten) {
    // #9 item 7: `kitti2rawlog SEQ -o SEQ/velodyne/000001.bin` destroyed the scan.
    const std::string seq = syntheticSequence("same", 3, 3, true), dir = tempDir("same_out");
    for (const std::string& target : {seq + "/velodyne/000001.bin", seq + "/poses.txt"}) {
        const std::string before = gseg::test::readText(target);
        const ToolRun r = runKitti2rawlog(seq + " -o " + target, dir);
        EXPECT_EQ(r.status, 2) << target;
        EXPECT_NE(r.err.find("is the input"), std::string::npos) << r.err;
        EXPECT_TRUE(gseg::test::readText(target) == before) << target;
    }
    ToolRun r = runKitti2rawlog(seq + " -o " + dir + "/a.rawlog --simplemap " + dir + "/a.rawlog", dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("name the same file"), std::string::npos) << r.err;
    r = runKitti2rawlog(seq + " -o " + dir + "/missing/a.rawlog", dir);  // fail early, bad usage
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("kitti2rawlog: 1 scans"), std::string::npos) << "no scan converted: " << r.err;
    expectNothingLeftBehind(dir);
    fs::remove_all(seq), fs::remove_all(dir);
}

TEST(Kitti2RawlogTool, DiskFullIsAnErrorAndNoFile) {
    // #9 item 6: a full disk gave "wrote ..." and exit 0 with a truncated rawlog. The file size
    // limit (EFBIG once the signal is ignored) stands in for a full disk.
    const std::string seq = syntheticSequence("full", 3, 3, true, 20000), dir = tempDir("full_out");
    const ToolRun r = runKitti2rawlog(seq + " -o " + dir + "/f.rawlog --simplemap " + dir + "/f.simplemap", dir,
                              "ulimit -f 64; trap '' XFSZ;");
    EXPECT_EQ(r.status, 1) << r.err;
    EXPECT_NE(r.err.find(dir + "/f.rawlog: write failed after "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(" bytes (File too large)"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("wrote"), std::string::npos) << r.err;
    expectNothingLeftBehind(dir);
    // The same without the limit works.
    EXPECT_EQ(runKitti2rawlog(seq + " -o " + dir + "/f.rawlog", dir).status, 0);
    EXPECT_EQ(readBack(dir + "/f.rawlog").size(), 3u);
    fs::remove_all(seq), fs::remove_all(dir);
}

TEST(Kitti2RawlogTool, RepeatContinuesTheTrajectory) {
    // Poses: 1 m steps along camera z = velodyne x; times 0.5 s apart.
    const std::string seq = syntheticSequence("repeat", 3, 3, true), dir = tempDir("repeat_out");
    const ToolRun r = runKitti2rawlog(seq + " -o " + dir + "/r.rawlog --repeat 3", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const auto entries = readBack(dir + "/r.rawlog");
    ASSERT_EQ(entries.size(), 9u);
    for (std::size_t n = 0; n < 9; ++n) {
        ASSERT_TRUE(entries[n].pose && entries[n].scan);
        EXPECT_NEAR(entries[n].pose->pose.mean.x(), double(n), 1e-6) << n;
        EXPECT_NEAR(entries[n].pose->pose.mean.y(), 0.0, 1e-6) << n;
        EXPECT_NEAR(mrpt::Clock::toDouble(entries[n].scan->timestamp), kBase + 0.5 * double(n), 1e-6) << n;
        expectOdometryIsThePose(entries[n]);
        EXPECT_EQ(entries[n].scan->pointcloud->size(), 3u);
    }
    fs::remove_all(seq), fs::remove_all(dir);
}

TEST(Kitti2RawlogTool, StartTimeSetsTheBaseDate) {
    const std::string seq = syntheticSequence("start", 2, 2, true), dir = tempDir("start_out");
    ASSERT_EQ(runKitti2rawlog("-i " + seq + " -o " + dir + "/s.rawlog --start-time 2020-02-29T12:30:15.25Z", dir).status, 0);
    const auto entries = readBack(dir + "/s.rawlog");
    ASSERT_EQ(entries.size(), 2u);
    const double base = 1582979415.25;  // 2020-02-29 12:30:15.25 UTC
    EXPECT_NEAR(mrpt::Clock::toDouble(entries[0].scan->timestamp), base, 1e-6);
    EXPECT_NEAR(mrpt::Clock::toDouble(entries[1].scan->timestamp), base + 0.5, 1e-6);
    ASSERT_EQ(runKitti2rawlog("-i " + seq + " -o " + dir + "/d.rawlog --start-time 2012-01-01", dir).status, 0);
    EXPECT_NEAR(mrpt::Clock::toDouble(readBack(dir + "/d.rawlog")[0].scan->timestamp), 1325376000.0, 1e-6);
    for (const char* bad : {"yesterday", "2020-13-01", "2020-02-29T25:00:00", "1970-01-01", "2020-02-29Tnoon"}) {
        const ToolRun r = runKitti2rawlog("-i " + seq + " -o " + dir + "/x.rawlog --start-time " + bad, dir);
        EXPECT_EQ(r.status, 2) << bad;
        EXPECT_NE(r.err.find("--start-time needs a UTC date"), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(dir + "/x.rawlog")) << bad;
    }
    fs::remove_all(seq), fs::remove_all(dir);
}

TEST(Kitti2RawlogTool, InputOptionAndTheOldPositionalFormGiveTheSameRawlog) {
    const std::string seq = syntheticSequence("forms", 3, 3, true), dir = tempDir("forms_out");
    ASSERT_EQ(runKitti2rawlog("-i " + seq + " -o " + dir + "/a.rawlog", dir).status, 0);
    ASSERT_EQ(runKitti2rawlog(seq + " -o " + dir + "/b.rawlog", dir).status, 0);
    EXPECT_TRUE(gseg::test::readText(dir + "/a.rawlog") == gseg::test::readText(dir + "/b.rawlog"));
    ToolRun r = runKitti2rawlog("-i " + seq + " " + seq + " -o " + dir + "/c.rawlog", dir);  // both: ambiguous
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("give the sequence folder once"), std::string::npos) << r.err;
    r = runKitti2rawlog("-o " + dir + "/c.rawlog", dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("needs the sequence folder"), std::string::npos) << r.err;
    r = runKitti2rawlog("-i " + seq + " -o " + dir + "/c.rawlog --first x", dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(runKitti2rawlog("--version", dir).status, 0);
    EXPECT_EQ(runKitti2rawlog("--help", dir).status, 0);
    EXPECT_FALSE(fs::exists(dir + "/c.rawlog"));
    fs::remove_all(seq), fs::remove_all(dir);
}

}  // namespace

// #9 item 9 for the map layer's outputs (kitti2rawlog, rawlog-octomap): a run ended by a signal
// leaves no temporary file. strace delivers SIGTERM at the second look at the only scan: the first
// is the check of the inputs before any output, the second the reading, after the temporary rawlog
// was made (no sleeps). (The scan was a FIFO the tool waited on in open(); since #34 a FIFO is
// refused before it is opened, which this test checks too.)
TEST(Kitti2RawlogTool, InterruptedRunLeavesNoTemporary) {
    const fs::path dir = gseg::test::freshDir("kitti2rawlog", "interrupted");
    fs::create_directories(dir / "seq/velodyne");
    const fs::path scan = dir / "seq/velodyne/000000.bin";
    ASSERT_EQ(::mkfifo(scan.c_str(), 0600), 0);
    const auto fifo = gseg::test::runCommand("timeout 60 " + gseg::test::tool("kitti2rawlog") + " -i " + (dir / "seq").string() +
                                             " -o " + (dir / "out.rawlog").string() + " -q 2>&1");
    EXPECT_EQ(fifo.status, 1) << fifo.output;
    EXPECT_NE(fifo.output.find("000000.bin: not a regular file (a FIFO)"), std::string::npos) << fifo.output;
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), "out.rawlog"), "");
    if (gseg::test::runCommand("command -v strace").status != 0) GTEST_SKIP() << "strace is not installed (apt-get install strace)";
    if (gseg::test::runCommand("strace -o /dev/null true").status != 0) GTEST_SKIP() << "strace cannot trace here (ptrace refused)";
    fs::remove(scan);
    const std::vector<float> points(4 * 100, 1.f);
    std::ofstream(scan, std::ios::binary).write(reinterpret_cast<const char*>(points.data()), std::streamsize(points.size() * 4));
    const std::string trace = (dir / "trace.txt").string();
    const auto r = gseg::test::runCommand("strace -f -o " + trace + " -P " + scan.string() +
                                          " -e inject=all:signal=SIGTERM:when=2 " + gseg::test::tool("kitti2rawlog") + " -i " +
                                          (dir / "seq").string() + " -o " + (dir / "out.rawlog").string() + " -q 2>&1");
    EXPECT_EQ(r.status, 128 + SIGTERM) << r.output;
    EXPECT_NE(gseg::test::readText(trace).find("SIGTERM"), std::string::npos) << gseg::test::readText(trace);
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), "out.rawlog"), "");
    EXPECT_NE(r.output.find("kitti2rawlog: interrupted (SIGTERM)"), std::string::npos) << r.output;
}
