// rawlog-gseg end to end: ground / obstacle pairs, pass-through, hostile inputs and runs, batches and
// MPI, the drive's context (#31). The filter itself: tests/mrpt/test_ground_filter.cpp.
#include <gseg/io/kitti.hpp>
#include <gseg/mrpt/rawlog_io.hpp>
#include <support/labelled_drive.hpp>
#include <support/sim_observations.hpp>
#include <support/child.hpp>
#include <support/lidar_sim.hpp>
#include <support/paths.hpp>

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/maps/CPointsMapXYZI.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3D.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

const std::string kVlp16 = "/usr/share/mrpt/datasets/test_velodyne_VLP16.rawlog";
const std::string kKfSlam = "/usr/share/mrpt/datasets/kf-slam_6D_demo.rawlog";
const fs::path kDir = fs::path(GSEG_BINARY_DIR) / "tests" / "rawlog_gseg_tool";

/// The built rawlog-gseg with `args` (shell words): exit status and stdout + stderr.
gseg::test::CommandResult rawlogGseg(const std::string& args) { return gseg::test::runToolCommand("rawlog-gseg", args); }

std::vector<std::string> entryClasses(const std::string& rawlog) {
    std::vector<std::string> out;
    gseg::mrpt::forEachRawlogEntry(rawlog, [&](std::size_t, const auto& obj) {
        out.push_back(obj->GetRuntimeClass()->className);
        if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(obj))
            for (const auto& o : *sf) out.back() += std::string(" ") + o->GetRuntimeClass()->className;
        return true;
    });
    return out;
}

}  // namespace

TEST(RawlogGsegTool, Vlp16RawlogGetsGroundAndObstacleObservations) {
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " absent (package mrpt-common)";
    fs::create_directories(kDir);
    const std::string out = (kDir / "vlp16.rawlog").string();
    const auto r = rawlogGseg("-w -i '" + kVlp16 + "' -o '" + out +
                                          "' -c '" GSEG_SOURCE_DIR "/config/vlp16.yaml'");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("1 scans segmented, 11305 points"), std::string::npos) << r.output;
    std::size_t ground = 0, obstacles = 0, entries = 0;
    gseg::mrpt::forEachRawlogEntry(out, [&](std::size_t, const auto& obj) {
        ++entries;
        if (auto pc = std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(obj)) {
            if (pc->sensorLabel == "Velodyne1_SCAN_ground") ground = pc->pointcloud->size();
            if (pc->sensorLabel == "Velodyne1_SCAN_obstacles") obstacles = pc->pointcloud->size();
        }
        return true;
    });
    EXPECT_EQ(entries, 3u);  // the scan, its ground, its obstacles
    EXPECT_EQ(ground + obstacles, 11305u);
    EXPECT_EQ(ground, 2224u);  // the same as `gseg segment` with this config (distToGround: auto)

    auto rep = rawlogGseg("-i '" + kVlp16 + "' -o '" + out +
                                      "' --replace");
    EXPECT_EQ(rep.status, 2) << "the previous output is not replaced without -w: " << rep.output;
    EXPECT_EQ(entryClasses(out).size(), 3u);
    rep = rawlogGseg("-i '" + kVlp16 + "' -o '" + out + "' --replace -w");
    ASSERT_EQ(rep.status, 0) << rep.output;
    EXPECT_EQ(entryClasses(out).size(), 2u);
}

