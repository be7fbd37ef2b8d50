// What a user sees first in the Debian viewers (issue #22): every PLY carries its class as a
// scalar field CloudCompare loads by default, in the one palette; CloudCompare -SILENT under Xvfb
// keeps it (skipped where CloudCompare is not installed); every .3Dscene carries its legend and
// opens framing its whole content; the README's VLP-16 and sequence-00 figures come from runs.

#include "support/child.hpp"
#include "support/paths.hpp"

#include <gseg/io/ply.hpp>
#include <gseg/map/map_colours.hpp>
#include <gseg/map/traversability_map.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/rawlog_io.hpp>
#include <gseg/mrpt/scene.hpp>
#include <gseg/palette.hpp>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/opengl/COctoMapVoxels.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/COpenGLViewport.h>
#include <mrpt/opengl/CText.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

/// A seeded scan: x, y, z, intensity per point, ground (label 1) on z = -1.7, the rest above it.
struct LabelledScan {
    std::vector<float> xyzi;
    std::vector<std::uint8_t> labels;
};

LabelledScan seededScan(std::size_t n) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-20.f, 20.f), h(0.f, 2.f), in(0.f, 255.f);
    LabelledScan s;
    for (std::size_t i = 0; i < n; ++i) {
        const bool ground = i % 3 != 0;
        s.xyzi.insert(s.xyzi.end(), {u(rng), u(rng), ground ? -1.7f : -1.2f + h(rng), in(rng)});
        s.labels.push_back(ground ? 1 : 0);
    }
    return s;
}

/// A small map: a ground plane around the origin and a wall at x = 6, seen from two sensor positions.
std::string writeSmallMap(const fs::path& dir, gseg::map::MapStats* stats = nullptr) {
    std::vector<float> ground, wall;
    for (float x = -8; x <= 8; x += 0.1f)
        for (float y = -8; y <= 8; y += 0.1f) ground.insert(ground.end(), {x, y, -1.7f});
    for (float y = -3; y <= 3; y += 0.1f)
        for (float z = -1.5f; z <= 0.5f; z += 0.1f) wall.insert(wall.end(), {6.f, y, z});
    gseg::map::TraversabilityMap map;
    for (const double x : {0.0, 1.0})
        map.insertScan(gseg::PointCloudView(ground.data(), ground.size() / 3), gseg::PointCloudView(wall.data(), wall.size() / 3),
                       Eigen::Vector3d(x, 0, 0));
    const std::string prefix = (dir / "map").string();
    map.write(prefix);
    if (stats) *stats = map.stats();
    return prefix;
}

/// The PLY's class field, label and colours agree point by point: class 1 exactly where label 1
/// (ground), 2 where label 0; RGB the palette's colour of the label.
void expectClassFieldAgrees(const std::string& ply, const std::string& scalar) {
    const std::vector<double> label = gseg::io::readPlyProperty(ply, "label"), cls = gseg::io::readPlyProperty(ply, scalar);
    const std::vector<double> r = gseg::io::readPlyProperty(ply, "red"), g = gseg::io::readPlyProperty(ply, "green"),
                              b = gseg::io::readPlyProperty(ply, "blue");
    ASSERT_EQ(cls.size(), label.size());
    std::size_t ones = 0;
    for (std::size_t i = 0; i < label.size(); ++i) {
        ASSERT_TRUE(label[i] == 0 || label[i] == 1) << ply << " vertex " << i;
        ASSERT_EQ(cls[i], label[i] == 1 ? 1 : 2) << ply << " vertex " << i;
        const std::uint8_t* want = label[i] == 1 ? gseg::palette::kGround : gseg::palette::kNonGround;
        ASSERT_EQ(r[i], want[0]) << i;
        ASSERT_EQ(g[i], want[1]) << i;
        ASSERT_EQ(b[i], want[2]) << i;
        ones += cls[i] == 1;
    }
    EXPECT_GT(ones, 0u) << ply;
    EXPECT_LT(ones, label.size()) << ply;
}

