// `gseg segment` end to end: the built executable on real and broken inputs.
#include <gseg/io/kitti.hpp>
#include <support/paths.hpp>

#include <mrpt/img/CImage.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sys/stat.h>

namespace {

const std::string kDir = std::string(GSEG_BINARY_DIR) + "/tests/segment_tool";

using ToolRun = gseg::test::CommandResult;

ToolRun segmentTool(const std::string& args) {
    ::mkdir(kDir.c_str(), 0755);
    return gseg::test::runCommand("'" + gseg::test::tool("gseg") + "' segment " + args);
}

bool exists(const std::string& p) {
    struct stat st {};
    return ::stat(p.c_str(), &st) == 0;
}

std::string out(const std::string& name) {
    const std::string p = kDir + "/" + name;
    std::remove(p.c_str());
    return p;
}

std::string writeBin(const std::string& name, const std::vector<float>& v, std::size_t bytes = SIZE_MAX) {
    const std::string p = kDir + "/" + name;
    ::mkdir(kDir.c_str(), 0755);
    std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(v.data()),
                                             std::streamsize(std::min(bytes, v.size() * sizeof(float))));
    return p;
}

const std::string kVlp16 = "/usr/share/mrpt/datasets/test_velodyne_VLP16.rawlog";

}  // namespace

TEST(SegmentTool, KittiScanWritesLabelsPlyAndPng) {
    const std::string scan = gseg::test::sharedData("semantickitti/sequences/08/velodyne/000000.bin");
    if (scan.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/08/velodyne/000000.bin");
    const std::string labels = out("k.labels"), ply = out("k.ply"), png = out("k.png");
    const ToolRun r = segmentTool("'" + scan + "' --config '" GSEG_SOURCE_DIR "/config/kitti_hdl64.yaml' --labels-out '" +
                       labels + "' --ply-out '" + ply + "' --png-out '" + png + "'");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("points 123389"), std::string::npos) << r.output;
    const auto bytes = gseg::io::readFileBytes(labels);
    ASSERT_EQ(bytes.size(), 123389u);
    std::size_t ground = 0;
    for (auto b : bytes) {
        ASSERT_LE(b, 1);
        ground += b;
    }
    EXPECT_GT(ground, 50000u);  // a suburban street: about 60 % ground
    EXPECT_LT(ground, 90000u);
    EXPECT_EQ(gseg::io::readFileBytes(ply).size() > 123389u * 15, true);
    mrpt::img::CImage img;
    ASSERT_TRUE(img.loadFromFile(png));
    EXPECT_EQ(img.getWidth(), 800u);
}

TEST(SegmentTool, RealVlp16RawlogGroundLiesBelowTheSensor) {
    if (!exists(kVlp16)) GTEST_SKIP() << kVlp16 << " absent (package mrpt-common)";
    const std::string labels = out("v.labels");
    const ToolRun r = segmentTool("'" + kVlp16 + "' -c '" GSEG_SOURCE_DIR "/config/vlp16.yaml' --labels-out '" + labels + "'");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("CObservationVelodyneScan"), std::string::npos);
    const auto bytes = gseg::io::readFileBytes(labels);
    ASSERT_EQ(bytes.size(), 11305u);
    std::size_t ground = 0;
    for (auto b : bytes) ground += b;
    // Measured 2060 (18.2 %, sensor height estimated 2.27 m): a yard with buildings, vehicles and
    // vegetation close to the sensor.
    EXPECT_GT(ground, 11305u * 15 / 100);
    EXPECT_LT(ground, 11305u * 35 / 100);
}

TEST(SegmentTool, RawlogIndexPastTheEndIsAnError) {
    if (!exists(kVlp16)) GTEST_SKIP() << kVlp16 << " absent (package mrpt-common)";
    const ToolRun r = segmentTool("'" + kVlp16 + "' --index 3");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.output.find("past the last LiDAR observation"), std::string::npos) << r.output;
}

TEST(SegmentTool, BadInputsFailWithOneLineAndWriteNothing) {
    std::vector<float> good;
    for (int i = 0; i < 200; ++i) good.insert(good.end(), {float(i % 20), float(i / 20), -1.7f, 0.f});
    std::vector<float> nan = good;
    nan[4 * 17 + 1] = std::numeric_limits<float>::quiet_NaN();
    const std::string badYaml = kDir + "/bad.yaml", unknownYaml = kDir + "/unknown.yaml";
    writeBin("dummy", {});
    std::ofstream(badYaml) << "cellSizeX: -1.5\n";
    std::ofstream(unknownYaml) << "cellSizeXY: 1.5\n";
    const struct {
        std::string args, expect;
    } cases[] = {
        {"/nonexistent/scan.bin", "cannot open"},
        {"'" + writeBin("trunc.bin", good, 16 * 10 + 7) + "'", "not a multiple of 16"},
        {"'" + writeBin("empty.bin", {}) + "'", "empty"},
        {"'" + writeBin("ok.bin", good) + "' -c '" + badYaml + "'", "cellSizeX"},
        {"'" + writeBin("ok.bin", good) + "' -c '" + unknownYaml + "'", "cellSizeXY"},
        {"'" + writeBin("scan.xyz", good) + "'", "unknown scan format"},
    };
    for (const auto& c : cases) {
        const std::string labels = out("bad.labels"), png = out("bad.png");
        const ToolRun r = segmentTool(c.args + " --labels-out '" + labels + "' --png-out '" + png + "'");
        EXPECT_EQ(r.status, 1) << c.args << "\n" << r.output;
        EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.args << "\n" << r.output;
        EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
        EXPECT_FALSE(exists(labels)) << c.args;
        EXPECT_FALSE(exists(png)) << c.args;
    }
    EXPECT_EQ(segmentTool("").status, 2);  // usage error
    // A point without a return (NaN) is not an error: it is labelled non-ground.
    const std::string nanLabels = out("nan.labels");
    const ToolRun r = segmentTool("'" + writeBin("nan.bin", nan) + "' --labels-out '" + nanLabels + "'");
    ASSERT_EQ(r.status, 0) << r.output;
    const auto bytes = gseg::io::readFileBytes(nanLabels);
    ASSERT_EQ(bytes.size(), 200u);
    EXPECT_EQ(bytes[17], 0);
}

TEST(SegmentTool, AutomaticSensorHeightOnTheRealVlp16Scan) {
    if (!exists(kVlp16)) GTEST_SKIP() << kVlp16 << " absent (package mrpt-common)";
    const std::string cfg = kDir + "/auto.yaml";
    std::ofstream(cfg) << "distToGround: auto\n";
    const ToolRun r = segmentTool("'" + kVlp16 + "' -c '" + cfg + "'");
    ASSERT_EQ(r.status, 0) << r.output;
    const auto at = r.output.find("distToGround auto: ");
    ASSERT_NE(at, std::string::npos) << r.output;
    const double h = std::stod(r.output.substr(at + 19));
    EXPECT_GT(h, 1.9);  // measured 2.08; by hand from the data about 2.2 (config/vlp16.yaml)
    EXPECT_LT(h, 2.4);
}