// The KITTI defaults on the VLP-16 scan (2.27 m up) find 0.6 % ground: the run says why, once.
TEST(RawlogGsegTool, AFixedHeightThatTheScanContradictsIsSaid) {
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " absent (package mrpt-common)";
    fs::create_directories(kDir);
    const std::string out = (kDir / "vlp16_kitti.rawlog").string();
    const auto r = rawlogGseg("-w -i '" + kVlp16 + "' -o '" + out +
                                          "' -c '" GSEG_SOURCE_DIR "/config/kitti_hdl64.yaml'");
    ASSERT_EQ(r.status, 0) << "a warning, not an error: " << r.output;
    EXPECT_NE(r.output.find("entry 0 ('Velodyne1_SCAN'): the ground lies 2.27 m below the sensor"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("distToGround is 1.723 m"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("0.6 % ground"), std::string::npos) << "what the warning is about: " << r.output;
    const auto right = rawlogGseg("-w -i '" + kVlp16 + "' -o '" +
                                              out + "' -c '" GSEG_SOURCE_DIR "/config/vlp16.yaml'");
    ASSERT_EQ(right.status, 0) << right.output;
    EXPECT_EQ(right.output.find("the ground lies"), std::string::npos) << "auto: nothing to say: " << right.output;
    const auto quiet = rawlogGseg("-q -w -i '" + kVlp16 + "' -o '" +
                                              out + "' -c '" GSEG_SOURCE_DIR "/config/kitti_hdl64.yaml'");
    ASSERT_EQ(quiet.status, 0) << quiet.output;
    EXPECT_EQ(quiet.output, "") << "--quiet prints errors only";
}

TEST(RawlogGsegTool, SensoryFrameLayoutPassesThroughEntryForEntry) {
    if (!fs::exists(kKfSlam)) GTEST_SKIP() << kKfSlam << " absent (package mrpt-common)";
    fs::create_directories(kDir);
    const std::string out = (kDir / "kf.rawlog").string();
    const auto r = rawlogGseg("-w -i '" + kKfSlam + "' -o '" + out + "'");
    // No 3D scan in it (2D laser scans): every entry passed through, and exit 3 saying so (#34; it
    // was 0 with "0 scans segmented", where rawlog-octomap refuses the rawlog).
    ASSERT_EQ(r.status, 3) << r.output;
    EXPECT_NE(r.output.find("rawlog-gseg: no 3D LiDAR scan in the rawlog (CObservationPointCloud, "), std::string::npos) << r.output;
    EXPECT_EQ(entryClasses(out), entryClasses(kKfSlam));  // 600 sensory frames + 600 actions, none dropped
}

TEST(RawlogGsegTool, CorruptInputNamesTheEntryAndLeavesNoOutput) {
    if (!fs::exists(kKfSlam)) GTEST_SKIP() << kKfSlam << " absent (package mrpt-common)";
    fs::create_directories(kDir);
    // A plain copy of the demo rawlog, cut in the middle of an entry.
    const std::string plain = (kDir / "plain.rawlog").string(), cut = (kDir / "cut.rawlog").string();
    ASSERT_EQ(std::system(("gzip -dc '" + kKfSlam + "' > '" + plain + "' 2>/dev/null || cp '" + kKfSlam + "' '" +
                           plain + "'").c_str()), 0);
    const auto size = fs::file_size(plain);
    fs::copy_file(plain, cut, fs::copy_options::overwrite_existing);
    fs::resize_file(cut, size / 2 + 7);
    const std::string out = (kDir / "never.rawlog").string();
    fs::remove(out);
    auto r = rawlogGseg("-i '" + cut + "' -o '" + out + "'");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("entry "), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out));
    std::ofstream(kDir / "garbage.rawlog") << "not a rawlog, just text";
    r = rawlogGseg("-i '" + (kDir / "garbage.rawlog").string() +
                               "' -o '" + out + "'");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("garbage.rawlog: not an MRPT rawlog"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out));
    for (const auto& e : fs::directory_iterator(kDir))
        EXPECT_EQ(e.path().string().find("never.rawlog.gseg-"), std::string::npos) << "temporary left behind";
}

TEST(RawlogGsegTool, StockRawlogEditReadsTheOutputWithThePluginLoaded) {
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " absent (package mrpt-common)";
    if (!fs::exists("/usr/bin/rawlog-edit")) GTEST_SKIP() << "rawlog-edit absent (package mrpt-apps)";
    fs::create_directories(kDir);
    const std::string out = (kDir / "plugin.rawlog").string();
    ASSERT_EQ(rawlogGseg("-w -i '" + kVlp16 + "' -o '" + out + "'").status, 0);
    const auto r = gseg::test::runCommand(GSEG_PLUGIN_HOST_ENV "rawlog-edit -p '" GSEG_BINARY_DIR
                                          "/lib/libgseg_mrpt.so' --info -i '" + out + "'");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("Velodyne1_SCAN_ground"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("Velodyne1_SCAN_obstacles"), std::string::npos) << r.output;
}

// --- rawlog-gseg on hostile runs (issue #9 items 6 to 9, 11; #10 item 5) ----------------------------

namespace {

const std::string kRotScan = "/usr/share/mrpt/datasets/rot_scan_velodyne.rawlog";

using gseg::test::simulatedCloud;
using gseg::test::streetScan;

}  // namespace

namespace {

using gseg::test::q;

/// sensorLabels of every observation, entry by entry (a sensory frame's joined by '+').
std::vector<std::string> entryLabels(const std::string& rawlog) {
    std::vector<std::string> out;
    gseg::mrpt::forEachRawlogEntry(rawlog, [&](std::size_t, const auto& obj) {
        if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj)) out.push_back(o->sensorLabel);
        else if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(obj)) {
            std::string all;
            for (const auto& o : *sf) all += (all.empty() ? "" : "+") + o->sensorLabel;
            out.push_back(all);
        } else out.push_back(obj->GetRuntimeClass()->className);
        return true;
    });
    return out;
}

fs::path freshDir(const std::string& name) { return gseg::test::freshDir("rawlog_gseg_tool", name); }

std::string fileBytes(const fs::path& p) { return gseg::test::readText(p.string()); }

}  // namespace

TEST(RawlogGsegToolHostile, InputAsOutputIsRefusedBeforeAnythingIsWritten) {
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " absent (package mrpt-common)";
    const fs::path dir = freshDir("same");
    fs::copy_file(kVlp16, dir / "x.rawlog");
    fs::create_hard_link(dir / "x.rawlog", dir / "hard.rawlog");
    fs::create_symlink(dir / "x.rawlog", dir / "soft.rawlog");
    const std::string before = fileBytes(dir / "x.rawlog");
    for (const char* out : {"x.rawlog", "hard.rawlog", "soft.rawlog", "./x.rawlog"}) {
        const auto r = rawlogGseg("-i " + q(dir / "x.rawlog") + " -o " + q(dir / out) + " --replace");
        EXPECT_EQ(r.status, 2) << out << "\n" << r.output;
        EXPECT_NE(r.output.find("refusing to overwrite an input"), std::string::npos) << r.output;
    }
    EXPECT_EQ(fileBytes(dir / "x.rawlog"), before);
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp"), "");
}