/// The names of a PLY's vertex properties, in header order.
std::vector<std::string> plyProperties(const std::string& ply) {
    std::istringstream in(gseg::test::readText(ply).substr(0, 4096));
    std::vector<std::string> names;
    for (std::string line; std::getline(in, line) && line != "end_header";) {
        std::istringstream words(line);
        std::string w, type, name;
        words >> w >> type >> name;
        if (w == "property") names.push_back(name);
    }
    return names;
}

}  // namespace

TEST(ViewerPly, ScanPlyCarriesTheClassFirstAsAScalarFieldAndReadsBack) {
    const fs::path dir = gseg::test::freshDir("viewers", "scan_ply");
    const LabelledScan s = seededScan(3000);
    gseg::io::PlyOptions options;
    options.intensity = true;
    const std::string ply = (dir / "scan.ply").string();
    gseg::io::writeLabelledPly(ply, gseg::PointCloudView(s.xyzi.data(), s.labels.size(), 16), s.labels, gseg::io::PlyColours(),
                               options);
    EXPECT_EQ(gseg::io::classScalarProperty(options), "scalar_class");
    // CloudCompare shows the first scalar field: the class, before the intensity.
    const std::vector<std::string> props = plyProperties(ply);
    const std::vector<std::string> want = {"x", "y", "z", "scalar_class", "intensity", "red", "green", "blue", "label"};
    EXPECT_EQ(props, want);
    EXPECT_EQ(gseg::io::readPly(ply), s.xyzi);  // x, y, z, intensity exactly
    const std::vector<double> label = gseg::io::readPlyProperty(ply, "label");
    for (std::size_t i = 0; i < label.size(); ++i) ASSERT_EQ(label[i], s.labels[i]) << i;
    expectClassFieldAgrees(ply, "scalar_class");
    // #33: the header says one convention, 1 the ground in every field (was scalar_non_ground 1
    // non-ground beside label 1 ground).
    const std::string text = gseg::test::readText(ply).substr(0, 1024);
    EXPECT_NE(text.find("comment scalar_class: 1 ground, 2 non-ground"), std::string::npos) << text;
    EXPECT_NE(text.find("comment label: 1 ground, 0 non-ground"), std::string::npos) << text;
}

TEST(ViewerPly, MapPlyCarriesTheObstacleClassAsAScalarFieldInThePalette) {
    const fs::path dir = gseg::test::freshDir("viewers", "map_ply");
    const std::string ply = writeSmallMap(dir) + "_traversability.ply";
    const std::vector<std::string> props = plyProperties(ply);
    ASSERT_GE(props.size(), 4u);
    EXPECT_EQ(props[3], "scalar_class");  // the scan's field, the same values
    expectClassFieldAgrees(ply, "scalar_class");
    // The palette is the map's colours too.
    const auto t = gseg::map::colourOf(gseg::map::ColumnClass::Traversable), o = gseg::map::colourOf(gseg::map::ColumnClass::Obstacle);
    EXPECT_EQ(std::vector<int>({t.r, t.g, t.b}), std::vector<int>(gseg::palette::kGround, gseg::palette::kGround + 3));
    EXPECT_EQ(std::vector<int>({o.r, o.g, o.b}), std::vector<int>(gseg::palette::kNonGround, gseg::palette::kNonGround + 3));
}

/// Runs `CloudCompare -SILENT` under Xvfb on `ply`, exporting what it loaded as ASC with a header;
/// returns the column names and the rows, or skips the test where CloudCompare is absent.
struct Asc {
    std::vector<std::string> columns;
    std::vector<std::vector<double>> rows;
};

Asc cloudCompareSilent(const fs::path& dir, const std::string& ply, std::string& error) {
    const std::string cmd = "cd '" + dir.string() + "' && xvfb-run -a env LIBGL_ALWAYS_SOFTWARE=1 CloudCompare -SILENT -O '" + ply +
                            "' -C_EXPORT_FMT ASC -SEP SEMICOLON -ADD_HEADER -SAVE_CLOUDS 2>&1";
    const auto r = gseg::test::runCommand(cmd);
    Asc asc;
    std::string file;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.path().extension() == ".asc") file = e.path().string();
    if (r.status != 0 || file.empty()) {
        error = "CloudCompare -SILENT wrote no ASC (exit " + std::to_string(r.status) + "): " + r.output;
        return asc;
    }
    std::ifstream in(file);
    std::string line;
    std::getline(in, line);
    if (line.rfind("//", 0) == 0) line = line.substr(2);
    std::istringstream header(line);
    for (std::string c; std::getline(header, c, ';');) asc.columns.push_back(c);
    while (std::getline(in, line)) {
        std::istringstream cells(line);
        std::vector<double> row;
        for (std::string c; std::getline(cells, c, ';');) row.push_back(std::stod(c));
        asc.rows.push_back(row);
    }
    return asc;
}

