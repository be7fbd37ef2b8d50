// gseg-observations2map (the stock observations2map with the map plugin; #34): its own checks of
// the configuration and of the outputs, MRPT's messages, and signals, with a stand-in
// observations2map on PATH (no mrpt-apps needed). The route through the real observations2map is
// test_map_routes' (MapRoutes).
#include <support/child.hpp>
#include <support/labelled_drive.hpp>
#include <support/map_files.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <sys/stat.h>
#include <utility>
#include <vector>

namespace fs = std::filesystem;

namespace {

using gseg::test::kMapFiles;
using gseg::test::q;
using gseg::test::writeText;

struct Wrapper {
    fs::path dir, ini, simplemap, stubs;
    std::string prefix;
};

/// A folder with a valid INI, a "simplemap" (any regular file: the stand-in reads nothing) and a
/// folder `stubs` for a stand-in observations2map (`body`: its shell script after #!/bin/sh).
Wrapper makeWrapper(const std::string& name, const std::string& body = "") {
    Wrapper w;
    w.dir = gseg::test::freshDir("tool_observations2map", name);
    w.ini = w.dir / "maps.ini";
    writeText(w.ini, "[MappingApplication]\ngsegTraversabilityMap_count = 1\n"
                     "[MappingApplication_gsegTraversabilityMap_00_creationOpts]\nresolution = 0.2\n");
    w.simplemap = w.dir / "in.simplemap";
    writeText(w.simplemap, "not read by the stand-in");
    w.stubs = w.dir / "stubs";
    fs::create_directories(w.stubs);
    if (!body.empty()) {
        writeText(w.stubs / "observations2map", "#!/bin/sh\n" + body);
        fs::permissions(w.stubs / "observations2map", fs::perms::owner_all);
    }
    w.prefix = (w.dir / "m").string();
    return w;
}

gseg::test::CommandResult runWrapper(const Wrapper& w, const std::string& args) {
    return gseg::test::runCommand("PATH=" + q(w.stubs) + ":$PATH timeout 60 " + gseg::test::tool("gseg-observations2map") + " " +
                                  args + " 2>&1");
}

/// The files of map 00 of `prefix` (kMapFiles).
std::vector<std::string> mapFiles(const std::string& prefix) {
    std::vector<std::string> out;
    for (const std::string& f : kMapFiles) out.push_back(prefix + "_gseg_maps__CTraversabilityOctoMap_00" + f);
    return out;
}

bool sanitizedPlugin() {
    return gseg::test::runCommand("ldd " + q(fs::path(GSEG_BINARY_DIR) / "lib/libgseg_map.so") + " | grep -q libasan").status == 0;
}

}  // namespace

TEST(Observations2mapTool, AMisspeltSectionAWrongIndexOtherMapsAndAnAbsurdCountAreRefused) {
    const Wrapper w = makeWrapper("config");
    const std::string base = "[MappingApplication]\ngsegTraversabilityMap_count = 1\n";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {base + "[MappingApplication_gsegTraversabilityMap_00_creationOpt]\nresolution = 0.1\n",
         "bad.ini:3: [MappingApplication_gsegTraversabilityMap_00_creationOpt]: unknown section"},
        {base + "[MappingApplication_gsegTraversabilityMap_01_creationOpts]\nresolution = 0.1\n",
         "bad.ini:3: [MappingApplication_gsegTraversabilityMap_01_creationOpts]: unknown section"},
        {"[MappingApplication]\ngsegTraversabilityMap_count = 100000\n", "gsegTraversabilityMap_count = 100000: at most 16"},
        {base + "occupancyGrid_count = 1\n", "occupancyGrid_count = 1: this wrapper builds gseg's maps only"},
    };
    for (const auto& [ini, words] : cases) {
        writeText(w.dir / "bad.ini", ini);
        const auto r = runWrapper(w, "-c " + q(w.dir / "bad.ini") + " -i " + q(w.simplemap) + " -o " + q(w.prefix));
        EXPECT_EQ(r.status, 2) << ini << r.output;
        EXPECT_NE(r.output.find(words), std::string::npos) << r.output;
        EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    }
}

TEST(Observations2mapTool, EveryOneOfTheMapFilesIsCheckedAndListed) {
    if (sanitizedPlugin()) GTEST_SKIP() << "a sanitized plugin cannot be preloaded into the stand-in";
    // The stand-in writes the 17 files of map 00 as the plugin would.
    std::string writes;
    for (const std::string& f : kMapFiles) writes += "echo new > \"$3_gseg_maps__CTraversabilityOctoMap_00" + f + "\"\n";
    const Wrapper w = makeWrapper("sixteen", writes);
    const std::vector<std::string> files = mapFiles(w.prefix);
    // An existing costmap (not one of the 6 voxel files checked before): refused without -w, kept.
    writeText(files[7], "mine");
    auto r = runWrapper(w, q(w.ini) + " " + q(w.simplemap) + " " + q(w.prefix));
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("_00_costmap.yaml exists: give -w"), std::string::npos) << r.output;
    EXPECT_EQ(gseg::test::readText(files[7]), "mine");
    EXPECT_FALSE(fs::exists(files[0]));
    r = runWrapper(w, "-w " + q(w.ini) + " " + q(w.simplemap) + " " + q(w.prefix));
    EXPECT_EQ(r.status, 0) << r.output;
    std::string listed;
    for (const std::string& f : kMapFiles) listed += (listed.empty() ? "" : ",") + f.substr(1);
    EXPECT_NE(r.output.find("wrote " + w.prefix + "_gseg_maps__CTraversabilityOctoMap_00_{" + listed + "}"), std::string::npos)
        << r.output;
    const auto help = gseg::test::runCommand(gseg::test::tool("gseg-observations2map") + " --help");
    for (const std::string& f : kMapFiles) EXPECT_NE(help.output.find(f.substr(1)), std::string::npos) << f;
    // One file missing afterwards (the last): nothing said written.
    std::string fifteen;
    for (std::size_t k = 0; k + 1 < kMapFiles.size(); ++k)
        fifteen += "echo new > \"$3_gseg_maps__CTraversabilityOctoMap_00" + kMapFiles[k] + "\"\n";
    const Wrapper v = makeWrapper("fifteen", fifteen);
    r = runWrapper(v, q(v.ini) + " " + q(v.simplemap) + " " + q(v.prefix));
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("observations2map wrote no " + v.prefix + "_gseg_maps__CTraversabilityOctoMap_00" + kMapFiles.back()),
              std::string::npos) << r.output;
}

