// The README's two routes to the traversability maps give the same files, byte for byte:
//   kitti2rawlog SEQ -o X.rawlog --simplemap X.simplemap
//   rawlog-octomap -i X.rawlog -o PREFIX -c config/kitti_hdl64.yaml
//   LD_PRELOAD=build/lib/libgseg_map.so observations2map config/octomap_maps.ini X.simplemap OUT
// (and gseg-observations2map, which cannot end having written nothing). On a simulated KITTI-like
// sequence always, and on SemanticKITTI 00 where ../shared/data has it. The observations2map part
// is skipped where mrpt-apps is not installed.
#include <gseg/map/traversability_map.hpp>
#include <support/child.hpp>
#include <support/lidar_sim.hpp>
#include <support/map_files.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <iterator>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

using gseg::test::runCommand;

const std::string kSource = GSEG_SOURCE_DIR, kBuild = GSEG_BINARY_DIR;

/// Sanitized builds: stock observations2map loading the sanitized plugin needs the ASan runtime
/// first in LD_PRELOAD (and leaks of the stock app are not ours). Empty in other builds.
const std::string kAsan = GSEG_ASAN_RUNTIME;
const std::string kHostEnv = kAsan.empty() ? "" : "LD_PRELOAD='" + kAsan + "' ASAN_OPTIONS=detect_leaks=0 ";
const std::string kPreload = kAsan.empty() ? "" : kAsan + ":";

bool haveObservations2map() { return runCommand("command -v observations2map").status == 0; }

std::string tempDir(const std::string& name) { return gseg::test::freshDir("map_routes", name).string(); }

/// A KITTI odometry sequence of four HDL-64 scans 2 m apart on a street with a wall and a box:
/// velodyne/*.bin, poses.txt (camera 0), calib.txt (Tr) and times.txt.
std::string simulatedSequence(const std::string& dir, double height = 1.723) {
    fs::create_directories(dir + "/velodyne");
    std::ofstream poses(dir + "/poses.txt"), times(dir + "/times.txt");
    for (int k = 0; k < 4; ++k) {
        const double x = 2.0 * k;  // the sensor moves along velodyne x = camera z
        gseg::test::Scene scene;
        scene.addFlatGround(height);
        scene.addBox(12 - x, 4, -height, 13 - x, 5, -0.2);      // a box ahead on the left
        scene.addBox(-10 - x, -6.2, -height, 30 - x, -6, 1.5);  // a wall on the right
        gseg::test::Lidar lidar;
        lidar.seed = 11u + unsigned(k);
        const gseg::test::SimScan s = gseg::test::simulate(scene, lidar);
        std::vector<float> xyzi;
        for (std::size_t i = 0; i < s.size(); ++i) xyzi.insert(xyzi.end(), {s.xyz[3 * i], s.xyz[3 * i + 1], s.xyz[3 * i + 2], 0.5f});
        char name[64];
        std::snprintf(name, sizeof name, "/velodyne/%06d.bin", k);
        std::ofstream(dir + name, std::ios::binary).write(reinterpret_cast<const char*>(xyzi.data()), std::streamsize(xyzi.size() * 4));
        poses << "1 0 0 0 0 1 0 0 0 0 1 " << x << "\n";
        times << 0.1 * k << "\n";
    }
    std::ofstream(dir + "/calib.txt") << "Tr: 0 -1 0 0 0 0 -1 0 1 0 0 0\n";
    return dir;
}

/// kitti2rawlog of the first scan of simulatedSequence(dir/seq): dir/seq.rawlog and dir/seq.simplemap.
gseg::test::CommandResult simulatedSimplemap(const std::string& dir) {
    return runCommand(gseg::test::tool("kitti2rawlog") + " -i '" + simulatedSequence(dir + "/seq") + "' -o " + dir +
                      "/seq.rawlog --simplemap " + dir + "/seq.simplemap --last 1");
}