bool haveCloudCompare() {
    return gseg::test::runCommand("command -v CloudCompare && command -v xvfb-run").status == 0;
}

TEST(ViewerPly, CloudCompareSilentLoadsTheClassFieldOfScanAndMapPlys) {
    if (!haveCloudCompare())
        GTEST_SKIP() << "CloudCompare or xvfb-run not installed (apt-get install cloudcompare xvfb): not checked";
    const fs::path dir = gseg::test::freshDir("viewers", "cloudcompare");
    const LabelledScan s = seededScan(2000);
    gseg::io::PlyOptions options;
    options.intensity = true;
    fs::create_directories(dir / "scan");
    const std::string scan = (dir / "scan" / "scan.ply").string();
    gseg::io::writeLabelledPly(scan, gseg::PointCloudView(s.xyzi.data(), s.labels.size(), 16), s.labels, gseg::io::PlyColours(),
                               options);
    fs::create_directories(dir / "map");
    const std::string map = writeSmallMap(dir / "map") + "_traversability.ply";
    const struct {
        std::string ply, field;
    } cases[] = {{scan, "class"}, {map, "class"}};
    for (const auto& c : cases) {
        SCOPED_TRACE(c.ply);
        std::string error;
        const Asc asc = cloudCompareSilent(fs::path(c.ply).parent_path(), c.ply, error);
        ASSERT_TRUE(error.empty()) << error;
        // CloudCompare's own name for the field (the `scalar_` prefix dropped, `_` as a space).
        const auto at = std::find(asc.columns.begin(), asc.columns.end(), c.field);
        ASSERT_NE(at, asc.columns.end()) << "no '" << c.field << "' column among " << ::testing::PrintToString(asc.columns);
        const std::size_t k = std::size_t(at - asc.columns.begin());
        const std::vector<double> label = gseg::io::readPlyProperty(c.ply, "label");
        ASSERT_EQ(asc.rows.size(), label.size());
        const auto g = std::find(asc.columns.begin(), asc.columns.end(), "G");
        ASSERT_NE(g, asc.columns.end());
        for (std::size_t i = 0; i < label.size(); ++i) {
            ASSERT_EQ(asc.rows[i].at(k), label[i] == 1 ? 1 : 2) << "point " << i;
            ASSERT_EQ(asc.rows[i].at(std::size_t(g - asc.columns.begin())),
                      label[i] == 1 ? gseg::palette::kGround[1] : gseg::palette::kNonGround[1]) << "point " << i;
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Scenes: the legend SceneViewer3D draws and the camera it takes from the file.

namespace {

struct SceneView {
    bool followCamera = false;
    double legendWidth = 0, legendHeight = 0;  ///< [px] the legend viewport's size
    double pathMark = 0;                       ///< [m] the boxes at the sensor positions
    float pointing[3] = {0, 0, 0};
    float zoom = 0;
    std::vector<std::string> legend;  ///< the legend viewport's texts, in order
};

SceneView readScene(const std::string& path) {
    mrpt::opengl::COpenGLScene scene;
    EXPECT_TRUE(scene.loadFromFile(path)) << path;
    SceneView v;
    v.followCamera = scene.followCamera();
    const auto& cam = scene.getViewport("main")->getCamera();
    v.pointing[0] = cam.getPointingAtX(), v.pointing[1] = cam.getPointingAtY(), v.pointing[2] = cam.getPointingAtZ();
    v.zoom = cam.getZoomDistance();
    if (const auto legend = scene.getViewport("legend")) {
        double x = 0, y = 0;
        legend->getViewportPosition(x, y, v.legendWidth, v.legendHeight);
        for (const auto& o : *legend)
            if (const auto text = std::dynamic_pointer_cast<mrpt::opengl::CText>(o)) v.legend.push_back(text->getString());
    }
    for (const auto& o : *scene.getViewport("main"))
        if (const auto marks = std::dynamic_pointer_cast<mrpt::opengl::COctoMapVoxels>(o); marks && marks->getName() == "sensor positions, blue")
            if (marks->getVoxelCount(0) > 0) v.pathMark = marks->getVoxel(0, 0).side_length;
    return v;
}

/// The camera frames the box: pointing at its centre, and the box's bounding sphere within the
/// 30 deg field of view at that distance (not a close-up of a part of it, nor a speck).
void expectFrames(const SceneView& v, const float lo[3], const float hi[3]) {
    float r2 = 0;
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(v.pointing[a], 0.5f * (lo[a] + hi[a]), 1e-3f) << "axis " << a;
        r2 += 0.25f * (hi[a] - lo[a]) * (hi[a] - lo[a]);
    }
    const float halfHeight = v.zoom * std::tan(15.f * 3.14159265f / 180.f);  // visible half height at the centre
    EXPECT_GT(v.zoom, std::sqrt(r2)) << "the camera sits inside the content";
    EXPECT_GT(halfHeight, 0.5f * std::sqrt(r2)) << "a close-up: the content is larger than the view";
    EXPECT_LT(halfHeight, 2.0f * std::sqrt(r2)) << "the content is a speck in the view";
}

}  // namespace

TEST(ViewerScene, ScanSceneCarriesItsLegendAndFramesEveryPoint) {
    const fs::path dir = gseg::test::freshDir("viewers", "scan_scene");
    const LabelledScan s = seededScan(3000);
    const gseg::PointCloudView view(s.xyzi.data(), s.labels.size(), 16);
    const std::string path = (dir / "scan.3Dscene").string();
    const std::string bytes = gseg::mrpt::scanSceneBytes(view, s.labels, "gseg: a seeded scan");
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    const SceneView v = readScene(path);
    EXPECT_TRUE(v.followCamera) << "SceneViewer3D keeps its own close-up camera unless followCamera is set";
    ASSERT_GE(v.legend.size(), 3u);
    EXPECT_EQ(v.legend[0], "gseg: a seeded scan");
    EXPECT_EQ(v.legend[1], "ground: 2000 points");
    EXPECT_EQ(v.legend[2], "non-ground: 1000 points");
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (std::size_t i = 0; i < view.size(); ++i)
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], view.point(i)[a]), hi[a] = std::max(hi[a], view.point(i)[a]);
    expectFrames(v, lo, hi);
}