TEST(RawlogGsegToolHostile, FullDiskIsAnErrorAndLeavesNothing) {
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " absent (package mrpt-common)";
    const fs::path dir = freshDir("full");
    // A file-size limit of 40 blocks: the output cannot be written completely, exactly as on a full
    // disk (before: "wrote ..." and exit 0 with a truncated gzip).
    const auto r = gseg::test::runCommand("ulimit -f 40; exec '" + gseg::test::tool("rawlog-gseg") + "' -i '" + kVlp16 +
                                          "' -o " + q(dir / "out.rawlog"));
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("File too large"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("wrote"), std::string::npos) << r.output;
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ""), "");
}

TEST(RawlogGsegToolHostile, OneBadScanDoesNotSinkTheRun) {
    const fs::path dir = freshDir("badscan");
    const auto scan = streetScan();
    // Observation layout: a good scan, a scan with no-return NaNs, a Velodyne scan whose vectors
    // differ in length (cannot be segmented), a 2D scan (not LiDAR), another good scan.
    auto good = std::make_shared<mrpt::obs::CObservationPointCloud>(simulatedCloud(scan));
    good->sensorLabel = "GOOD";
    auto holed = std::make_shared<mrpt::obs::CObservationPointCloud>(simulatedCloud(scan));
    holed->sensorLabel = "HOLES";
    for (int k = 0; k < 4; ++k) holed->pointcloud->insertPoint(std::numeric_limits<float>::quiet_NaN(), 0, 0);
    auto broken = std::make_shared<mrpt::obs::CObservationVelodyneScan>();
    broken->sensorLabel = "BROKEN";
    broken->point_cloud.x.assign(1000, 1.f);
    broken->point_cloud.y.assign(10, 1.f);
    broken->point_cloud.z.assign(10, 1.f);
    auto laser = std::make_shared<mrpt::obs::CObservation2DRangeScan>();
    laser->sensorLabel = "LASER";
    {
        gseg::mrpt::RawlogWriter w((dir / "in.rawlog").string());
        for (const mrpt::obs::CObservation* o : std::initializer_list<const mrpt::obs::CObservation*>{
                 good.get(), holed.get(), broken.get(), laser.get(), good.get()})
            w.write(*o);
        // Sensory-frame layout: one frame holding a broken and a good scan.
        mrpt::obs::CSensoryFrame sf;
        sf.insert(broken);
        sf.insert(good);
        w.write(sf);
        w.commit();
    }
    std::ofstream(dir / "c.yaml") << "distToGround: 1.73\n";
    const auto r = rawlogGseg("-i " + q(dir / "in.rawlog") + " -o " + q(dir / "out.rawlog") + " -c " + q(dir / "c.yaml"));
    EXPECT_EQ(r.status, 3) << r.output;  // finished, but something was skipped
    EXPECT_NE(r.output.find("entry 2 ('BROKEN') skipped, passed through unchanged: "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("entry 5 ('BROKEN') skipped"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("4 scans segmented"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("4 non-finite points labelled non-ground"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("2 skipped"), std::string::npos) << r.output;
    EXPECT_EQ(entryLabels((dir / "out.rawlog").string()),
              (std::vector<std::string>{"GOOD", "GOOD_ground", "GOOD_obstacles", "HOLES", "HOLES_ground",
                                        "HOLES_obstacles", "BROKEN", "LASER", "GOOD", "GOOD_ground", "GOOD_obstacles",
                                        "BROKEN+GOOD+GOOD_ground+GOOD_obstacles"}));
    // --replace still passes the unsegmentable scan through.
    const auto rep = rawlogGseg("-i " + q(dir / "in.rawlog") + " -o " + q(dir / "rep.rawlog") + " --replace -c " +
                                q(dir / "c.yaml"));
    EXPECT_EQ(rep.status, 3) << rep.output;
    const auto replaced = entryLabels((dir / "rep.rawlog").string());
    EXPECT_EQ(std::count(replaced.begin(), replaced.end(), "BROKEN"), 1) << "the broken scan must be kept";
    EXPECT_EQ(std::count(replaced.begin(), replaced.end(), "GOOD"), 0);
}

TEST(RawlogGsegToolHostile, ItsOwnOutputIsNeverSplitAgain) {
    if (!fs::exists(kVlp16) || !fs::exists(kKfSlam)) GTEST_SKIP() << "mrpt-common sample rawlogs absent";
    const fs::path dir = freshDir("twice");
    // Observation layout: scan, scan_ground, scan_obstacles read again.
    ASSERT_EQ(rawlogGseg("-i '" + kVlp16 + "' -o " + q(dir / "once.rawlog")).status, 0);
    const auto again = rawlogGseg("-i " + q(dir / "once.rawlog") + " -o " + q(dir / "twice.rawlog"));
    ASSERT_EQ(again.status, 0) << again.output;
    EXPECT_NE(again.output.find("0 scans segmented"), std::string::npos) << again.output;
    EXPECT_NE(again.output.find("1 already split"), std::string::npos) << again.output;
    const auto labels = entryLabels((dir / "twice.rawlog").string());
    EXPECT_EQ(labels, entryLabels((dir / "once.rawlog").string()));
    EXPECT_EQ(labels, (std::vector<std::string>{"Velodyne1_SCAN", "Velodyne1_SCAN_ground", "Velodyne1_SCAN_obstacles"}));
    // --replace output: only the halves, which are never split.
    ASSERT_EQ(rawlogGseg("-i '" + kVlp16 + "' -o " + q(dir / "rep.rawlog") + " --replace").status, 0);
    const auto rep = rawlogGseg("-i " + q(dir / "rep.rawlog") + " -o " + q(dir / "rep2.rawlog"));
    EXPECT_NE(rep.output.find("0 scans segmented"), std::string::npos) << rep.output;
    EXPECT_EQ(entryLabels((dir / "rep2.rawlog").string()), entryLabels((dir / "rep.rawlog").string()));
    // Sensory-frame layout: a frame holding a point cloud scan, segmented once, then passed through.
    const auto scan = streetScan();
    {
        gseg::mrpt::RawlogWriter w((dir / "sf.rawlog").string());
        mrpt::obs::CSensoryFrame sf;
        sf.insert(std::make_shared<mrpt::obs::CObservationPointCloud>(simulatedCloud(scan)));
        w.write(sf);
        w.commit();
    }
    ASSERT_EQ(rawlogGseg("-i " + q(dir / "sf.rawlog") + " -o " + q(dir / "sf1.rawlog")).status, 0);
    const auto sf2 = rawlogGseg("-i " + q(dir / "sf1.rawlog") + " -o " + q(dir / "sf2.rawlog"));
    EXPECT_NE(sf2.output.find("1 already split"), std::string::npos) << sf2.output;
    EXPECT_EQ(entryLabels((dir / "sf2.rawlog").string()), (std::vector<std::string>{"SIM+SIM_ground+SIM_obstacles"}));
}

TEST(RawlogGsegToolHostile, RotatingScansAreSegmented) {
    if (!fs::exists(kRotScan)) GTEST_SKIP() << kRotScan << " absent (package mrpt-common)";
    const fs::path dir = freshDir("rot");
    const auto r = rawlogGseg("-i '" + kRotScan + "' -o " + q(dir / "rot.rawlog") + " -c '" GSEG_SOURCE_DIR
                              "/config/vlp16.yaml'");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("1 scans segmented, 11305 points"), std::string::npos) << r.output;  // before: 0 scans
    EXPECT_EQ(entryLabels((dir / "rot.rawlog").string()),
              (std::vector<std::string>{"Velodyne1_SCAN", "Velodyne1_SCAN_ground", "Velodyne1_SCAN_obstacles"}));
}

TEST(RawlogGsegToolHostile, InterruptedRunLeavesNoTemporary) {
    if (!fs::exists(kKfSlam)) GTEST_SKIP() << kKfSlam << " absent (package mrpt-common)";
    const fs::path dir = freshDir("interrupted");
    // The input is a pipe: the tool has created its temporary output and is reading (it cannot
    // finish before we close the pipe) when SIGTERM arrives. No sleeps: the write below returns
    // only once the tool has read most of what was written.
    ASSERT_EQ(std::system(("gzip -dc '" + kKfSlam + "' > " + q(dir / "plain.rawlog")).c_str()), 0);
    const auto plain = gseg::io::readFileBytes((dir / "plain.rawlog").string());
    ASSERT_GT(plain.size(), 300000u);
    const fs::path fifo = dir / "in.rawlog";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    ::alarm(120);  // a tool that died before opening its input would leave open() below blocked
    const pid_t pid = gseg::test::spawnTool("rawlog-gseg", {"-i", fifo.string(), "-o", (dir / "out.rawlog").string()},
                                            (dir / "stderr.txt").string());
    ASSERT_GT(pid, 0);
    const int fd = ::open(fifo.c_str(), O_WRONLY);  // returns once the tool opened its input
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::write(fd, plain.data(), 300000), 300000);  // 300 kB: most of it consumed by the tool
    EXPECT_NE(gseg::test::entriesContaining(dir.string(), ".out.rawlog.gseg-"), "");  // mid-run: the temporary exists
    ::kill(pid, SIGTERM);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ::close(fd);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM);
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), "out.rawlog"), "");
    EXPECT_NE(gseg::test::readText((dir / "stderr.txt").string()).find("interrupted (SIGTERM)"), std::string::npos);
    ::alarm(0);
}