/// The YAML that says what an observations2map INI (one gsegTraversabilityMap) says: its `_gseg`
/// keys at the top level, `_sensorHeight` as `sensorHeight:`, `_creationOpts` as `traversability:`.
std::string yamlOfIni(const std::string& ini) {
    std::istringstream in(ini);
    std::string line, yaml, map;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == ';' || line[0] == '#') continue;
        if (line[0] == '[') {
            map = line.find("_sensorHeight]") != std::string::npos   ? "sensorHeight"
                  : line.find("_creationOpts]") != std::string::npos ? "traversability"
                  : line.find("_gseg]") != std::string::npos         ? ""
                                                                     : "-";
            if (map != "-" && !map.empty()) yaml += map + ":\n";
            continue;
        }
        const std::size_t eq = line.find('=');
        if (map == "-" || eq == std::string::npos) continue;
        auto trim = [](std::string t) {
            t.erase(0, t.find_first_not_of(" \t"));
            t.erase(t.find_last_not_of(" \t") + 1);
            return t;
        };
        yaml += (map.empty() ? "" : "  ") + trim(line.substr(0, eq)) + ": " + trim(line.substr(eq + 1)) + "\n";
    }
    return yaml;
}

/// Runs both routes on `sequence` and compares every file: rawlog-octomap with `yaml` (relative to
/// the source folder, or absolute), observations2map and the wrapper with `ini`.
void expectSameMapsFromBothRoutes(const std::string& sequence, const std::string& dir,
                                  const std::string& yaml = "config/kitti_hdl64.yaml",
                                  const std::string& ini = "config/octomap_maps.ini") {
    ASSERT_EQ(gseg::map::TraversabilityMap::outputPaths("x").size(), gseg::test::kMapFiles.size());
    auto r = runCommand(gseg::test::tool("kitti2rawlog") + " -i '" + sequence + "' -o " + dir + "/seq.rawlog --simplemap " +
                        dir + "/seq.simplemap");
    ASSERT_EQ(r.status, 0) << r.output;
    r = runCommand("cd '" + kSource + "' && '" + gseg::test::tool("rawlog-octomap") + "' -i " + dir + "/seq.rawlog -o " +
                   dir + "/r -c " + yaml);
    ASSERT_EQ(r.status, 0) << r.output;
    if (!haveObservations2map()) GTEST_SKIP() << "observations2map absent (apt-get install mrpt-apps): route 2 not run";
    r = runCommand("cd '" + kSource + "' && " + (kAsan.empty() ? "" : "ASAN_OPTIONS=detect_leaks=0 ") + "LD_PRELOAD='" + kPreload + kBuild + "/lib/libgseg_map.so' observations2map " + ini + " " +
                   dir + "/seq.simplemap " + dir + "/o2m < /dev/null");
    ASSERT_EQ(r.status, 0) << r.output;
    r = runCommand("cd '" + kSource + "' && " + kHostEnv + "'" + gseg::test::tool("gseg-observations2map") + "' " + ini + " " + dir +
                   "/seq.simplemap " + dir + "/w");
    ASSERT_EQ(r.status, 0) << r.output;
    for (const std::string& s : gseg::test::kMapFiles) {
        const std::string a = gseg::test::readText(dir + "/r" + s);
        EXPECT_GT(a.size(), 100u) << s;
        // The costmap's YAML names its own PGM: compared with the prefix swapped.
        auto named = [&](const std::string& prefix) {
            std::string t = gseg::test::readText(dir + "/" + prefix + s);
            const std::size_t at = s == "_costmap.yaml" ? t.find(prefix + "_costmap.pgm") : std::string::npos;
            return at == std::string::npos ? t : t.replace(at, prefix.size(), "r");
        };
        EXPECT_TRUE(a == named("o2m_gseg_maps__CTraversabilityOctoMap_00")) << s << " differs";
        EXPECT_TRUE(a == named("w_gseg_maps__CTraversabilityOctoMap_00")) << s << " differs";
    }
}

}  // namespace

TEST(MapRoutes, RawlogOctomapAndObservations2mapGiveByteIdenticalFilesOnASimulatedDrive) {
    const std::string dir = tempDir("sim");
    expectSameMapsFromBothRoutes(simulatedSequence(dir + "/seq"), dir);
    fs::remove_all(dir);
}