TEST(ViewerScene, MapSceneCarriesItsLegendAndFramesTheWholeMap) {
    const fs::path dir = gseg::test::freshDir("viewers", "map_scene");
    gseg::map::MapStats stats;
    const std::string prefix = writeSmallMap(dir, &stats);
    const SceneView v = readScene(prefix + "_traversability.3Dscene");
    EXPECT_TRUE(v.followCamera);
    ASSERT_EQ(v.legend.size(), 6u);
    // The counts are the console's (rawlog-octomap's "voxels (0.20 m): N ground, M obstacle").
    EXPECT_EQ(v.legend[1].rfind("ground voxels: " + std::to_string(stats.groundVoxels), 0), 0u) << v.legend[1];
    EXPECT_EQ(v.legend[2], "obstacle voxels: " + std::to_string(stats.obstacleVoxels));
    // The legend's box is sized to its longest line, not to the window.
    std::size_t chars = 0;
    for (const auto& t : v.legend) chars = std::max(chars, t.size());
    EXPECT_GT(v.legendWidth, 1.0) << "a width in pixels";
    EXPECT_LE(v.legendWidth, gseg::mrpt::kSceneLegendCharPx * double(chars) + 2 * gseg::mrpt::kSceneLegendPadPx);
    EXPECT_NEAR(v.legendHeight, gseg::mrpt::kSceneLegendLinePx * 6 + gseg::mrpt::kSceneLegendPadPx, 1e-9);
    EXPECT_GE(v.pathMark, 0.4) << "the sensor positions: boxes of at least two voxels";
    EXPECT_NE(v.legend[0].find("traversability map"), std::string::npos) << v.legend[0];
    EXPECT_NE(v.legend[1].find("ground voxels"), std::string::npos) << v.legend[1];
    EXPECT_NE(v.legend[2].find("obstacle"), std::string::npos) << v.legend[2];
    EXPECT_NE(v.legend[3].find("2.5D map"), std::string::npos) << v.legend[3];
    EXPECT_NE(v.legend[4].find("path"), std::string::npos) << v.legend[4];
    // The box of the voxels shown (the PLY holds their centres) and the path.
    const std::vector<float> xyz = gseg::io::readPly(prefix + "_traversability.ply");
    float lo[3] = {0, 0, 0}, hi[3] = {1, 0, 0};  // the path: (0,0,0) and (1,0,0)
    for (std::size_t i = 0; i < xyz.size(); i += 4)
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], xyz[i + std::size_t(a)]), hi[a] = std::max(hi[a], xyz[i + std::size_t(a)]);
    expectFrames(v, lo, hi);
}

