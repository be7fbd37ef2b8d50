// `gseg eval-map` end to end: a hand-placed drive and map, the printed figures and the report, bad
// input in one line with the old report kept, usage. The scorer itself and the tool against
// score_map.py on the shared drives: tests/eval/test_map_score.cpp.
#include <gseg/io/ros_map.hpp>

#include <support/child.hpp>
#include <support/output_files.hpp>
#include <support/labelled_drive.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using gseg::io::RosMap;

using gseg::test::writeBytes;
using gseg::test::writeText;

gseg::test::CommandResult evalMap(const std::string& args) {
    return gseg::test::runCommand("'" + gseg::test::tool("gseg") + "' eval-map " + args + " 2>&1");
}

/// The rows drive with a map: cells 0-4 of the traversable row free, the obstacle row occupied.
using ToolCase = gseg::test::RowsDriveCase;
ToolCase toolCase(const std::string& name) { return gseg::test::rowsDriveCase("eval_map_tool", name); }

TEST(EvalMapTool, PrintsTheMapBesideTheBaselineAndWritesTheReport) {
    const ToolCase c = toolCase("tool_report");
    const auto r = evalMap("'" + c.drive.string() + "' '" + c.map.string() + "' --report '" + (c.dir / "out/r").string() + "'");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("traversable recall                  50.00       100.00"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("obstacle recall                    100.00       100.00"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("cells scored                           20           20"), std::string::npos) << r.output;
    const std::string csv = gseg::test::readText((c.dir / "out/r_map_score.csv").string());
    EXPECT_NE(csv.find("\nmap,100.0000,50.0000,66.6667,100.0000,0.0000,0.0000,20,15,5,5,0,10,0,0,0,,,\n"), std::string::npos) << csv;
    EXPECT_NE(csv.find("\nheight_band,100.0000,100.0000,100.0000,100.0000,0.0000,0.0000,20,20,"), std::string::npos) << csv;
    const std::string png = gseg::test::readText((c.dir / "out/r_map_cells.png").string());
    ASSERT_GT(png.size(), 8u);
    EXPECT_EQ(png.substr(1, 3), "PNG");
    // The same inputs by name, quietly: nothing printed.
    const auto q = evalMap("-i '" + c.drive.string() + "' --map '" + c.map.string() + "' -q");
    EXPECT_EQ(q.status, 0) << q.output;
    EXPECT_EQ(q.output, "");
}

TEST(EvalMapTool, BadInputIsOneLineNamingTheFileAndTheReportIsKept) {
    const ToolCase c = toolCase("tool_bad");
    const std::string report = (c.dir / "r").string();
    ASSERT_EQ(evalMap("'" + c.drive.string() + "' '" + c.map.string() + "' -q --report '" + report + "'").status, 0);
    const std::string before = gseg::test::readText(report + "_map_score.csv");
    ASSERT_FALSE(before.empty());
    // An existing report without -w: bad usage, before any work.
    const auto again = evalMap("'" + c.drive.string() + "' '" + c.map.string() + "' --report '" + report + "'");
    EXPECT_EQ(again.status, 2) << again.output;
    // An unreadable map, a label file that does not match its scan: exit 1, the old report kept.
    writeText(c.dir / "broken.yaml", "image: broken.pgm\nresolution: 0.2\n");
    const auto map = evalMap("'" + c.drive.string() + "' '" + (c.dir / "broken.yaml").string() + "' -w --report '" + report + "'");
    EXPECT_EQ(map.status, 1) << map.output;
    EXPECT_NE(map.output.find("gseg eval-map: " + (c.dir / "broken.yaml").string()), std::string::npos) << map.output;
    EXPECT_EQ(std::count(map.output.begin(), map.output.end(), '\n'), 1) << map.output;
    const std::uint32_t one = 40;
    writeBytes(c.drive / "labels" / "000000.label", &one, 4);
    const auto labels = evalMap("'" + c.drive.string() + "' '" + c.map.string() + "' -w -q --report '" + report + "'");
    EXPECT_EQ(labels.status, 1) << labels.output;
    EXPECT_NE(labels.output.find("000000.label: 1 labels for"), std::string::npos) << labels.output;
    EXPECT_EQ(gseg::test::readText(report + "_map_score.csv"), before);
    EXPECT_EQ(gseg::test::entriesContaining(c.dir.string(), ".tmp"), "");
    // Usage errors; --help and --version.
    EXPECT_EQ(evalMap("'" + c.drive.string() + "'").status, 2);
    const auto help = evalMap("--help");
    EXPECT_EQ(help.status, 0);
    EXPECT_NE(help.output.find("--elevation"), std::string::npos) << help.output;
    EXPECT_EQ(evalMap("--version").status, 0);
    EXPECT_EQ(evalMap("'" + c.drive.string() + "' '" + c.map.string() + "' --clearance 0.2").status, 2);
}

}  // namespace
