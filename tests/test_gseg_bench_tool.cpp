// `gseg bench` end to end on a shared KITTI scan (or a synthetic one when the data is absent).
#include <support/lidar_sim.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

namespace {

using gseg::test::runGseg;

}  // namespace

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