// ---------------------------------------------------------------------------------------------
// The README's figures come from runs: parsed from README.md and the pages it links that hold them
// (docs/mrpt.md, docs/maps.md), compared with what the tools print and write.

namespace {

/// README.md and its pages with figures, with every run of whitespace as one space (their
/// sentences wrap anywhere).
std::string readmeFlat() {
    std::string text;
    for (const char* page : {"/README.md", "/docs/mrpt.md", "/docs/maps.md"})
        text += gseg::test::readText(std::string(GSEG_SOURCE_DIR) + page) + "\n";
    std::string flat;
    for (const char c : text)
        if (!std::isspace(static_cast<unsigned char>(c))) flat += c;
        else if (!flat.empty() && flat.back() != ' ') flat += ' ';
    return flat;
}

/// The points of the observations labelled `label` in a rawlog.
std::size_t pointsOf(const std::string& rawlog, const std::string& label) {
    std::size_t n = 0;
    gseg::mrpt::forEachRawlogEntry(rawlog, [&](std::size_t, const std::shared_ptr<mrpt::serialization::CSerializable>& o) {
        if (const auto pc = std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(o); pc && pc->sensorLabel == label)
            n += pc->pointcloud->size();
        return true;
    });
    return n;
}

/// "17.1 % ground, 35.00 ms per scan, distToGround auto: estimated 2.27 m" without the time (and
/// the configuration file named relative to the source folder, as the README runs it).
std::string withoutTime(const std::string& line) {
    const std::string shorter = std::regex_replace(line, std::regex("[0-9.]+ ms per scan"), "ms");
    const std::string src = std::string(GSEG_SOURCE_DIR) + "/";
    const std::size_t at = shorter.find("[" + src);
    return at == std::string::npos ? shorter : shorter.substr(0, at + 1) + shorter.substr(at + 1 + src.size());
}

/// The summary line of a rawlog-gseg run ("rawlog-gseg: 1 entries, ..."), "" if none.
std::string summaryLine(const std::string& output) {
    std::istringstream in(output);
    for (std::string line; std::getline(in, line);)
        if (line.rfind("rawlog-gseg: 1 entries", 0) == 0) return line;
    return "";
}

}  // namespace