TEST(MapRoutes, AnIniThatSaysDistToGroundAutoMapsAsTheToolWithAutoHeight) {
    // #17: the plugin kept only the parameters of its configuration, so `distToGround = auto`
    // mapped with the default height and said nothing.
    const std::string dir = tempDir("auto");
    std::string ini = gseg::test::readText(kSource + "/config/octomap_maps.ini");
    const std::size_t at = ini.find("distToGround = 1.723");
    ASSERT_NE(at, std::string::npos) << "config/octomap_maps.ini changed: adapt the test";
    ini.replace(at, std::string("distToGround = 1.723").size(), "distToGround = auto");
    std::ofstream(dir + "/auto.ini") << ini;
    std::ofstream(dir + "/auto.yaml") << yamlOfIni(ini);
    ASSERT_NE(yamlOfIni(ini).find("distToGround: auto\n"), std::string::npos) << yamlOfIni(ini);
    // The sensor 2.2 m up instead of the configured 1.723 m: the estimated height maps otherwise.
    const std::string sequence = simulatedSequence(dir + "/seq", 2.2);
    expectSameMapsFromBothRoutes(sequence, dir, dir + "/auto.yaml", dir + "/auto.ini");
    const auto fixedHeight = runCommand("cd '" + kSource + "' && '" + gseg::test::tool("rawlog-octomap") + "' -i " + dir +
                                        "/seq.rawlog -o " + dir + "/fixed -c config/kitti_hdl64.yaml");
    ASSERT_EQ(fixedHeight.status, 0) << fixedHeight.output;
    EXPECT_FALSE(gseg::test::readText(dir + "/fixed_ground.bt") == gseg::test::readText(dir + "/r_ground.bt"))
        << "auto and fixed height gave the same map: the test shows nothing";
    fs::remove_all(dir);
}

TEST(MapRoutes, RawlogOctomapAndObservations2mapGiveByteIdenticalFilesOnKitti00) {
    const std::string poses = gseg::test::sharedData("semantickitti/sequences/00/poses.txt");
    if (poses.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/00/poses.txt");
    const std::string dir = tempDir("kitti");
    expectSameMapsFromBothRoutes(fs::path(poses).parent_path().string(), dir);
    fs::remove_all(dir);
}

TEST(MapRoutes, Observations2mapWithoutThePluginWritesNothingAndTheWrapperSaysSo) {
    if (!haveObservations2map()) GTEST_SKIP() << "observations2map absent (apt-get install mrpt-apps)";
    const std::string dir = tempDir("noplugin");
    auto r = simulatedSimplemap(dir);
    ASSERT_EQ(r.status, 0) << r.output;
    // MRPT's behaviour, the reason for the wrapper: exit 0, "done", no file.
    r = runCommand("cd '" + kSource + "' && observations2map config/octomap_maps.ini " + dir + "/seq.simplemap " + dir +
                   "/bare < /dev/null");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_FALSE(fs::exists(dir + "/bare_gseg_maps__CTraversabilityOctoMap_00_ground.bt"));
    // The wrapper: a configuration without gseg's map is bad usage, an empty simplemap bad input.
    std::ofstream(dir + "/none.ini") << "[MappingApplication]\nCOccupancyGridMap2D_count = 0\n";
    const std::string wrapper = kHostEnv + gseg::test::tool("gseg-observations2map");
    r = runCommand(wrapper + " " + dir + "/none.ini " + dir + "/seq.simplemap " + dir + "/w");
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("no gsegTraversabilityMap"), std::string::npos) << r.output;
    r = runCommand(wrapper + " '" + kSource + "/config/octomap_maps.ini' " + dir + "/missing.simplemap " + dir + "/w");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("missing.simplemap: cannot read"), std::string::npos) << r.output;
    r = runCommand(wrapper + " '" + kSource + "/config/octomap_maps.ini' " + dir + "/seq.simplemap");
    EXPECT_EQ(r.status, 2) << r.output;
    // A previous run's files do not count as written now: a simplemap without scans leaves the
    // map empty, observations2map exits 0 and writes nothing.
    r = runCommand(wrapper + " '" + kSource + "/config/octomap_maps.ini' " + dir + "/seq.simplemap " + dir + "/w");
    ASSERT_EQ(r.status, 0) << r.output;
    {
        mrpt::io::CFileGZOutputStream f(dir + "/empty.simplemap");
        mrpt::serialization::archiveFrom(f) << mrpt::maps::CSimpleMap();
    }
    r = runCommand(wrapper + " -w '" + kSource + "/config/octomap_maps.ini' " + dir + "/empty.simplemap " + dir + "/w");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("observations2map wrote no"), std::string::npos) << r.output;
    std::ofstream(dir + "/garbage.simplemap") << "not a simplemap";
    r = runCommand(wrapper + " -w '" + kSource + "/config/octomap_maps.ini' " + dir + "/garbage.simplemap " + dir + "/w");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_EQ(runCommand(wrapper + " --version").status, 0);
    EXPECT_EQ(runCommand(wrapper + " --help").status, 0);
    fs::remove_all(dir);
}

