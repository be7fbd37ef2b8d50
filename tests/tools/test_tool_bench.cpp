// `gseg bench`: one row per scan, distToGround: auto per scan, configuration errors, and end to
// end on a simulated scan (phase / step breakdown, threads and memory lines).
#include <support/lidar_sim.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace fs = std::filesystem;

namespace {

const fs::path kDir = fs::path(GSEG_BINARY_DIR) / "tests" / "tool_bench";

using gseg::test::runGseg;

/// A simulated HDL-64 scan of flat ground `height` below the sensor with a box, as a KITTI .bin.
std::string writeScan(const fs::path& dir, const std::string& name, double height) {
    gseg::test::Scene s;
    s.addFlatGround(height);
    s.addBox(6, -1, -height, 8, 1, -height + 1.5);
    const auto scan = gseg::test::simulate(s, gseg::test::Lidar::hdl64());
    std::vector<float> xyzi;
    for (std::size_t i = 0; i < scan.size(); ++i)
        xyzi.insert(xyzi.end(), {scan.xyz[3 * i], scan.xyz[3 * i + 1], scan.xyz[3 * i + 2], 0.f});
    const fs::path path = dir / name;
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(xyzi.data()), std::streamsize(xyzi.size() * sizeof(float)));
    return path.string();
}

/// The line of the per-scan table that starts with `name`, or "".
std::string rowOf(const std::string& out, const std::string& name) {
    std::istringstream in(out);
    for (std::string l; std::getline(in, l);)
        if (l.rfind(name + " ", 0) == 0) return l;
    return "";
}

}  // namespace

TEST(BenchToolPerScan, OneRowPerScanAndAutoHeightPerScan) {
    const fs::path dir = kDir / "rows";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string low = writeScan(dir, "low.bin", 1.73), high = writeScan(dir, "high.bin", 2.5);
    std::ofstream(dir / "auto.yaml") << "distToGround: auto\n";
    int status = -1;
    const std::string out =
        runGseg("bench", "'" + low + "' '" + high + "' --repeat 2 --config '" + (dir / "auto.yaml").string() + "'", status);
    ASSERT_EQ(status, 0) << out;
    EXPECT_NE(out.find("low.bin: distToGround auto 1.7"), std::string::npos) << out;
    EXPECT_NE(out.find("high.bin: distToGround auto 2.5"), std::string::npos) << out;
    EXPECT_NE(out.find("warm-up + 2 repeats, 1 thread(s); build: "), std::string::npos) << out;
    // scan, points, median, p90, min, Mpoints/s with min <= median <= p90.
    for (const char* name : {"low.bin", "high.bin", "all scans"}) {
        std::istringstream row(rowOf(out, name).substr(std::string(name).size()));
        std::size_t points = 0;
        double median = -1, p90 = -1, min = -1, rate = -1;
        ASSERT_TRUE(row >> points >> median >> p90 >> min >> rate) << name << " row missing in:\n" << out;
        EXPECT_GT(points, 10000u);
        EXPECT_GT(min, 0.0);
        EXPECT_LE(min, median);
        EXPECT_LE(median, p90);
        EXPECT_GT(rate, 0.0);
    }
    EXPECT_NE(out.find("throughput: "), std::string::npos) << out;
}

TEST(BenchToolPerScan, BadConfigAndArguments) {
    const fs::path dir = kDir / "bad";
    fs::create_directories(dir);
    std::ofstream(dir / "bad.yaml") << "noSuchKey: 3\n";
    const std::string scan = (dir / "scan.bin").string();
    const std::vector<float> pts(4 * 10, 1.0f);
    std::ofstream(scan, std::ios::binary).write(reinterpret_cast<const char*>(pts.data()), 160);
    int status = -1;
    std::string out = runGseg("bench", "'" + scan + "' --config '" + (dir / "bad.yaml").string() + "'", status);
    EXPECT_EQ(status, 1) << out;
    EXPECT_NE(out.find("gseg bench: "), std::string::npos) << out;
    EXPECT_NE(out.find("noSuchKey"), std::string::npos) << out;
    out = runGseg("bench", "'" + scan + "' --threads 0", status);
    EXPECT_EQ(status, 2) << out;
    // One scan over several threads is gone (#32): the option is unknown.
    out = runGseg("bench", "'" + scan + "' --threads-per-scan 2", status);
    EXPECT_EQ(status, 2) << out;
    EXPECT_NE(out.find("unknown option '--threads-per-scan'"), std::string::npos) << out;
    out = runGseg("bench", "", status);
    EXPECT_EQ(status, 2) << out;
}