namespace {

/// A plain (uncompressed) rawlog of `n` point-cloud observations, as bytes.
std::vector<std::uint8_t> plainRawlog(const fs::path& dir, std::size_t n) {
    {
        gseg::mrpt::RawlogWriter w((dir / "gz.rawlog").string());
        for (std::size_t k = 0; k < n; ++k) {
            auto pc = mrpt::maps::CSimplePointsMap::Create();
            for (int i = 0; i < 3; ++i) pc->insertPoint(1234.5f + float(i), 2.f, -1.7f);
            mrpt::obs::CObservationPointCloud obs;
            obs.pointcloud = pc;
            obs.sensorLabel = "PC" + std::to_string(k);
            w.write(obs);
        }
        w.commit();
    }
    EXPECT_EQ(std::system(("gzip -dc " + q(dir / "gz.rawlog") + " > " + q(dir / "plain.rawlog")).c_str()), 0);
    return gseg::io::readFileBytes((dir / "plain.rawlog").string());
}

void writeBytes(const fs::path& p, const std::vector<std::uint8_t>& b) {
    std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
}

}  // namespace

TEST(RawlogGsegToolHostile, ErrorsSayWhatIsWrongInOneLineWithTheEntry) {
    const fs::path dir = freshDir("errors");
    std::ofstream(dir / "text.rawlog") << "not a rawlog, just text";
    auto r = rawlogGseg("-i " + q(dir / "text.rawlog") + " -o " + q(dir / "o.rawlog"));
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find((dir / "text.rawlog").string() + ": not an MRPT rawlog (a rawlog is a stream of serialized MRPT objects, "
                            "optionally gzip-compressed; this file does not start with one)"),
              std::string::npos)
        << r.output;
    EXPECT_EQ(r.output.find("corrupt"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("===="), std::string::npos) << r.output;  // before: "(==== MRPT exception ====)"
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    // Cut inside the second entry: that entry, the class MRPT was reading, and MRPT's own reason.
    auto bytes = plainRawlog(dir, 3);
    bytes.resize(bytes.size() / 2);
    writeBytes(dir / "cut.rawlog", bytes);
    r = rawlogGseg("-i " + q(dir / "cut.rawlog") + " -o " + q(dir / "o.rawlog"));
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("entry 1 (mrpt::obs::CObservationPointCloud) is corrupt or truncated ("), std::string::npos)
        << r.output;
    EXPECT_EQ(r.output.find("===="), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_FALSE(fs::exists(dir / "o.rawlog"));
}