// #18 points 7 and 8, #17 item 5: the wrapper prints why observations2map failed, in one line
// naming the file (and line and key where there is one), exit 1; the plugin's INI refuses unknown
// and repeated keys as a YAML file does, and keeps the whole configuration (distToGround = auto).
TEST(MapRoutes, TheWrapperNamesTheFileAndReasonOfEveryConfigurationError) {
    if (!haveObservations2map()) GTEST_SKIP() << "observations2map absent (apt-get install mrpt-apps)";
    const std::string dir = tempDir("wrapper_errors");
    auto r = simulatedSimplemap(dir);
    ASSERT_EQ(r.status, 0) << r.output;
    const std::string ini = gseg::test::readText(kSource + "/config/octomap_maps.ini");
    const auto lineOf = [&](const std::string& text, const std::string& key) {
        const std::size_t at = text.find("\n" + key + " = ");
        return std::to_string(1 + std::count(text.begin(), text.begin() + long(at) + 1, '\n'));
    };
    struct Case {
        std::string key, replacement, expected;  // expected: after "<file>"
    };
    const std::string gsegSection = "[MappingApplication_gsegTraversabilityMap_00_gseg]";
    const std::string optsSection = "[MappingApplication_gsegTraversabilityMap_00_creationOpts]";
    const Case cases[] = {
        {"distToGround", "distToGround = banana", ":" + lineOf(ini, "distToGround") + ": " + gsegSection +
                                                      ": parameter 'distToGround': cannot read 'banana' as a number"},
        {"resolution", "resolution = 0", ": TraversabilityOptions.resolution [m] = 0: must lie in [0.01, 10]"},
        {"probHit", "probHit = 1.5", ": TraversabilityOptions.probHit = 1.5: must lie in (0.5, 1)"},
        {"distToGround", "distToGround = 1.723\nbananaKey = 1",
         ":" + std::to_string(std::stoi(lineOf(ini, "distToGround")) + 1) + ": " + gsegSection + ": unknown parameter 'bananaKey'"},
        {"probHit", "probHit = 0.7\nprobHits = 0.7",
         ":" + std::to_string(std::stoi(lineOf(ini, "probHit")) + 1) + ": " + optsSection + ": unknown traversability option 'probHits'"},
        {"distToGround", "distToGround = 1.723\ndistToGround = 1.9",
         ":" + std::to_string(std::stoi(lineOf(ini, "distToGround")) + 1) + ": " + gsegSection +
             " 'distToGround' given twice (also on line " + lineOf(ini, "distToGround") + ")"},
    };
    const std::string wrapper = kHostEnv + gseg::test::tool("gseg-observations2map");
    for (const Case& c : cases) {
        std::string text = ini;
        const std::size_t at = text.find("\n" + c.key + " = ") + 1;
        text.replace(at, text.find('\n', at) - at, c.replacement);
        const std::string path = dir + "/bad.ini";
        std::ofstream(path) << text;
        r = runCommand(wrapper + " -w " + path + " " + dir + "/seq.simplemap " + dir + "/m");
        EXPECT_EQ(r.status, 1) << r.output;
        EXPECT_NE(r.output.find("gseg-observations2map: " + path + c.expected + "\n"), std::string::npos)
            << c.replacement << " -> " << r.output;
        EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << "one line: " << r.output;
        EXPECT_FALSE(fs::exists(dir + "/m_gseg_maps__CTraversabilityOctoMap_00_ground.bt"));
    }
    // A FIFO (as configuration or input) is refused before observations2map runs.
    ASSERT_EQ(::mkfifo((dir + "/fifo").c_str(), 0600), 0);
    r = runCommand(wrapper + " '" + kSource + "/config/octomap_maps.ini' " + dir + "/fifo " + dir + "/m");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find(dir + "/fifo: not a regular file"), std::string::npos) << r.output;
    r = runCommand(wrapper + " " + dir + "/fifo " + dir + "/seq.simplemap " + dir + "/m");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find(dir + "/fifo: not a regular file"), std::string::npos) << r.output;
    fs::remove_all(dir);
}
