// Memory before work (#18 point 2): the map layer's estimate (gseg/map/memory_estimate.hpp), how it
// scales with the resolution, the range and the scans, its calibration on the real sequence-00
// scan, the limit it is compared with, and rawlog-octomap refusing an option that cannot fit
// (under --max-memory and under `ulimit -v`) in one line, before any work, leaving nothing.
#include <gseg/io/kitti.hpp>
#include <gseg/map/memory_estimate.hpp>
#include <support/child.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <cmath>
#include <filesystem>
#include <limits>

#include <sys/resource.h>

namespace fs = std::filesystem;

namespace {

/// A spinning 64-beam sensor 1.73 m above flat ground: beams from -24 to +2 degrees, 900 columns;
/// beams that reach the ground end there, the others at 40 m (a wall all around).
std::vector<float> spinningScan() {
    std::vector<float> xyz;
    for (int beam = 0; beam < 64; ++beam) {
        const double el = (-24.0 + 26.0 * beam / 63) * M_PI / 180;
        for (int c = 0; c < 900; ++c) {
            const double az = 2 * M_PI * c / 900;
            const double range = el < 0 ? std::min(40.0, 1.73 / std::sin(-el)) : 40.0;
            xyz.insert(xyz.end(), {float(range * std::cos(el) * std::cos(az)), float(range * std::cos(el) * std::sin(az)),
                                   float(range * std::sin(el))});
        }
    }
    return xyz;
}

double peakAt(const std::vector<float>& xyz, double resolution, double maxRange = 50, std::size_t inFlight = 6,
              std::size_t scans = 6) {
    gseg::map::TraversabilityOptions o;
    o.resolution = resolution, o.maxRange = maxRange;
    const auto f = gseg::map::rayFootprint(gseg::PointCloudView(xyz.data(), xyz.size() / 3), Eigen::Vector3d::Zero(), o);
    return gseg::map::estimateMemory(f).peak(inFlight, scans);
}

TEST(MemoryEstimate, CountsTheRaysAndTheirSolidAngle) {
    std::vector<float> xyz = spinningScan();
    const std::size_t n = xyz.size() / 3;
    xyz.insert(xyz.end(), {std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f, 0.f, 0.f, 0.f});  // no return; the origin
    gseg::map::TraversabilityOptions o;
    const auto f = gseg::map::rayFootprint(gseg::PointCloudView(xyz.data(), xyz.size() / 3), Eigen::Vector3d::Zero(), o);
    EXPECT_EQ(f.rays, n) << "the NaN point and the point at the sensor cast no ray";
    // 26 degrees of elevation all around: 2 pi (sin 2 + sin 24 deg) = 2.77 sr (1-degree bins: a bin more).
    EXPECT_GT(f.solidAngle, 2.7);
    EXPECT_LT(f.solidAngle, 3.2);
    EXPECT_GT(f.voxels, f.sparseVoxels);
    EXPECT_GT(f.voxels, f.words);
    EXPECT_GT(f.words, f.bricks);
    EXPECT_GT(f.bricks, 0);
    // The same scan seen from elsewhere: the same footprint.
    std::vector<float> moved = xyz;
    for (std::size_t i = 0; i < moved.size(); i += 3) moved[i] += 100.f;
    const auto g = gseg::map::rayFootprint(gseg::PointCloudView(moved.data(), moved.size() / 3), Eigen::Vector3d(100, 0, 0), o);
    EXPECT_NEAR(g.voxels, f.voxels, 0.01 * f.voxels) << "(float rounding moves a few ray ends)";
    EXPECT_THROW(gseg::map::rayFootprint(gseg::PointCloudView(xyz.data(), 1), Eigen::Vector3d::Zero(),
                                         [] { gseg::map::TraversabilityOptions bad; bad.resolution = 0; return bad; }()),
                 std::invalid_argument);
}

TEST(MemoryEstimate, GrowsWithFinerVoxelsLongerRaysMoreScansInFlightAndMoreScans) {
    const std::vector<float> xyz = spinningScan();
    double previous = 0;
    for (double r : {0.4, 0.2, 0.1, 0.05, 0.02, 0.01}) {
        const double peak = peakAt(xyz, r);
        if (previous > 0) {
            // Halving the voxel edge: at least the rays' length in voxels twice over (x 2), at
            // most the volume (x 8), whatever the process's constant part.
            EXPECT_GT(peak - 100e6, 1.5 * (previous - 100e6)) << r << " m";
            EXPECT_LT(peak, 8.5 * previous) << r << " m";
        }
        previous = peak;
    }
    EXPECT_LT(peakAt(xyz, 0.05, 20), peakAt(xyz, 0.05, 50)) << "a shorter --max-range";
    EXPECT_LT(peakAt(xyz, 0.05, 50, 2), peakAt(xyz, 0.05, 50, 6)) << "fewer scans in flight";
    EXPECT_LT(peakAt(xyz, 0.05, 50, 6, 6), peakAt(xyz, 0.05, 50, 6, 600)) << "a longer drive";
    EXPECT_GT(peakAt(xyz, 0.01), 4e9) << "0.01 m voxels over 40 m rays: gigabytes";
}

// The calibration (README, Robustness): the first sequence-00 scan at 0.2, 0.1 and 0.05 m against
// the peak RSS rawlog-octomap measured on the six scans (146, 324, 1268 MB; 2 worker threads, 6
// scans in flight), within 25 %.
TEST(MemoryEstimate, MatchesThePeakMeasuredOnSequence00) {
    const std::string bin = gseg::test::sharedData("semantickitti/sequences/00/velodyne/000000.bin");
    if (bin.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/00/velodyne/000000.bin");
    const std::vector<float> raw = gseg::io::readKittiBin(bin);
    std::vector<float> xyz;
    for (std::size_t i = 0; i + 3 < raw.size(); i += 4) xyz.insert(xyz.end(), {raw[i], raw[i + 1], raw[i + 2]});
    const std::pair<double, double> measured[] = {{0.2, 146e6}, {0.1, 324e6}, {0.05, 1268e6}};
    for (const auto& [resolution, peak] : measured) {
        const double estimate = peakAt(xyz, resolution);
        EXPECT_GT(estimate, 0.75 * peak) << resolution << " m: " << estimate / 1e6 << " MB";
        EXPECT_LT(estimate, 1.25 * peak) << resolution << " m: " << estimate / 1e6 << " MB";
    }
    EXPECT_GT(peakAt(xyz, 0.01), 24e9) << "0.01 m: more than the 24 GB it was killed at";
}

TEST(MemoryEstimate, TheLimitIsTheLowestOfTheMachineAndTheProcessLimits) {
    const gseg::map::MemoryLimit here = gseg::map::memoryLimit();
    EXPECT_GT(here.bytes, 0);
    EXPECT_FALSE(here.what.empty());
    // Under ulimit -v (in a child: the limit stays there): 1 GB more than the address space in use.
    const auto child = gseg::test::runInChild([] {
        rlimit l{};
        ::getrlimit(RLIMIT_AS, &l);
        const double before = gseg::map::memoryLimit().bytes;
        std::ifstream status("/proc/self/status");
        double vmKb = -1;
        for (std::string line; std::getline(status, line);)
            if (line.rfind("VmSize:", 0) == 0) vmKb = std::stod(line.substr(7));
        if (vmKb <= 0) return 10;
        l.rlim_cur = rlim_t(vmKb * 1024 + 1e9);
        if (::setrlimit(RLIMIT_AS, &l) != 0) return 11;
        const gseg::map::MemoryLimit m = gseg::map::memoryLimit();
        if (!(m.bytes <= 1.01e9 && m.bytes <= before)) return 12;
        return m.machine || m.what == "the address-space limit (ulimit -v)" ? 0 : 13;
    });
    EXPECT_TRUE(child.exited);
    EXPECT_EQ(child.code, 0);
    EXPECT_EQ(gseg::map::formatBytes(324e6), "324 MB");
    EXPECT_EQ(gseg::map::formatBytes(1.18e9), "1.2 GB");
    EXPECT_EQ(gseg::map::formatBytes(27.4e9), "27 GB");
}

// The tool: the six sequence-00 scans through kitti2rawlog.
class RawlogOctomapMemory : public ::testing::Test {
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

TEST_F(RawlogOctomapMemory, MaxMemoryRefusesBeforeAnyWorkNamingTheOptionsAndTheEstimate) {
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

TEST_F(RawlogOctomapMemory, UnderUlimitVTheResolutionThatCannotFitIsRefusedNotKilled) {
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

}  // namespace