TEST(RawlogGsegToolHostile, ASizeFieldAskingForGigabytesNamesTheEntryAndLeavesNothing) {
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "ulimit -v and AddressSanitizer's shadow memory do not mix";
#else
    // MRPT's deserializer trusts the point count of a CSimplePointsMap: 3 patched to 2^30 makes it
    // allocate 12 GB. Under a memory limit (README: reading untrusted rawlogs) MRPT 2.5.8 then
    // crashes (its aligned allocation returns null) or throws std::bad_alloc. Either way the entry
    // is named and nothing is left behind.
    const fs::path dir = freshDir("huge");
    auto bytes = plainRawlog(dir, 2);
    const float x0 = 1234.5f;
    std::uint8_t pattern[8] = {3, 0, 0, 0};
    std::memcpy(pattern + 4, &x0, 4);
    const auto second = std::search(std::search(bytes.begin(), bytes.end(), pattern, pattern + 8) + 1, bytes.end(),
                                    pattern, pattern + 8);
    ASSERT_NE(second, bytes.end());
    const std::uint32_t huge = 1u << 30;
    std::memcpy(&*second, &huge, 4);
    writeBytes(dir / "huge.rawlog", bytes);
    const auto r = gseg::test::runCommand("ulimit -v 4000000; exec '" + gseg::test::tool("rawlog-gseg") + "' -i " +
                                          q(dir / "huge.rawlog") + " -o " + q(dir / "o.rawlog"));
    EXPECT_NE(r.status, 0) << r.output;
    const bool named = r.output.find("crashed (SIGSEGV) while reading entry 1 of") != std::string::npos ||
                       r.output.find("entry 1 (mrpt::obs::CObservationPointCloud) is corrupt") != std::string::npos;
    EXPECT_TRUE(named) << r.output;
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), "o.rawlog"), "");
#endif
}

TEST(RawlogGsegToolHostile, AFileCutInsideASizeFieldIsTruncatedNotAGarbageSize) {
    // Found by fuzz_rawlog: MRPT 2.5.8 accepts a short read, so a rawlog cut inside a 4-byte count
    // left 3 bytes of garbage in it (2.8 GB allocated for a 265-byte file). Now: truncated, named.
    const fs::path dir = freshDir("cut_field");
    {
        gseg::mrpt::RawlogWriter w((dir / "gz.rawlog").string());
        w.write(mrpt::obs::CActionCollection());
        w.write(mrpt::obs::CActionCollection());
        w.commit();
    }
    ASSERT_EQ(std::system(("gzip -dc " + q(dir / "gz.rawlog") + " > " + q(dir / "plain.rawlog")).c_str()), 0);
    auto bytes = gseg::io::readFileBytes((dir / "plain.rawlog").string());
    bytes.resize(bytes.size() - 3);  // inside the second collection's count
    writeBytes(dir / "cut.rawlog", bytes);
#if defined(__SANITIZE_ADDRESS__)
    const std::string limit;  // ASan reserves more address space than any ulimit -v allows
#else
    const std::string limit = "ulimit -v 1500000; ";  // before: the garbage count had to fit in this
#endif
    const auto r = gseg::test::runCommand(limit + "exec '" + gseg::test::tool("rawlog-gseg") + "' -i " +
                                          q(dir / "cut.rawlog") + " -o " + q(dir / "o.rawlog"));
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("entry 1 (mrpt::obs::CActionCollection) is corrupt or truncated"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("(the file ends inside an entry ("), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(" bytes of a field): truncated)"), std::string::npos) << r.output;
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), "o.rawlog"), "");
}

// --- Batches (#12) ------------------------------------------------------------------------------

