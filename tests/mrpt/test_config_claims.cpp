// One source of truth for configurations: each shipped config file says in one line how it
// differs from the defaults ("Differs from ... in: key (value), ..." or "in: nothing"), and this
// test holds every file to that line: the keys named have the value named, every other key is the
// default. The INI for observations2map is read the way observations2map reads it.
#include <gseg/map/octomap_plugin.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/params.hpp>
#include <support/paths.hpp>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/maps/TMetricMapInitializer.h>

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <regex>
#include <sstream>

namespace {

const std::string kConfig = std::string(GSEG_SOURCE_DIR) + "/config/";

/// The keys and values that the line "Differs from <what> in: ..." names (empty for "nothing").
/// Fails the test if there is not exactly one such line.
std::map<std::string, std::string> claimedDifferences(const std::string& text, const std::string& what) {
    const std::regex line("Differs from " + what + " in: ([^\n]*)");
    std::map<std::string, std::string> out;
    std::size_t lines = 0;
    for (auto it = std::sregex_iterator(text.begin(), text.end(), line); it != std::sregex_iterator(); ++it, ++lines) {
        const std::string list = (*it)[1];
        if (list.rfind("nothing", 0) == 0) continue;
        const std::regex item("([A-Za-z0-9]+) \\(([^)]*)\\)");
        for (auto k = std::sregex_iterator(list.begin(), list.end(), item); k != std::sregex_iterator(); ++k)
            out[(*k)[1]] = (*k)[2];
    }
    EXPECT_EQ(lines, 1u) << "one line 'Differs from " << what << " in: ...' expected";
    return out;
}

/// Holds the YAML file `name` to its claim line.
void expectYamlIsWhatItSays(const std::string& name) {
    SCOPED_TRACE(name);
    const auto claims = claimedDifferences(gseg::test::readText(kConfig + name), "the library defaults");
    const auto cfg = gseg::mrpt::loadConfig(kConfig + name);
    const gseg::Params defaults;
    for (const auto& key : gseg::Params::keys()) {
        const auto claim = claims.find(key);
        if (key == "distToGround" && cfg.distToGroundAuto) {
            EXPECT_TRUE(claim != claims.end() && claim->second == "auto") << "distToGround: auto is not claimed";
            continue;
        }
        if (claim == claims.end()) {
            EXPECT_EQ(cfg.params.get(key), defaults.get(key)) << key << " differs from the default but the file does not say so";
        } else {
            EXPECT_NE(cfg.params.get(key), defaults.get(key)) << key << " is claimed to differ but is the default";
            EXPECT_DOUBLE_EQ(std::stod(cfg.params.get(key)), std::stod(claim->second)) << key;
        }
    }
    for (const auto& [key, value] : claims)
        EXPECT_NE(std::find(gseg::Params::keys().begin(), gseg::Params::keys().end(), key), gseg::Params::keys().end())
            << "claimed key " << key << " is not a gseg::Params key";
}

}  // namespace

TEST(ConfigClaims, EachYamlFileDiffersFromTheDefaultsExactlyWhereItSays) {
    for (const char* f : {"kitti_hdl64.yaml", "auto_height.yaml", "vlp16.yaml"}) expectYamlIsWhatItSays(f);
}

TEST(ConfigClaims, TheObservations2mapIniIsRawlogOctomapWithKittiHdl64AsItSays) {
    const std::string path = kConfig + "octomap_maps.ini", text = gseg::test::readText(path);
    // Read as observations2map reads it: the [MappingApplication] maps.
    mrpt::config::CConfigFile ini(path);
    mrpt::maps::TSetOfMetricMapInitializers maps;
    maps.loadFromConfigFile(ini, "MappingApplication");
    ASSERT_EQ(maps.size(), 1u);
    const auto* def = dynamic_cast<const gseg_maps::CTraversabilityOctoMap::TMapDefinition*>(maps.begin()->get());
    ASSERT_NE(def, nullptr) << "the INI does not ask for gseg's map";
    // creationOpts: rawlog-octomap's defaults (TraversabilityOptions), as the file says.
    EXPECT_TRUE(claimedDifferences(text, "rawlog-octomap's defaults").empty());
    const gseg::map::TraversabilityOptions o, d = def->config.traversability;
    EXPECT_EQ(d.resolution, o.resolution);
    EXPECT_EQ(d.maxRange, o.maxRange);
    EXPECT_EQ(d.clearance, o.clearance);
    EXPECT_EQ(d.probHit, o.probHit);
    EXPECT_EQ(d.probMiss, o.probMiss);
    EXPECT_EQ(d.clampMin, o.clampMin);
    EXPECT_EQ(d.clampMax, o.clampMax);
    EXPECT_EQ(d.occupancyThreshold, o.occupancyThreshold);
    // The gseg section: the library defaults, i.e. config/kitti_hdl64.yaml (what the README's
    // `rawlog-octomap -c config/kitti_hdl64.yaml` uses).
    EXPECT_TRUE(claimedDifferences(text, "the library defaults").empty());
    const auto kitti = gseg::mrpt::loadConfig(kConfig + "kitti_hdl64.yaml");
    for (const auto& key : gseg::Params::keys()) {
        EXPECT_EQ(def->config.params.get(key), gseg::Params().get(key)) << key;
        EXPECT_EQ(def->config.params.get(key), kitti.params.get(key)) << key;
    }
}