TEST(Observations2mapTool, MrptsOwnMessageIsShownNeverItsKeyPrompt) {
    if (sanitizedPlugin()) GTEST_SKIP() << "a sanitized plugin cannot be preloaded into the stand-in";
    const Wrapper w = makeWrapper("prompt", "echo 'Loading simplemap...'\necho 'Error: the file is a rawlog, not a CSimpleMap'\n"
                                            "echo 'Press any key to continue...'\nexit 255\n");
    const auto r = runWrapper(w, q(w.ini) + " " + q(w.simplemap) + " " + q(w.prefix));
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("gseg-observations2map: Error: the file is a rawlog, not a CSimpleMap"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("Press any key"), std::string::npos) << r.output;
    // What MRPT 2.5.8's observations2map prints given a rawlog (seen with the real one): the
    // exception's message with its further lines, not its closing "Program finished" line.
    const Wrapper real = makeWrapper("prompt_real",
                                     "echo ' observations2map - Part of the MRPT'\nprintf 'Loading simplemap...==== MRPT exception ====\\n'\n"
                                     "echo 'Message:  Stored class does not match with existing object!!:'\n"
                                     "echo ' Stored: mrpt::obs::CObservationOdometry'\necho ' Expected: mrpt::maps::CSimpleMap'\n"
                                     "echo 'Location: ./libs/serialization/src/CArchive.cpp:508: [void ReadObject(CSerializable*)'\n"
                                     "echo 'Call stack backtrace:'\necho '[0 ]     0x7fa7452b1ae3 '\necho\n"
                                     "echo 'Program finished for an exception!!'\necho 'Press any key to continue...'\nexit 255\n");
    const auto m = runWrapper(real, q(real.ini) + " " + q(real.simplemap) + " " + q(real.prefix));
    EXPECT_EQ(m.status, 1) << m.output;
    EXPECT_NE(m.output.find("gseg-observations2map: Stored class does not match with existing object!!: Stored: "
                            "mrpt::obs::CObservationOdometry Expected: mrpt::maps::CSimpleMap (configuration "),
              std::string::npos)
        << m.output;
    EXPECT_EQ(m.output.find("Program finished"), std::string::npos) << m.output;
}

TEST(Observations2mapTool, SigtermAndSigintStopObservations2mapAndRemoveItsTemporaries) {
    if (sanitizedPlugin()) GTEST_SKIP() << "a sanitized plugin cannot be preloaded into the stand-in";
    for (const std::string sig : {"TERM", "INT"}) {
        // The stand-in makes a temporary as the plugin's writer names them, says so through a FIFO
        // (no sleeps), then waits for ever.
        const Wrapper w = makeWrapper("signal_" + sig,
                                      "echo $$ > \"$(dirname \"$3\")/child.pid\"\n"
                                      "touch \"$(dirname \"$3\")/.$(basename \"$3\")_gseg_maps__CTraversabilityOctoMap_00_ground.bt.gseg-host-$$-0.tmp\"\n"
                                      "echo ready > \"$(dirname \"$3\")/ready\"\nexec tail -f /dev/null\n");
        ASSERT_EQ(::mkfifo((w.dir / "ready").c_str(), 0600), 0);
        // env --default-signal: a background job of a shell without job control starts with SIGINT
        // ignored; a Ctrl-C reaches a wrapper in the foreground, so it must reach this one.
        const auto r = gseg::test::runCommand(
            "PATH=" + q(w.stubs) + ":$PATH env --default-signal=INT " + gseg::test::tool("gseg-observations2map") + " " + q(w.ini) + " " + q(w.simplemap) + " " +
            q(w.prefix) + " 2> " + q(w.dir / "err.txt") + " & w=$!; read x < " + q(w.dir / "ready") + "; kill -" + sig +
            " $w; wait $w; echo rc=$?; kill -0 $(cat " + q(w.dir / "child.pid") + ") 2>/dev/null && echo child alive; true");
        EXPECT_NE(r.output.find(sig == "TERM" ? "rc=143" : "rc=130"), std::string::npos) << sig << ": " << r.output;
        EXPECT_EQ(r.output.find("child alive"), std::string::npos) << sig << ": observations2map left running";
        EXPECT_NE(gseg::test::readText((w.dir / "err.txt").string()).find("interrupted (SIG" + sig + "): observations2map stopped"),
                  std::string::npos) << gseg::test::readText((w.dir / "err.txt").string());
        EXPECT_EQ(gseg::test::entriesContaining(w.dir.string(), ".tmp") + gseg::test::entriesContaining(w.dir.string(), ".gseg-o2m"), "")
            << sig;
    }
}