namespace {

/// rawlog-gseg batch inputs (#12): three good rawlogs in two folders and a truncated one.
struct Batch {
    std::vector<std::string> good;  ///< inputs
    std::string bad;                ///< the truncated input
};

Batch makeBatch(const fs::path& dir) {
    fs::remove_all(dir);
    fs::create_directories(dir / "a");
    fs::create_directories(dir / "b");
    fs::copy_file(kVlp16, dir / "a/test_velodyne_VLP16.rawlog");
    fs::copy_file(kVlp16, dir / "b/again.rawlog");
    const std::string plain = (dir / "plain").string(), cut = (dir / "b/cut.rawlog").string();
    EXPECT_EQ(std::system(("gzip -dc '" + kKfSlam + "' > '" + plain + "' 2>/dev/null || cp '" + kKfSlam + "' '" + plain + "'").c_str()), 0);
    fs::copy_file(plain, cut);
    fs::resize_file(cut, fs::file_size(plain) / 2 + 7);
    return {{(dir / "a/test_velodyne_VLP16.rawlog").string(), kKfSlam, (dir / "b/again.rawlog").string()}, cut};
}

/// Each output of a batch in `out` is the same bytes as a run on its input alone; the bad input
/// left nothing behind.
void expectBatchOutputs(const Batch& batch, const fs::path& out, const fs::path& single) {
    fs::create_directories(single);
    for (const std::string& in : batch.good) {
        const std::string name = fs::path(in).filename().string();
        const auto alone = rawlogGseg("-i '" + in + "' -o '" +
                                                  (single / name).string() + "'");
        // kf-slam's demo holds 2D laser scans only: passed through, exit 3 saying so (#34).
        const bool no3d = in == kKfSlam;
        ASSERT_EQ(alone.status, no3d ? 3 : 0) << alone.output;
        EXPECT_EQ(alone.output.find("no 3D LiDAR scan in the rawlog") != std::string::npos, no3d) << alone.output;
        const std::string one = gseg::test::readText((single / name).string());
        EXPECT_GT(one.size(), 1000u) << name;
        EXPECT_TRUE(one == gseg::test::readText((out / name).string())) << name << ": batch output differs";
    }
    for (const auto& e : fs::directory_iterator(out))
        EXPECT_EQ(e.path().filename().string().find("cut.rawlog"), std::string::npos) << "left behind: " << e.path();
}

}  // namespace

TEST(RawlogGsegTool, ABatchIntoAFolderEqualsOneRunPerInputAndABadInputLosesNothingElse) {
    if (!fs::exists(kVlp16) || !fs::exists(kKfSlam)) GTEST_SKIP() << "mrpt-common's datasets absent (package mrpt-common)";
    const fs::path dir = kDir / "batch";
    const Batch batch = makeBatch(dir);
    std::string args;
    for (const std::string& in : {batch.good[0], batch.bad, batch.good[1], batch.good[2]}) args += " -i '" + in + "'";
    const auto r = gseg::test::runCommand("'" + gseg::test::tool("rawlog-gseg") + "'" + args + " -o '" + (dir / "out").string() + "'");
    EXPECT_EQ(r.status, 1) << "something failed: " << r.output;
    EXPECT_NE(r.output.find("rawlog-gseg: " + batch.bad + ": entry "), std::string::npos) << "named: " << r.output;
    EXPECT_NE(r.output.find("rawlog-gseg: 3 of 4 rawlogs written, failed: " + batch.bad + "\n"), std::string::npos) << r.output;
    EXPECT_LT(r.output.find("again.rawlog: 1 entries"), r.output.find("3 of 4")) << r.output;
    expectBatchOutputs(batch, dir / "out", dir / "single");
}

TEST(RawlogGsegTool, ABatchThatCannotBeWrittenIsRefusedBeforeAnyWork) {
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " absent (package mrpt-common)";
    const fs::path dir = kDir / "batch_usage";
    fs::remove_all(dir);
    fs::create_directories(dir / "x");
    fs::copy_file(kVlp16, dir / "x/test_velodyne_VLP16.rawlog");
    const std::string tool = "'" + gseg::test::tool("rawlog-gseg") + "'";
    auto r = gseg::test::runCommand(tool + " -i '" + kVlp16 + "' -i '" + (dir / "x/test_velodyne_VLP16.rawlog").string() +
                                    "' -o '" + (dir / "out").string() + "'");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("two inputs named test_velodyne_VLP16.rawlog"), std::string::npos) << r.output;
    r = gseg::test::runCommand(tool + " -i '" + (dir / "x/test_velodyne_VLP16.rawlog").string() + "' -i '" + kKfSlam +
                               "' -o '" + (dir / "x").string() + "'");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("is the input"), std::string::npos) << r.output;
    EXPECT_TRUE(gseg::test::readText((dir / "x/test_velodyne_VLP16.rawlog").string()) == gseg::test::readText(kVlp16));
    r = gseg::test::runCommand(tool + " -o '" + (dir / "out").string() + "'");
    EXPECT_EQ(r.status, 2) << r.output;
    r = gseg::test::runCommand(tool + " --list '" + (dir / "missing.txt").string() + "' -o '" + (dir / "out").string() + "'");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("missing.txt: cannot read the list"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "out")) << "nothing made";
}

