// `gseg segment` end to end: the built executable on real and broken inputs.
#include <gseg/io/kitti.hpp>
#include <gseg/io/ply.hpp>
#include <gseg/mrpt/rawlog_io.hpp>
#include <support/child.hpp>
#include <support/paths.hpp>

#include <mrpt/img/CImage.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CPointCloudColoured.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sys/stat.h>
#include <unistd.h>

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

TEST(SegmentTool, KittiScanWritesLabelsPlyPngAndScene) {
    const std::string scan = gseg::test::sharedData("semantickitti/sequences/08/velodyne/000000.bin");
    if (scan.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/08/velodyne/000000.bin");
    const std::string labels = out("k.labels"), ply = out("k.ply"), png = out("k.png"), scene = out("k.3Dscene");
    const ToolRun r = segmentTool("'" + scan + "' --config '" GSEG_SOURCE_DIR "/config/kitti_hdl64.yaml' --labels-out '" +
                       labels + "' --ply-out '" + ply + "' --png-out '" + png + "' --scene-out '" + scene + "'");
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
    // The PLY: the input points with their intensity, and the labels as a `label` property.
    const std::vector<float> input = gseg::io::readKittiBin(scan), back = gseg::io::readPly(ply);
    ASSERT_EQ(back, input);  // x, y, z, intensity, exactly
    const std::vector<double> label = gseg::io::readPlyProperty(ply, "label"), green = gseg::io::readPlyProperty(ply, "green");
    ASSERT_EQ(label.size(), bytes.size());
    for (std::size_t i = 0; i < bytes.size(); ++i) {
        ASSERT_EQ(label[i], double(bytes[i])) << i;
        ASSERT_EQ(green[i], bytes[i] ? gseg::palette::kGround[1] : gseg::palette::kNonGround[1]) << i;
    }
    mrpt::img::CImage img;
    ASSERT_TRUE(img.loadFromFile(png));
    EXPECT_EQ(img.getWidth(), 800u);
    // The scene: MRPT's loader reads it; one coloured point per input point.
    mrpt::opengl::COpenGLScene view;
    ASSERT_TRUE(view.loadFromFile(scene));
    const auto points = view.getByClass<mrpt::opengl::CPointCloudColoured>();
    ASSERT_TRUE(points);
    ASSERT_EQ(points->size(), bytes.size());
    std::size_t greenPoints = 0;
    for (std::size_t i = 0; i < points->size(); ++i) greenPoints += points->getPointColor(i).G == gseg::palette::kGround[1];
    EXPECT_EQ(greenPoints, ground);
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
    // Measured 2224 (19.7 %, sensor height estimated 2.27 m): a yard with buildings, vehicles and
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

// #18 point 10: a negative --index used the first scan; it is bad usage, refused before reading.
TEST(SegmentTool, ANegativeIndexIsBadUsage) {
    for (const char* index : {"-1", "-7"}) {
        const ToolRun r = segmentTool("'" + kVlp16 + "' --index " + index + " --labels-out /nonexistent/x.labels");
        EXPECT_EQ(r.status, 2) << r.output;
        EXPECT_NE(r.output.find(std::string("--index needs N >= 0 (the N-th LiDAR observation of a rawlog, 0-based), got ") + index),
                  std::string::npos) << r.output;
    }
    if (!exists(kVlp16)) GTEST_SKIP() << kVlp16 << " absent (package mrpt-common)";
    EXPECT_EQ(segmentTool("'" + kVlp16 + "' --index 0").status, 0);
}

TEST(SegmentTool, BadInputsFailWithOneLineAndWriteNothing) {
    std::vector<float> good;
    for (int i = 0; i < 200; ++i) good.insert(good.end(), {float(i % 20), float(i / 20), -1.7f, 0.f});
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

// Without -c: the one default of every route (gseg::mrpt::defaultConfig(), distToGround auto), said
// in the summary with where it came from; with a file, the file.
TEST(SegmentTool, WithoutAConfigurationTheHeightIsEstimatedAndTheSummarySaysSo) {
    if (!exists(kVlp16)) GTEST_SKIP() << kVlp16 << " absent (package mrpt-common)";
    const ToolRun r = segmentTool("'" + kVlp16 + "'");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("distToGround: auto, estimated per scan (fallback 1.723 m) [the default: no configuration file]"),
              std::string::npos) << r.output;
    const auto at = r.output.find("distToGround auto: ");
    ASSERT_NE(at, std::string::npos) << r.output;
    EXPECT_GT(std::stod(r.output.substr(at + 19)), 1.9) << r.output;
    const std::string kitti = std::string(GSEG_SOURCE_DIR) + "/config/kitti_hdl64.yaml";
    const ToolRun k = segmentTool("'" + kVlp16 + "' -c '" + kitti + "'");
    ASSERT_EQ(k.status, 0) << k.output;
    EXPECT_NE(k.output.find("distToGround: 1.723 m, fixed [" + kitti + "]"), std::string::npos) << k.output;
}

// --- Hostile runs (issue #9 items 6 to 9) --------------------------------------------------------------

namespace {

std::vector<float> flatScan() {
    std::vector<float> v;
    for (int i = 0; i < 400; ++i) v.insert(v.end(), {float(i % 20) - 10.f, float(i / 20) - 10.f, -1.7f, 0.f});
    return v;
}

}  // namespace

TEST(SegmentToolHostile, NonFinitePointsAreLabelledNonGroundAndCounted) {
    std::vector<float> pts = flatScan();
    pts[4 * 17 + 1] = std::numeric_limits<float>::quiet_NaN();
    pts[4 * 33] = std::numeric_limits<float>::infinity();
    const std::string labels = out("nan.labels"), png = out("nan.png");
    const ToolRun r = segmentTool("'" + writeBin("nan.bin", pts) + "' --labels-out '" + labels + "' --png-out '" + png + "'");
    ASSERT_EQ(r.status, 0) << r.output;  // before: the whole scan was refused ("point 17")
    EXPECT_NE(r.output.find("2 non-finite point(s)"), std::string::npos) << r.output;
    const auto bytes = gseg::io::readFileBytes(labels);
    ASSERT_EQ(bytes.size(), 400u);
    EXPECT_EQ(bytes[17], 0);
    EXPECT_EQ(bytes[33], 0);
    EXPECT_TRUE(exists(png));
}

TEST(SegmentToolHostile, AnOutputThatIsTheInputIsRefusedBeforeWriting) {
    const std::string scan = writeBin("in.bin", flatScan());
    const std::string link = kDir + "/in-link.bin";
    std::remove(link.c_str());
    ASSERT_EQ(::link(scan.c_str(), link.c_str()), 0);
    const auto before = gseg::io::readFileBytes(scan);
    for (const std::string& args : {"--labels-out '" + scan + "'", "--png-out '" + link + "'",
                                    "--ply-out '" + kDir + "/./in.bin'"}) {
        const ToolRun r = segmentTool("'" + scan + "' " + args);
        EXPECT_EQ(r.status, 2) << args << "\n" << r.output;
        EXPECT_NE(r.output.find("refusing to overwrite an input"), std::string::npos) << r.output;
    }
    EXPECT_EQ(gseg::io::readFileBytes(scan), before);
    const std::string both = out("both.out");
    const ToolRun r = segmentTool("'" + scan + "' --ply-out '" + both + "' --png-out '" + both + "'");
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_FALSE(exists(both));
}

TEST(SegmentToolHostile, FullDiskWritesNoOutputAtAll) {
    // 4 blocks fit the labels (400 bytes) but not the PLY: nothing may be left, not even the labels
    // (before: the labels were written, and a cut PNG reported as written with exit 0).
    const std::string scan = writeBin("full.bin", flatScan());
    const std::string labels = out("full.labels"), ply = out("full.ply"), png = out("full.png");
    const ToolRun r = gseg::test::runCommand("ulimit -f 4; exec '" + gseg::test::tool("gseg") + "' segment '" + scan +
                                             "' --labels-out '" + labels + "' --ply-out '" + ply + "' --png-out '" + png + "'");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("File too large"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("wrote"), std::string::npos) << r.output;
    for (const std::string& p : {labels, ply, png}) EXPECT_FALSE(exists(p)) << p;
    EXPECT_EQ(gseg::test::entriesContaining(kDir, ".tmp"), "");
}

TEST(SegmentToolRawlog, AScanThatCannotBeReadNamesItsEntryInOneLine) {
    const std::string rawlog = (gseg::test::freshDir("segment_tool", "rawlog_errors") / "broken.rawlog").string();
    {
        gseg::mrpt::RawlogWriter w(rawlog);
        mrpt::obs::CObservationVelodyneScan broken;
        broken.sensorLabel = "BROKEN";
        broken.point_cloud.x.assign(100, 1.f);
        broken.point_cloud.y.assign(10, 1.f);
        broken.point_cloud.z.assign(10, 1.f);
        w.write(broken);
        w.commit();
    }
    const ToolRun r = segmentTool("'" + rawlog + "'");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("rawlog entry 0: CObservationVelodyneScan 'BROKEN': point_cloud vectors differ in length "
                            "(x 100, y 10, z 10"),
              std::string::npos)
        << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
}