TEST(ReadmeFigures, Vlp16FiguresAreWhatRawlogGsegWrites) {
    const std::string vlp16 = "/usr/share/mrpt/datasets/test_velodyne_VLP16.rawlog";
    if (!fs::exists(vlp16)) GTEST_SKIP() << vlp16 << " absent (package mrpt-common)";
    const std::string readme = readmeFlat();
    std::smatch m;
    ASSERT_TRUE(std::regex_search(readme, m, std::regex("`Velodyne1_SCAN_ground` \\((\\d+) points\\) and `Velodyne1_SCAN_obstacles` \\((\\d+) points\\)")))
        << "README.md no longer states the VLP-16 split";
    const std::size_t ground = std::stoul(m[1]), obstacles = std::stoul(m[2]);
    const fs::path dir = gseg::test::freshDir("viewers", "readme_vlp16");
    const std::string withConfig = (dir / "vlp16.rawlog").string();
    const auto r = gseg::test::runCommand(gseg::test::tool("rawlog-gseg") + " -i " + vlp16 + " -o " + withConfig + " -c " +
                                          GSEG_SOURCE_DIR + "/config/vlp16.yaml 2>&1");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(pointsOf(withConfig, "Velodyne1_SCAN_ground"), ground);
    EXPECT_EQ(pointsOf(withConfig, "Velodyne1_SCAN_obstacles"), obstacles);
    // The two summaries the README shows (no -c, then config/vlp16.yaml), but for the time.
    std::vector<std::string> shown;
    const std::regex summary("rawlog-gseg: 1 entries, [^;]*; wrote out.rawlog");
    for (auto it = std::sregex_iterator(readme.begin(), readme.end(), summary); it != std::sregex_iterator(); ++it)
        shown.push_back(withoutTime(it->str()));
    ASSERT_EQ(shown.size(), 2u) << "README.md: the two rawlog-gseg summaries of the VLP-16 rawlog";
    const std::string noConfig = (dir / "out.rawlog").string();
    const auto a = gseg::test::runCommand("cd '" + dir.string() + "' && " + gseg::test::tool("rawlog-gseg") + " -i " + vlp16 +
                                          " -o out.rawlog 2>/dev/null");
    ASSERT_EQ(a.status, 0) << a.output;
    const auto b = gseg::test::runCommand("cd '" + dir.string() + "' && " + gseg::test::tool("rawlog-gseg") + " -i " + vlp16 +
                                          " -o out.rawlog -w -c " + GSEG_SOURCE_DIR + "/config/vlp16.yaml 2>/dev/null");
    ASSERT_EQ(b.status, 0) << b.output;
    EXPECT_EQ(withoutTime(summaryLine(a.output)), shown[0]);
    EXPECT_EQ(withoutTime(summaryLine(b.output)), shown[1]);
}