TEST(BenchToolHostile, NanPointsAndEmptyScansNeverAbort) {
    // Before: an exception escaped a worker thread and aborted the process (issue #9 item 4).
    const fs::path dir = kDir / "hostile";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string scan = writeScan(dir, "nan.bin", 1.73);
    {
        std::fstream f(scan, std::ios::in | std::ios::out | std::ios::binary);
        const float nan = std::numeric_limits<float>::quiet_NaN();
        f.seekp(16 * 5 + 4);
        f.write(reinterpret_cast<const char*>(&nan), 4);
    }
    std::ofstream(dir / "empty.ply") << "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                                        "property float z\nend_header\n";
    int status = -1;
    std::string out = runGseg("bench", "'" + scan + "' --repeat 1 --threads 2", status);
    EXPECT_EQ(status, 0) << out;
    EXPECT_NE(out.find("warm-up + 1 repeats, 2 thread(s); build: "), std::string::npos) << out;
    // An old configuration with the retired key `threads` still runs, warned about once (#32).
    std::ofstream(dir / "old.yaml") << "distToGround: 1.73\nthreads: 3\n";
    const std::string old = runGseg("bench", "'" + scan + "' --repeat 1 -c '" + (dir / "old.yaml").string() + "'", status);
    EXPECT_EQ(status, 0) << old;
    const std::string warning = "gseg bench: warning: " + (dir / "old.yaml").string() + ":2: 'threads' is ignored: ";
    ASSERT_NE(old.find(warning), std::string::npos) << old;
    EXPECT_EQ(old.find(warning, old.find(warning) + 1), std::string::npos) << "said once: " << old;
    EXPECT_NE(out.find("nan.bin: 1 non-finite point(s) left out"), std::string::npos) << out;
    out = runGseg("bench", "'" + scan + "' '" + (dir / "empty.ply").string() + "' --repeat 1 --threads 2", status);
    EXPECT_EQ(status, 3) << out;  // done, one scan could not be timed
    EXPECT_NE(out.find("empty.ply: skipped: no finite point"), std::string::npos) << out;
    EXPECT_FALSE(rowOf(out, "nan.bin").empty()) << out;
    out = runGseg("bench", "'" + (dir / "empty.ply").string() + "' --repeat 1", status);
    EXPECT_EQ(status, 1) << out;
    EXPECT_NE(out.find("gseg bench: no scan to time"), std::string::npos) << out;
}

TEST(BenchTool, ReportsTimesPerPhaseStepAndTheMachine) {
    gseg::test::Scene s;
    s.addFlatGround(1.73);
    s.addBox(5, -1, -1.73, 7, 1, 0);
    const auto scan = gseg::test::simulate(s, gseg::test::Lidar::hdl64());
    std::vector<float> xyzi;
    for (std::size_t i = 0; i < scan.size(); ++i)
        xyzi.insert(xyzi.end(), {scan.xyz[3 * i], scan.xyz[3 * i + 1], scan.xyz[3 * i + 2], 0.f});
    const std::string path = std::string(GSEG_BINARY_DIR) + "/tests/bench_scan.bin";
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(xyzi.data()),
                                                std::streamsize(xyzi.size() * sizeof(float)));
    int status = -1;
    const std::string out = runGseg("bench", "'" + path + "' --repeat 3 --threads 2", status);
    ASSERT_EQ(status, 0) << out;
    const std::string points = std::to_string(scan.size()) + " points";
    for (const std::string expected : {"median", "p90", "phase I", "phase II", "plane fit", "expansion",
                                       "hardware threads", "peak memory", "2 thread(s)", points.c_str()})
        EXPECT_NE(out.find(expected), std::string::npos) << expected << " missing from:\n" << out;
    runGseg("bench", "/nonexistent.bin", status);
    EXPECT_EQ(status, 1);
    runGseg("bench", "'" + path + "' --repeat 0", status);
    EXPECT_EQ(status, 2);
}