TEST(RawlogGsegTool, TwoMpiRanksSplitABatchAndWriteWhatOneProcessWrites) {
    GSEG_TEST_MPIRUN_OR_SKIP(mpirun, 2);
    if (!fs::exists(kVlp16) || !fs::exists(kKfSlam)) GTEST_SKIP() << "mrpt-common's datasets absent (package mrpt-common)";
    const fs::path dir = kDir / "batch_mpi";
    const Batch batch = makeBatch(dir);
    std::ofstream list(dir / "list.txt");
    list << "# inputs of the batch\n" << batch.good[0] << "\n\n" << batch.bad << "\n  " << batch.good[1] << "  \n" << batch.good[2] << "\n";
    list.close();
    const auto r = gseg::test::runCommand(mpirun + "'" + gseg::test::tool("rawlog-gseg") + "' --list '" +
                                          (dir / "list.txt").string() + "' -o '" + (dir / "out").string() + "'");
    EXPECT_EQ(r.status, 1) << "something failed: " << r.output;
    EXPECT_NE(r.output.find("rawlog-gseg: " + batch.bad + ": entry "), std::string::npos) << "named: " << r.output;
    const std::size_t at = r.output.find("rawlog-gseg: 3 of 4 rawlogs written (inputs per process: ");
    ASSERT_NE(at, std::string::npos) << r.output;
    int first = 0, second = 0;
    ASSERT_EQ(std::sscanf(r.output.c_str() + at, "rawlog-gseg: 3 of 4 rawlogs written (inputs per process: %d, %d)", &first, &second), 2);
    EXPECT_TRUE(first > 0 && second > 0 && first + second == 4) << r.output;
    // Without -c the height is estimated (distToGround: auto, the loader's default); rank 0 says
    // which height each VLP-16 input used, whoever had it.
    for (const std::size_t i : {std::size_t(0), std::size_t(2)})
        EXPECT_NE(r.output.find(batch.good[i] + ": 1 entries, 1 scans segmented, 11305 points"), std::string::npos) << r.output;
    std::size_t heights = 0;
    for (std::size_t at = r.output.find("distToGround auto: estimated 2.27 m"); at != std::string::npos;
         at = r.output.find("distToGround auto: estimated 2.27 m", at + 1))
        ++heights;
    EXPECT_EQ(heights, 2u) << r.output;
    expectBatchOutputs(batch, dir / "out", dir / "single");
}

TEST(RawlogGsegTool, UnderMpiAScanSkippedOnAnotherRankIsNamedByRankZeroAndExitsThree) {
    GSEG_TEST_MPIRUN_OR_SKIP(mpirun, 2);
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " absent (package mrpt-common)";
    const fs::path dir = freshDir("batch_mpi_skip");
    auto broken = std::make_shared<mrpt::obs::CObservationVelodyneScan>();  // vectors of different lengths
    broken->sensorLabel = "BROKEN";
    broken->point_cloud.x.assign(100, 1.f);
    broken->point_cloud.y.assign(10, 1.f);
    broken->point_cloud.z.assign(10, 1.f);
    {
        gseg::mrpt::RawlogWriter w((dir / "broken.rawlog").string());
        w.write(*broken);
        w.commit();
    }
    ASSERT_LT(fs::file_size(dir / "broken.rawlog"), fs::file_size(kVlp16)) << "the smaller input goes to rank 1";
    const auto r = gseg::test::runCommand(mpirun + "'" + gseg::test::tool("rawlog-gseg") + "' -i '" + kVlp16 + "' -i " +
                                          q(dir / "broken.rawlog") + " -o " + q(dir / "out"));
    EXPECT_EQ(r.status, 3) << "done, a scan passed through: " << r.output;
    EXPECT_NE(r.output.find("rawlog-gseg: " + (dir / "broken.rawlog").string() + ": entry 0 ('BROKEN') skipped, passed "
                            "through unchanged: "), std::string::npos) << "rank 1's skip, named by rank 0: " << r.output;
    EXPECT_NE(r.output.find("2 of 2 rawlogs written (inputs per process: 1, 1)"), std::string::npos) << r.output;
    EXPECT_EQ(entryLabels((dir / "out/broken.rawlog").string()), (std::vector<std::string>{"BROKEN"}));
}

// #18 point 10: a --sensor label that matches nothing (a typo) is named with the labels the
// rawlog has, and the run ends with exit 3 (done, but not what was asked), even with -q.
TEST(RawlogGsegToolHostile, ASensorFilterThatMatchesNothingIsNamedWithTheLabelsThereAre) {
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " absent (package mrpt-common)";
    const fs::path dir = freshDir("sensor_typo");
    auto r = rawlogGseg("-q -i " + q(kVlp16) + " -o " + q(dir / "out.rawlog") + " --sensor Velodyne1_SCA");
    EXPECT_EQ(r.status, 3) << r.output;
    EXPECT_NE(r.output.find("rawlog-gseg: --sensor Velodyne1_SCA matched no observation; the rawlog has LiDAR observations "
                            "from: Velodyne1_SCAN (1)"),
              std::string::npos) << r.output;
    EXPECT_EQ(entryLabels((dir / "out.rawlog").string()), entryLabels(kVlp16)) << "passed through unchanged";
    // The right label: segmented, no remark, exit 0.
    r = rawlogGseg("-i " + q(kVlp16) + " -o " + q(dir / "out.rawlog") + " -w --sensor Velodyne1_SCAN");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(r.output.find("matched no observation"), std::string::npos) << r.output;
    // A rawlog without LiDAR scans says so.
    if (fs::exists(kKfSlam)) {
        r = rawlogGseg("-i " + q(kKfSlam) + " -o " + q(dir / "kf.rawlog") + " --sensor VELODYNE");
        EXPECT_EQ(r.status, 3) << r.output;
        EXPECT_NE(r.output.find("--sensor VELODYNE matched no observation; the rawlog has no LiDAR observation"),
                  std::string::npos) << r.output;
    }
}