// #17: the plugin's map definition keeps the whole loaded configuration (distToGround = auto and
// the sensorHeight options included), read by the tools' loader: repeated and unknown keys are
// refused as in a YAML file.
TEST(ConfigClaims, ThePluginDefinitionKeepsTheWholeConfigurationAndRefusesWhatYamlRefuses) {
    const std::string head = "[MappingApplication]\ngsegTraversabilityMap_count = 1\n";
    const std::string prefix = "[MappingApplication_gsegTraversabilityMap_00_";
    // As observations2map reads it: a CConfigFile (whose file the loader reads again for repeated keys).
    const auto load = [](const std::string& text) {
        const std::string path = std::string(GSEG_BINARY_DIR) + "/tests/plugin_definition.ini";
        std::ofstream(path) << text;
        mrpt::config::CConfigFile ini(path);
        mrpt::maps::TSetOfMetricMapInitializers maps;
        maps.loadFromConfigFile(ini, "MappingApplication");
        const auto* def = dynamic_cast<const gseg_maps::CTraversabilityOctoMap::TMapDefinition*>(maps.begin()->get());
        if (!def) throw std::logic_error("no gseg map definition");
        return def->config;
    };
    const auto cfg = load(head + prefix + "gseg]\ndistToGround = auto\nheightGate = 0.2\n" + prefix +
                          "sensorHeight]\nmaxRange = 25\nminColumns = 6\n" + prefix + "creationOpts]\nresolution = 0.1\n");
    EXPECT_TRUE(cfg.distToGroundAuto);
    EXPECT_EQ(cfg.params.heightGate, 0.2);
    EXPECT_EQ(cfg.sensorHeight.maxRange, 25);
    EXPECT_EQ(cfg.sensorHeight.minColumns, 6);
    EXPECT_EQ(cfg.traversability.resolution, 0.1);
    const auto errorOf = [&](const std::string& text) -> std::string {
        try {
            load(text);
        } catch (const std::exception& e) {
            return e.what();
        }
        return "";
    };
    EXPECT_NE(errorOf(head + prefix + "creationOpts]\nresolution = 0.1\nresolution = 0.3\n").find("'resolution' given twice"),
              std::string::npos);
    EXPECT_NE(errorOf(head + prefix + "creationOpts]\nbanana = 1\n").find("unknown traversability option 'banana'"),
              std::string::npos);
    EXPECT_NE(errorOf(head + prefix + "sensorHeight]\nbanana = 1\n").find("unknown sensorHeight option 'banana'"),
              std::string::npos);
    // #32: the retired key `threads` loads, and the plugin says once on stderr that it is ignored.
    testing::internal::CaptureStderr();
    const auto old = load(head + prefix + "gseg]\nheightGate = 0.2\nthreads = 4\n");
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(old.params.heightGate, 0.2);
    ASSERT_EQ(old.warnings.size(), 1u);
    const std::string said = "gseg map plugin: warning: " + old.warnings[0] + "\n";
    EXPECT_NE(old.warnings[0].find(":5: [MappingApplication_gsegTraversabilityMap_00_gseg]: 'threads' is ignored"),
              std::string::npos) << old.warnings[0];
    EXPECT_NE(err.find(said), std::string::npos) << err;
    EXPECT_EQ(err.find(said, err.find(said) + 1), std::string::npos) << "said once: " << err;
}