TEST(ReadmeFigures, Sequence00MapFiguresAreWhatRawlogOctomapPrints) {
    const std::string seq = gseg::test::sharedData("semantickitti/sequences/00/poses.txt");
    if (seq.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/00/poses.txt");
    const std::string readme = readmeFlat();
    std::smatch m;
    ASSERT_TRUE(std::regex_search(readme, m, std::regex("this gives (\\d+) ground, (\\d+) obstacle and (\\d+) free voxels at 0.2 m, "
                                                        "clears (\\d+) obstacle voxels and leaves out (\\d+) reflection points")))
        << "README.md no longer states the sequence-00 map figures";
    const fs::path dir = gseg::test::freshDir("viewers", "readme_seq00");
    const std::string rawlog = (dir / "seq00.rawlog").string();
    const auto k = gseg::test::runCommand(gseg::test::tool("kitti2rawlog") + " -q -i " + fs::path(seq).parent_path().string() +
                                          " -o " + rawlog + " 2>&1");
    ASSERT_EQ(k.status, 0) << k.output;
    const auto r = gseg::test::runCommand(gseg::test::tool("rawlog-octomap") + " -i " + rawlog + " -o " + (dir / "seq00").string() +
                                          " -c " + GSEG_SOURCE_DIR + "/config/kitti_hdl64.yaml 2>&1");
    ASSERT_EQ(r.status, 0) << r.output;
    std::smatch v, refl;
    ASSERT_TRUE(std::regex_search(r.output, v, std::regex("voxels \\(0.20 m\\): (\\d+) ground, (\\d+) obstacle, (\\d+) free; (\\d+) obstacle voxels cleared")))
        << r.output;
    ASSERT_TRUE(std::regex_search(r.output, refl, std::regex("(\\d+) points more than belowGroundMargin below the ground left out"))) << r.output;
    EXPECT_EQ(m[1].str(), v[1].str()) << "ground voxels";
    EXPECT_EQ(m[2].str(), v[2].str()) << "obstacle voxels";
    EXPECT_EQ(m[3].str(), v[3].str()) << "free voxels";
    EXPECT_EQ(m[4].str(), v[4].str()) << "cleared obstacle voxels";
    EXPECT_EQ(m[5].str(), refl[1].str()) << "reflection points left out";
}

// ---------------------------------------------------------------------------------------------
// No configuration, any sensor: the loader's default is distToGround: auto where no file sets it.

TEST(DefaultConfig, DistToGroundIsAutoWhereNoFileSetsIt) {
    EXPECT_TRUE(gseg::mrpt::defaultConfig().distToGroundAuto);
    EXPECT_TRUE(gseg::mrpt::loadConfigOrDefault("").distToGroundAuto);  // a tool without -c
    EXPECT_DOUBLE_EQ(gseg::mrpt::defaultConfig().params.distToGround, gseg::Params().distToGround);  // the fallback
    // A file without the key: auto; a number fixes it; KITTI's file keeps its 1.723 m.
    const auto yaml = gseg::mrpt::loadConfigFromText("heightGate: 0.2\n", gseg::mrpt::ConfigFormat::Yaml, "t.yaml");
    EXPECT_TRUE(yaml.distToGroundAuto);
    EXPECT_DOUBLE_EQ(yaml.params.heightGate, 0.2);
    const auto fixed = gseg::mrpt::loadConfigFromText("distToGround: 0.9\n", gseg::mrpt::ConfigFormat::Yaml, "f.yaml");
    EXPECT_FALSE(fixed.distToGroundAuto);
    EXPECT_DOUBLE_EQ(fixed.params.distToGround, 0.9);
    const auto kitti = gseg::mrpt::loadConfig(std::string(GSEG_SOURCE_DIR) + "/config/kitti_hdl64.yaml");
    EXPECT_FALSE(kitti.distToGroundAuto);
    EXPECT_DOUBLE_EQ(kitti.params.distToGround, 1.723);
    EXPECT_FALSE(gseg::mrpt::loadConfigOrDefault(std::string(GSEG_SOURCE_DIR) + "/config/kitti_hdl64.yaml").distToGroundAuto);
    // The map plugin's INI: a gseg section without the key is auto too; with a number, fixed.
    mrpt::config::CConfigFileMemory ini;
    ini.setContent(std::string("[map_gseg]\nheightGate = 0.2\n"));
    gseg::mrpt::IniSections sections;
    sections.params = "map_gseg", sections.sensorHeight = "map_sensorHeight", sections.traversability = "map_creationOpts";
    EXPECT_TRUE(gseg::mrpt::loadConfigFromIni(ini, sections).distToGroundAuto);
    ini.setContent(std::string("[map_gseg]\ndistToGround = 1.723\n"));
    EXPECT_FALSE(gseg::mrpt::loadConfigFromIni(ini, sections).distToGroundAuto);
}

TEST(DefaultConfig, RawlogGsegWithoutConfigFindsTheVlp16GroundAndSaysTheHeight) {
    const std::string vlp16 = "/usr/share/mrpt/datasets/test_velodyne_VLP16.rawlog";
    if (!fs::exists(vlp16)) GTEST_SKIP() << vlp16 << " absent (package mrpt-common)";
    const fs::path dir = gseg::test::freshDir("viewers", "no_config");
    const auto r = gseg::test::runCommand(gseg::test::tool("rawlog-gseg") + " -i " + vlp16 + " -o '" + (dir / "out.rawlog").string() + "' 2>&1");
    ASSERT_EQ(r.status, 0) << r.output;
    const std::string line = summaryLine(r.output);
    std::smatch m;
    ASSERT_TRUE(std::regex_search(line, m, std::regex("([0-9.]+) % ground, .*distToGround auto: estimated ([0-9.]+) m"))) << r.output;
    EXPECT_GT(std::stod(m[1]), 15.0) << "with KITTI's 1.723 m it was 0.7 %";
    EXPECT_NEAR(std::stod(m[2]), 2.27, 0.05);
    EXPECT_EQ(r.output.find("the ground lies"), std::string::npos) << "no height warning where the height is estimated";
    // A fixed height the scan contradicts still warns (and the summary says it was fixed).
    const auto k = gseg::test::runCommand(gseg::test::tool("rawlog-gseg") + " -i " + vlp16 + " -o '" + (dir / "k.rawlog").string() +
                                          "' -c " + GSEG_SOURCE_DIR + "/config/kitti_hdl64.yaml 2>&1");
    ASSERT_EQ(k.status, 0) << k.output;
    EXPECT_NE(k.output.find("the ground lies 2.27 m below the sensor"), std::string::npos) << k.output;
    EXPECT_NE(summaryLine(k.output).find("distToGround 1.723 m (fixed)"), std::string::npos) << k.output;
}
