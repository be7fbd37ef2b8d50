// YAML and INI configuration files, PLY reading/writing.
#include <gseg/io/ply.hpp>
#include <gseg/mrpt/config.hpp>
#include <support/child.hpp>
#include <support/paths.hpp>

#include <mrpt/containers/yaml.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <unistd.h>

namespace {

std::string writeTemp(const std::string& name, const std::string& text) {
    return gseg::test::writeTestFile("mrpt_config", name, text);
}

std::string errorOf(const std::string& path) {
    try {
        gseg::mrpt::loadConfig(path);
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(Config, ShippedKittiFileIsTheLibraryDefaultsWithEveryKey) {
    const std::string path = std::string(GSEG_SOURCE_DIR) + "/config/kitti_hdl64.yaml";
    const auto cfg = gseg::mrpt::loadConfig(path);
    EXPECT_FALSE(cfg.distToGroundAuto);
    EXPECT_DOUBLE_EQ(cfg.params.distToGround, 1.723);
    EXPECT_DOUBLE_EQ(cfg.params.robotRadius, 2.7);
    EXPECT_DOUBLE_EQ(cfg.params.cellSizeX, 1.5);
    EXPECT_DOUBLE_EQ(cfg.params.cellSizeY, 1.0);
    EXPECT_DOUBLE_EQ(cfg.params.cellSizeZPhase1, 1.5);
    EXPECT_DOUBLE_EQ(cfg.params.cellSizeZPhase2, 0.2);
    EXPECT_DOUBLE_EQ(cfg.params.slopeThresholdDegrees, 30.0);
    EXPECT_DOUBLE_EQ(cfg.params.groundInlierThreshold, 0.125);
    EXPECT_DOUBLE_EQ(cfg.params.centroidSearchRadius, 5.0);
    // One source of truth: every key of the file is the library default.
    const gseg::Params defaults;
    for (const auto& key : gseg::Params::keys()) EXPECT_EQ(cfg.params.get(key), defaults.get(key)) << key;
    const std::string text = gseg::test::readText(path);
    // Every key of the algorithm.
    for (const auto& key : gseg::Params::keys())
        EXPECT_NE(text.find("\n" + key + ":"), std::string::npos) << key << " missing from " << path;
    // config/auto_height.yaml: the same with distToGround: auto (the numeric value is the fallback).
    const auto autoCfg = gseg::mrpt::loadConfig(std::string(GSEG_SOURCE_DIR) + "/config/auto_height.yaml");
    EXPECT_TRUE(autoCfg.distToGroundAuto);
    for (const auto& key : gseg::Params::keys()) EXPECT_EQ(autoCfg.params.get(key), defaults.get(key)) << key;
}

TEST(Config, ShippedVlp16File) {
    const auto cfg = gseg::mrpt::loadConfig(std::string(GSEG_SOURCE_DIR) + "/config/vlp16.yaml");
    EXPECT_TRUE(cfg.distToGroundAuto);
    EXPECT_DOUBLE_EQ(cfg.params.cellSizeX, gseg::Params().cellSizeX);  // not given: default
}

TEST(Config, YamlAndIniGiveIdenticalParams) {
    const auto y = gseg::mrpt::loadConfig(
        writeTemp("same.yaml", "distToGround: 0.9\ncellSizeX: 1.25\nransacSeed: 7\nminPointsForPca: 8\n"));
    const auto i = gseg::mrpt::loadConfig(
        writeTemp("same.ini", "[gseg]\ndistToGround = 0.9 ; metres\ncellSizeX = 1.25\nransacSeed = 7\nminPointsForPca = 8\n"));
    for (const auto& key : gseg::Params::keys()) EXPECT_EQ(y.params.get(key), i.params.get(key)) << key;
    EXPECT_DOUBLE_EQ(y.params.cellSizeX, 1.25);
    EXPECT_EQ(y.params.minPointsForPca, 8);
}

TEST(Config, NestedUnderGsegAndAuto) {
    const auto cfg = gseg::mrpt::loadConfig(writeTemp("nested.yaml", "gseg:\n  distToGround: auto\n  heightGate: 0.4\n"));
    EXPECT_TRUE(cfg.distToGroundAuto);
    EXPECT_DOUBLE_EQ(cfg.params.heightGate, 0.4);
    EXPECT_NE(gseg::mrpt::toYaml(cfg).find("distToGround: auto"), std::string::npos);
}

TEST(Config, ErrorsNameFileAndKey) {
    const std::string unknown = writeTemp("unknown_key.yaml", "cellSizeX: 1.5\ncelSizeY: 1.0\n");
    EXPECT_NE(errorOf(unknown).find("celSizeY"), std::string::npos) << errorOf(unknown);
    EXPECT_NE(errorOf(unknown).find(unknown), std::string::npos);
    const std::string negative = writeTemp("negative.yaml", "cellSizeX: -1.5\n");
    EXPECT_NE(errorOf(negative).find("cellSizeX"), std::string::npos) << errorOf(negative);
    const std::string text = writeTemp("text.ini", "[gseg]\nslopeThresholdDegrees = steep\n");
    EXPECT_NE(errorOf(text).find("slopeThresholdDegrees"), std::string::npos) << errorOf(text);
    EXPECT_NE(errorOf("/nonexistent/gseg.yaml").find("cannot open"), std::string::npos);
    EXPECT_NE(errorOf(writeTemp("nosection.ini", "[other]\na = 1\n")).find("[gseg]"), std::string::npos);
    EXPECT_NE(errorOf(writeTemp("x.toml", "a = 1\n")).find("unknown configuration format"), std::string::npos);
}

TEST(Ply, WrittenCloudReadsBackWithColours) {
    const std::vector<float> xyz = {1.5f, -2.f, -1.7f, 3.f, 4.f, 0.5f, -7.25f, 0.f, -1.6f};
    const std::string path = std::string(GSEG_BINARY_DIR) + "/tests/roundtrip.ply";
    gseg::io::writeLabelledPly(path, gseg::PointCloudView(xyz.data(), 3), {1, 0, 1});
    const auto back = gseg::io::readPly(path);
    ASSERT_EQ(back.size(), 12u);
    for (int i = 0; i < 3; ++i)
        for (int a = 0; a < 3; ++a) EXPECT_EQ(back[4 * i + a], xyz[3 * i + a]);
    EXPECT_THROW(gseg::io::writeLabelledPly(path, gseg::PointCloudView(xyz.data(), 3), {1}), std::invalid_argument);
}

TEST(Ply, AsciiWithIntensityAndDoubles) {
    const auto pts = gseg::io::readPly(writeTemp("a.ply",
        "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\n"
        "property float intensity\nproperty uchar red\nend_header\n1 2 3 0.5 255\n-4 -5 -6 7 0\n"));
    EXPECT_EQ(pts, (std::vector<float>{1, 2, 3, 0.5f, -4, -5, -6, 7}));
}

TEST(Ply, TruncatedOrGarbageFilesThrow) {
    const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\n"
                               "property float y\nproperty float z\nend_header\n";
    EXPECT_THROW(gseg::io::readPly(writeTemp("trunc.ply", header + std::string(50, '\0'))), std::runtime_error);
    EXPECT_THROW(gseg::io::readPly(writeTemp("garbage.ply", "this is not a ply\n")), std::runtime_error);
    EXPECT_THROW(gseg::io::readPly(writeTemp("noend.ply", "ply\nformat ascii 1.0\n")), std::runtime_error);
    EXPECT_THROW(gseg::io::readPly(writeTemp("empty.ply", "")), std::runtime_error);
}

// --- Hostile configuration files (issue #9 items 12 to 14) ------------------------------------------

namespace {

// loadConfig() in a child with a time limit: a hang ends as SIGALRM instead of a stuck test.
// Returns the child's exit code: 0 loaded, 1 std::runtime_error naming `path`, 2 any other error.
int loadWithin(const std::string& path, unsigned seconds) {
    return gseg::test::runInChild([&] {
               ::alarm(seconds);
               try {
                   gseg::mrpt::loadConfig(path);
               } catch (const std::runtime_error& e) {
                   return std::string(e.what()).find(path) != std::string::npos ? 1 : 3;
               } catch (...) {
                   return 2;
               }
               return 0;
           }).code;
}

}  // namespace

TEST(ConfigHostile, YamlDirectivesThatHangLibfyamlAreRefusedAtOnce) {
    // Both hang libfyaml 0.7.12 forever (found by fuzzing); the first is 16 bytes with a NUL.
    const std::string nul("%Y;ML 1.1\0" "1\n%-\xb5\na:", 16);
    for (const std::string& text : {nul, std::string("%-\xb5\na:"), std::string("%YAML 1.1\n%-\xb5\na: 1\n")}) {
        const std::string path = writeTemp("hang.yaml", text);
        EXPECT_EQ(loadWithin(path, 20), 1) << "hang or wrong error type";
    }
    EXPECT_NE(errorOf(writeTemp("dir.yaml", "%YAML 1.2\n---\ncellSizeX: 1\n")).find("directives"), std::string::npos);
}

TEST(ConfigHostile, ValidButUnboundedParametersAreRefusedByTheLoader) {
    const std::string path = writeTemp("iter.yaml", "ransacMaxIterations: 2147483647\nminGroundInlierRatio: 0\n");
    const std::string err = errorOf(path);
    EXPECT_NE(err.find("ransacMaxIterations"), std::string::npos) << err;
    EXPECT_NE(err.find("bounded time"), std::string::npos) << err;
    EXPECT_NE(errorOf(writeTemp("radius.ini", "[gseg]\ncentroidSearchRadius = 1e9\n")).find("centroidSearchRadius"),
              std::string::npos);
    // The shipped files stay within the limits.
    for (const char* f : {"kitti_hdl64.yaml", "vlp16.yaml"})
        EXPECT_NO_THROW(gseg::mrpt::loadConfig(std::string(GSEG_SOURCE_DIR) + "/config/" + f)) << f;
}

TEST(ConfigHostile, KeysBesideTheGsegMapAreAnError) {
    for (const std::string& text : {std::string("gseg:\n  heightGate: 0.4\ncellSizeX: 0\n"),
                                    std::string("cellSizeX: 0\ngseg:\n  heightGate: 0.4\n")}) {
        const std::string err = errorOf(writeTemp("beside.yaml", text));
        EXPECT_NE(err.find("beside the 'gseg:' map"), std::string::npos) << err;
    }
    // The same through an already parsed document.
    const auto doc = mrpt::containers::yaml::FromText("gseg:\n  heightGate: 0.4\ncellSizeX: 0\n");
    EXPECT_THROW(gseg::mrpt::loadConfigFromYaml(doc, "doc"), std::runtime_error);
}

TEST(ConfigHostile, ContentAfterANulByteIsNotIgnored) {
    const std::string yaml = writeTemp("nul.yaml", std::string("heightGate: 0.4\n\0cellSizeX: 0\n", 30));
    EXPECT_NE(errorOf(yaml).find("NUL byte at offset 16"), std::string::npos) << errorOf(yaml);
    const std::string ini = writeTemp("nul.ini", std::string("[gseg]\nheightGate = 0.4\n\0cellSizeX = 0\n", 38));
    EXPECT_NE(errorOf(ini).find("NUL byte"), std::string::npos) << errorOf(ini);
}

TEST(ConfigHostile, YamlBeyondFlatKeyValueLinesIsRefusedWithItsLine) {
    const struct {
        std::string text, expect;
    } cases[] = {
        {"cellSizeX: [1, 2\n", ":1: 'cellSizeX': '[1, 2' is not a single plain value"},
        {"heightGate: 0.4\nheightGate: 0.5\n", ":2: 'heightGate' given twice (also on line 1)"},
        {"a: &x 1\n", "not a single plain value"},
        {"gseg:\n  heightGate: 0.4\n    cellSizeX: 1\n", ":3: unexpected indentation"},
        {"heightGate 0.4\n", ":1: expected 'key: value'"},
        {"heightGate: '0.4\n", "unbalanced quotes"},
        {"\theightGate: 0.4\n", "tabs"},
        {"heightGate:\n", "has no value"},
        {"---\nheightGate: 0.4\n---\ncellSizeX: 1\n", "only one YAML document"},
    };
    for (const auto& c : cases) {
        const std::string err = errorOf(writeTemp("flat.yaml", c.text));
        EXPECT_NE(err.find(c.expect), std::string::npos) << c.text << " -> " << err;
    }
    // What the format does allow: comments, quotes, a document marker, a BOM, CRLF.
    const auto cfg = gseg::mrpt::loadConfig(writeTemp("ok.yaml", "\xEF\xBB\xBF---\r\n# comment\r\nheightGate: '0.4'  # m\r\n"
                                                                 "cellSizeX: \"1.25\"\r\ndistToGround: auto\r\n...\r\n"));
    EXPECT_DOUBLE_EQ(cfg.params.heightGate, 0.4);
    EXPECT_DOUBLE_EQ(cfg.params.cellSizeX, 1.25);
    EXPECT_TRUE(cfg.distToGroundAuto);
}

TEST(ConfigHostile, IniPreprocessorErrorsAreRuntimeErrorsNamingTheFileInOneLine) {
    for (const std::string& text : {std::string("[gseg]\nheightGate = $eval{1+}\n"),
                                    std::string("[gseg]\nheightGate = ${NO_SUCH_VARIABLE}\n")}) {
        const std::string path = writeTemp("eval.ini", text);
        std::string what;
        try {
            gseg::mrpt::loadConfig(path);
        } catch (const std::runtime_error& e) {  // the documented type: nothing else may escape
            what = e.what();
        }
        EXPECT_NE(what.find(path), std::string::npos) << what;
        EXPECT_EQ(what.find("==== MRPT exception"), std::string::npos) << what;
        EXPECT_EQ(what.find('\n'), std::string::npos) << what;
        EXPECT_NE(what.find("Line 2"), std::string::npos) << what;
    }
    // Evaluated expressions still work.
    EXPECT_DOUBLE_EQ(gseg::mrpt::loadConfig(writeTemp("ok.ini", "[gseg]\nheightGate = $eval{0.2*2}\n")).params.heightGate,
                     0.4);
}

TEST(ConfigHostile, IniLoopsThatWouldNeverEndAreRefused) {
    const std::string loop = writeTemp("loop.ini", "[gseg]\nheightGate = $eval{var x:=0; while(x<1e12)(x+=1); 1}\n");
    EXPECT_EQ(loadWithin(loop, 20), 1) << "hang or wrong error type";
    EXPECT_NE(errorOf(loop).find("loops are not allowed"), std::string::npos) << errorOf(loop);
    ::setenv("GSEG_TEST_SELF", "$env{GSEG_TEST_SELF}", 1);
    const std::string self = writeTemp("self.ini", "[gseg]\nheightGate = $env{GSEG_TEST_SELF}\n");
    EXPECT_EQ(loadWithin(self, 20), 1) << "hang or wrong error type";
}

// #18 point 8: INI refuses what YAML refuses. MRPT's CConfigFile keeps the last of a repeated key
// without a word; the loader reads the text again and refuses it, naming both lines.
TEST(ConfigIniYamlAgree, ARepeatedKeyIsRefusedInBothFormatsNamingTheLines) {
    const std::string yaml = errorOf(writeTemp("twice.yaml", "distToGround: 1.7\nheightGate: 0.2\ndistToGround: 1.9\n"));
    EXPECT_NE(yaml.find("twice.yaml:3: 'distToGround' given twice (also on line 1)"), std::string::npos) << yaml;
    const std::string ini = errorOf(writeTemp("twice.ini", "[gseg]\ndistToGround = 1.7\nheightGate = 0.2\ndistToGround = 1.9\n"));
    EXPECT_NE(ini.find("twice.ini:4: [gseg] 'distToGround' given twice (also on line 2)"), std::string::npos) << ini;
    // MRPT's keys ignore case, so two spellings are one key given twice; so is a key repeated in a
    // second [gseg] section (MRPT merges the two).
    EXPECT_NE(errorOf(writeTemp("case.ini", "[gseg]\nheightGate = 0.2\nHEIGHTGATE = 0.3\n")).find("given twice"), std::string::npos);
    EXPECT_NE(errorOf(writeTemp("again.ini", "[gseg]\nheightGate = 0.2\n[gseg]\nheightGate = 0.3\n")).find("given twice"),
              std::string::npos);
    // The same key in two sections is two keys.
    const auto cfg = gseg::mrpt::loadConfig(
        writeTemp("two.ini", "[gseg]\ndistToGround = auto\n[sensorHeight]\nmaxRange = 25\n[traversability]\nmaxRange = 40\n"));
    EXPECT_TRUE(cfg.distToGroundAuto);
    EXPECT_EQ(cfg.sensorHeight.maxRange, 25);
    EXPECT_EQ(cfg.traversability.maxRange, 40);
}

TEST(ConfigIniYamlAgree, UnknownKeysAndSectionsAreRefusedInBothFormats) {
    const std::string yaml = errorOf(writeTemp("unknown.yaml", "traversability:\n  resolution: 0.1\n  banana: 1\n"));
    EXPECT_NE(yaml.find("unknown.yaml:3: unknown traversability option 'banana'"), std::string::npos) << yaml;
    const std::string ini = errorOf(writeTemp("unknown.ini", "[gseg]\n[traversability]\nresolution = 0.1\nbanana = 1\n"));
    EXPECT_NE(ini.find("unknown.ini:4: [traversability]: unknown traversability option 'banana'"), std::string::npos) << ini;
    EXPECT_NE(errorOf(writeTemp("unknown2.ini", "[gseg]\nbanana = 1\n")).find("unknown parameter 'banana'"), std::string::npos);
    EXPECT_NE(errorOf(writeTemp("sensor.yaml", "sensorHeight:\n  minRang: 1\n")).find("unknown sensorHeight option 'minRang'"),
              std::string::npos);
    const std::string section = errorOf(writeTemp("section.ini", "[gseg]\n[sensorHeigth]\nminRange = 1\n"));
    EXPECT_NE(section.find("unknown section [sensorHeigth]"), std::string::npos) << section;
    const std::string map = errorOf(writeTemp("map.yaml", "sensorHeigth:\n  minRange: 1\n"));
    EXPECT_NE(map.find("map.yaml:1:"), std::string::npos) << map;
    const std::string twice = errorOf(writeTemp("map2.yaml", "traversability:\n  resolution: 0.1\ntraversability:\n  maxRange: 9\n"));
    EXPECT_NE(twice.find("map2.yaml:3: a second 'traversability:' map (also on line 1)"), std::string::npos) << twice;
}

// #32: a key gseg no longer reads (`threads`, one scan over several threads) loads in every format
// and route with one warning naming where and why, and changes nothing else; elsewhere it is unknown.
TEST(ConfigIniYamlAgree, ARetiredKeyLoadsWithOneWarningInEveryFormat) {
    const auto plain = gseg::mrpt::loadConfig(writeTemp("plain.yaml", "heightGate: 0.2\n"));
    EXPECT_TRUE(plain.warnings.empty());
    const auto yaml = gseg::mrpt::loadConfig(writeTemp("retired.yaml", "heightGate: 0.2\nthreads: 4\n"));
    ASSERT_EQ(yaml.warnings.size(), 1u);
    EXPECT_NE(yaml.warnings[0].find("retired.yaml:2: 'threads' is ignored: one scan is no longer split over threads"),
              std::string::npos) << yaml.warnings[0];
    EXPECT_NE(yaml.warnings[0].find("--threads"), std::string::npos) << "says what to use instead: " << yaml.warnings[0];
    EXPECT_EQ(gseg::mrpt::toYaml(yaml), gseg::mrpt::toYaml(plain));
    const auto nested = gseg::mrpt::loadConfig(writeTemp("nested.yaml", "gseg:\n  threads: 2\n  heightGate: 0.2\n"));
    ASSERT_EQ(nested.warnings.size(), 1u);
    EXPECT_NE(nested.warnings[0].find("nested.yaml:2: 'threads' is ignored"), std::string::npos) << nested.warnings[0];
    const auto ini = gseg::mrpt::loadConfig(writeTemp("retired.ini", "[gseg]\nheightGate = 0.2\nthreads = 8\n"));
    ASSERT_EQ(ini.warnings.size(), 1u);
    EXPECT_NE(ini.warnings[0].find("retired.ini:3: [gseg]: 'threads' is ignored"), std::string::npos) << ini.warnings[0];
    EXPECT_EQ(gseg::mrpt::toYaml(ini), gseg::mrpt::toYaml(plain));
    const auto parsed = gseg::mrpt::loadConfigFromYaml(::mrpt::containers::yaml::FromText("threads: 3\n"), "map");
    ASSERT_EQ(parsed.warnings.size(), 1u);
    EXPECT_NE(parsed.warnings[0].find("map: 'threads' is ignored"), std::string::npos) << parsed.warnings[0];
    // Ignored means not read: any value loads; in another section it is an unknown key as before.
    EXPECT_EQ(gseg::mrpt::loadConfig(writeTemp("any.yaml", "threads: many\n")).warnings.size(), 1u);
    EXPECT_NE(errorOf(writeTemp("elsewhere.yaml", "sensorHeight:\n  threads: 2\n")).find("unknown sensorHeight option 'threads'"),
              std::string::npos);
    EXPECT_EQ(std::count(gseg::Params::keys().begin(), gseg::Params::keys().end(), "threads"), 0);
}

// #17 item 5: every field of SensorHeightOptions and TraversabilityOptions from YAML and INI,
// through their key tables, validated with the key named.
TEST(ConfigOptionTables, EveryFieldOfBothOptionStructsLoadsFromYamlAndIniAlike) {
    std::string yaml = "gseg:\n  distToGround: auto\nsensorHeight:\n", ini = "[gseg]\ndistToGround = auto\n[sensorHeight]\n";
    gseg::SensorHeightOptions h;
    gseg::map::TraversabilityOptions t;
    // A valid value different from each default.
    const std::map<std::string, std::string> heightValues = {
        {"minRange", "1"},        {"maxRange", "25"},       {"columnSize", "1.5"},       {"minColumnPoints", "7"},
        {"floorThickness", "0.3"}, {"minColumns", "6"},     {"maxTiltDegrees", "12"},    {"planeTolerance", "0.15"},
        {"minLevelTiltDegrees", "2"}, {"maxLevelTiltDegrees", "9"}};
    const std::map<std::string, std::string> mapValues = {
        {"resolution", "0.1"}, {"maxRange", "40"},  {"probHit", "0.8"},  {"probMiss", "0.3"},
        {"clampMin", "0.1"},   {"clampMax", "0.95"}, {"occupancyThreshold", "0.6"}, {"clearance", "2.5"},
        {"minGroundPoints", "4"}, {"maxSlope", "15"}, {"slopeRadius", "0.8"}, {"maxStep", "0.3"}, {"maxRoughness", "0.15"},
        {"maxGroundRise", "0.5"}, {"groundRiseRadius", "1.2"}, {"obstacleClearProbability", "0.2"},
        {"minObstacleHeight", "0.25"}, {"driveTerrain", "false"}, {"terrainTolerance", "0.08"}, {"terrainRadius", "1.5"},
        {"terrainSparseRadius", "2.5"},
        {"terrainMinScans", "3"}, {"terrainPointTolerance", "0.04"}, {"terrainStandHeight", "0.4"}, {"terrainFootHeight", "0.1"},
        {"fillGaps", "false"},
        {"maxGapWidth", "1"}};
    ASSERT_EQ(heightValues.size(), gseg::SensorHeightOptions::keys().size());
    ASSERT_EQ(mapValues.size(), gseg::map::TraversabilityOptions::keys().size());
    for (const auto& key : gseg::SensorHeightOptions::keys()) {
        yaml += "  " + key + ": " + heightValues.at(key) + "\n", ini += key + " = " + heightValues.at(key) + "\n";
        h.set(key, heightValues.at(key));
        EXPECT_NE(h.get(key), gseg::SensorHeightOptions().get(key)) << key << ": pick a value other than the default";
        EXPECT_FALSE(gseg::SensorHeightOptions::describe(key).first.empty()) << key << " has no unit";
    }
    yaml += "traversability:\n", ini += "[traversability]\n";
    for (const auto& key : gseg::map::TraversabilityOptions::keys()) {
        yaml += "  " + key + ": " + mapValues.at(key) + "\n", ini += key + " = " + mapValues.at(key) + "\n";
        EXPECT_FALSE(gseg::map::TraversabilityOptions::describe(key).second.empty()) << key << " has no meaning";
        t.set(key, mapValues.at(key));
        EXPECT_NE(t.get(key), gseg::map::TraversabilityOptions().get(key)) << key << ": pick a value other than the default";
    }
    const auto a = gseg::mrpt::loadConfig(writeTemp("all.yaml", yaml)), b = gseg::mrpt::loadConfig(writeTemp("all.ini", ini));
    EXPECT_TRUE(a.distToGroundAuto && b.distToGroundAuto);
    for (const auto& [key, value] : heightValues) {
        EXPECT_DOUBLE_EQ(std::stod(a.sensorHeight.get(key)), std::stod(value)) << key;
        EXPECT_EQ(a.sensorHeight.get(key), b.sensorHeight.get(key)) << key;
    }
    for (const auto& [key, value] : mapValues) {
        if (value == "true" || value == "false") EXPECT_EQ(a.traversability.get(key), value) << key;
        else EXPECT_DOUBLE_EQ(std::stod(a.traversability.get(key)), std::stod(value)) << key;
        EXPECT_EQ(a.traversability.get(key), b.traversability.get(key)) << key;
    }
    // toYaml writes both maps, and reads back to the same configuration.
    const auto c = gseg::mrpt::loadConfigFromText(gseg::mrpt::toYaml(a), gseg::mrpt::ConfigFormat::Yaml, "round trip");
    EXPECT_EQ(gseg::mrpt::toYaml(c), gseg::mrpt::toYaml(a));
    // The same maps through an already parsed document.
    const auto doc = mrpt::containers::yaml::FromText(
        "gseg:\n  heightGate: 0.2\nsensorHeight:\n  maxRange: 25\ntraversability:\n  resolution: 0.1\n");
    const auto d = gseg::mrpt::loadConfigFromYaml(doc, "doc");
    EXPECT_EQ(d.params.heightGate, 0.2);
    EXPECT_EQ(d.sensorHeight.maxRange, 25);
    EXPECT_EQ(d.traversability.resolution, 0.1);
    EXPECT_THROW(gseg::mrpt::loadConfigFromYaml(mrpt::containers::yaml::FromText("traversability:\n  banana: 1\n"), "doc"),
                 std::runtime_error);
    // Invalid values are refused with the file, line and key.
    EXPECT_NE(errorOf(writeTemp("bad.yaml", "traversability:\n  resolution: 0\n")).find("resolution"), std::string::npos);
    EXPECT_NE(errorOf(writeTemp("bad2.yaml", "traversability:\n  probHit: 1.5\n")).find("probHit"), std::string::npos);
    EXPECT_NE(errorOf(writeTemp("bad3.yaml", "sensorHeight:\n  maxRange: 1\n")).find("sensorHeight option 'maxRange'"),
              std::string::npos);
    const std::string word = errorOf(writeTemp("bad4.ini", "[gseg]\n[sensorHeight]\nminColumns = many\n"));
    EXPECT_NE(word.find("bad4.ini:3: [sensorHeight]: sensorHeight option 'minColumns': cannot read 'many' as a whole number"),
              std::string::npos) << word;
}