// --- the drive's context (#31) ------------------------------------------------------------------

namespace {

/// Ground points of each scan of a rawlog-gseg output, in rawlog order (the "*_ground" clouds).
std::vector<std::size_t> groundPerScan(const std::string& rawlog) {
    std::vector<std::size_t> out;
    gseg::mrpt::forEachRawlogEntry(rawlog, [&](std::size_t, const auto& obj) {
        auto pc = std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(obj);
        const std::string suffix = "_ground";
        if (pc && pc->sensorLabel.size() > suffix.size() && pc->sensorLabel.compare(pc->sensorLabel.size() - suffix.size(), suffix.size(), suffix) == 0)
            out.push_back(pc->pointcloud->size());
        return true;
    });
    return out;
}

/// Drive 09 as the rawlog kDir/<name>.rawlog (with poses, or without), or "" (a failure reported).
std::string drive09Rawlog(bool poses, const std::string& name) { return gseg::test::drive09Rawlog(kDir, name, poses); }

}  // namespace

TEST(RawlogGsegTool, ADriveWithPosesIsLabelledWithItsTerrainModelAndWithoutAsEachScanAlone) {
    const std::string rel = "semantickitti-drives/sequences/09/poses.txt";
    if (gseg::test::sharedData(rel).empty()) GTEST_SKIP() << gseg::test::missingDataMessage(rel);
    const std::string withPoses = drive09Rawlog(true, "d09"), noPoses = drive09Rawlog(false, "d09_no_poses");
    ASSERT_FALSE(withPoses.empty() || noPoses.empty());
    const std::string cfg = " -c '" GSEG_SOURCE_DIR "/config/kitti_hdl64.yaml' -w -o '";
    const std::string ctx = (kDir / "d09_ctx.rawlog").string(), alone = (kDir / "d09_alone.rawlog").string(),
                      bare = (kDir / "d09_bare.rawlog").string();
    const auto r = rawlogGseg("-i '" + withPoses + "'" + cfg + ctx + "'");
    ASSERT_EQ(r.status, 0) << r.output;
    const std::size_t at = r.output.find("10 scans labelled with the drive's terrain model (");
    ASSERT_NE(at, std::string::npos) << r.output;
    const std::size_t colon = r.output.find("): ", at);
    ASSERT_NE(colon, std::string::npos) << r.output;
    const long turned = std::atol(r.output.c_str() + colon + 3);
    const std::size_t dropAt = r.output.find(" points turned ground, ", colon);
    ASSERT_NE(dropAt, std::string::npos) << r.output;
    const long dropped = std::atol(r.output.c_str() + dropAt + 23);
    const auto a = rawlogGseg("-i '" + withPoses + "'" + cfg + alone + "' --no-drive-context");
    ASSERT_EQ(a.status, 0) << a.output;
    EXPECT_EQ(a.output.find("terrain model"), std::string::npos) << a.output;
    const auto b = rawlogGseg("-i '" + noPoses + "'" + cfg + bare + "'");
    ASSERT_EQ(b.status, 0) << b.output;
    EXPECT_EQ(b.output.find("drive context"), std::string::npos) << "a rawlog of single scans says nothing of drives: " << b.output;

    const std::vector<std::size_t> g = groundPerScan(ctx), g0 = groundPerScan(alone), gb = groundPerScan(bare);
    ASSERT_EQ(g.size(), 10u);
    EXPECT_EQ(g0, gb) << "without the context, or without poses, every scan is labelled alone";
    long gained = 0;
    for (std::size_t k = 0; k < g.size(); ++k) {
        EXPECT_GE(g[k], g0[k]) << "scan " << k;
        gained += long(g[k]) - long(g0[k]);
    }
    EXPECT_EQ(gained, turned - dropped) << "the summary counts what changed";
    EXPECT_GT(turned, 10000) << "measured 2026-12-07: 17832 points of the rural drive's verges and far rings";
    EXPECT_GT(dropped, 0) << "measured 2026-12-07: 3947 feet of what stands";
    EXPECT_LT(dropped, turned / 2);
    // A FIFO is read once: its scans are labelled alone, and the summary says why.
    const fs::path fifo = kDir / "d09.fifo";
    fs::remove(fifo);
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    const auto f = gseg::test::runCommand("cat '" + withPoses + "' > '" + fifo.string() + "' & '" + gseg::test::tool("rawlog-gseg") +
                                          "' -i '" + fifo.string() + "'" + cfg + (kDir / "d09_fifo.rawlog").string() + "'");
    ASSERT_EQ(f.status, 0) << f.output;
    EXPECT_NE(f.output.find(", single-scan labels (no drive context: the input is not a regular file"), std::string::npos) << f.output;
    EXPECT_EQ(groundPerScan((kDir / "d09_fifo.rawlog").string()), g0);
}
