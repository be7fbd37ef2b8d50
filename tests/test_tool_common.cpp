// What every tool shares (#11 item 4): the progress reporter (gseg/progress.hpp), the output
// checks (gseg::io::checkOutputs) and, run on every tool, the options of apps/common/cli.hpp:
// --version, --help, --quiet, -w/--overwrite, and an unwritable output refused before any work.
#include <gseg/io/atomic_file.hpp>
#include <gseg/progress.hpp>
#include <gseg/version.hpp>
#include <support/child.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using gseg::test::runCommand;

namespace {

/// Progress lines written to memory with a clock the test moves.
struct Captured {
    char* buf = nullptr;
    std::size_t size = 0;
    std::FILE* f = open_memstream(&buf, &size);
    double now = 0;
    ~Captured() {
        if (f) std::fclose(f);
        std::free(buf);
    }
    std::string text() {
        std::fflush(f);
        return std::string(buf, size);
    }
};

TEST(Progress, PlainLinesAtASteadyRateWhenNotATerminal) {
    Captured out;
    gseg::Progress p(out.f, "tool", "scans", 0, 10.0, [&] { return out.now; });
    for (int k = 1; k <= 40; ++k) {
        out.now = k;  // one scan per second, a quarter of the input every 10 scans
        p.update(std::size_t(k), k / 40.0);
    }
    p.finish(40);
    const std::string t = out.text();
    EXPECT_EQ(t,
              "tool: 1 scans, 1.0 scans/s, 2 %, 39 s left\n"
              "tool: 11 scans, 1.0 scans/s, 28 %, 29 s left\n"
              "tool: 21 scans, 1.0 scans/s, 52 %, 19 s left\n"
              "tool: 31 scans, 1.0 scans/s, 78 %, 9 s left\n"
              "tool: 40 scans, 1.0 scans/s, 40 s in all\n");
}

TEST(Progress, SteadyRateWhateverTheItemRate) {
    // rawlog-gseg printed every 100th scan off a terminal: minutes apart on a slow input, many
    // lines a second on a fast one. Now one line per interval, fast or slow items alike.
    for (const double secondsPerItem : {0.01, 0.5, 7.0}) {
        Captured out;
        gseg::Progress p(out.f, "tool", "frames", 0, 10.0, [&] { return out.now; });
        const int items = int(std::lround(120.0 / secondsPerItem));  // two minutes of work
        for (int k = 1; k <= items; ++k) {
            out.now = k * secondsPerItem;
            p.update(std::size_t(k), -1, k % 3 ? "" : "1 skipped");
        }
        const std::string t = out.text();
        const auto lines = std::count(t.begin(), t.end(), '\n');
        EXPECT_GE(lines, 9) << secondsPerItem << " s per item:\n" << t;  // the first line + one per 10 s or so
        EXPECT_LE(lines, 13) << secondsPerItem << " s per item:\n" << t;
    }
}

TEST(Progress, SkippedItemsAreSaidApartFromTheItemsDone) {
    Captured out;
    gseg::Progress p(out.f, "gseg eval", "frames", 0, 10.0, [&] { return out.now; });
    out.now = 2;
    p.update(3, 0.5, "1 skipped");  // 3 frames scored, 1 skipped, 4 of 8 handled
    p.finish(6, "2 skipped");
    EXPECT_EQ(out.text(),
              "gseg eval: 3 frames, 1.5 frames/s, 50 %, 2 s left (1 skipped)\n"
              "gseg eval: 6 frames, 3.0 frames/s (2 skipped), 2 s in all\n");
}

TEST(Progress, OneLiveLineOnATerminal) {
    Captured out;
    gseg::Progress p(out.f, "tool", "scans", 1, 10.0, [&] { return out.now; });
    for (int k = 1; k <= 10; ++k) {
        out.now = 0.1 * k;
        p.update(std::size_t(k), -1);  // unknown fraction: no time left
    }
    p.message("tool: skipped scan 3");
    p.finish(10);
    const std::string t = out.text();
    EXPECT_EQ(std::count(t.begin(), t.end(), '\n'), 2) << t;
    EXPECT_EQ(t.find("left"), std::string::npos) << t;
    EXPECT_NE(t.find("\rtool: 1 scans, 10.0 scans/s\033[K"), std::string::npos) << t;
    EXPECT_EQ(t.find("\rtool: 2 scans"), std::string::npos) << "redrawn at most every 0.2 s: " << t;
    EXPECT_NE(t.find("\rtool: skipped scan 3\033[K\n"), std::string::npos) << t;
    EXPECT_NE(t.find("\rtool: 10 scans, 10.0 scans/s, 1 s in all\033[K\n"), std::string::npos) << t;
}

TEST(Progress, WorkerThreadsReportWholeLines) {
    // gseg eval's workers report directly: lines never interleave.
    Captured out;
    double clock = 0;
    std::mutex clockMutex;
    gseg::Progress p(out.f, "tool", "frames", 0, 0.0, [&] {
        std::lock_guard<std::mutex> lock(clockMutex);
        return clock += 1;
    });
    std::vector<std::thread> pool;
    for (int t = 0; t < 4; ++t)
        pool.emplace_back([&, t] {
            for (int k = 0; k < 200; ++k) {
                p.update(std::size_t(k), 0.5, "worker " + std::to_string(t));
                if (k % 50 == 0) p.message("tool: a message from worker " + std::to_string(t));
            }
        });
    for (auto& th : pool) th.join();
    std::istringstream lines(out.text());
    int n = 0;
    for (std::string line; std::getline(lines, line); ++n)
        ASSERT_TRUE(line.rfind("tool: ", 0) == 0 && line.find("tool: ", 1) == std::string::npos) << line;
    EXPECT_EQ(n, 4 * 200 + 4 * 4);
}

TEST(Progress, NoOutputPrintsNothing) {  // --quiet
    gseg::Progress p(nullptr, "tool", "scans");
    p.update(1, 0.5);
    p.message("nothing");
    p.finish(1);
    SUCCEED();
}

TEST(Progress, DurationsReadLikeClocks) {
    EXPECT_EQ(gseg::formatDuration(0), "0 s");
    EXPECT_EQ(gseg::formatDuration(59.4), "59 s");
    EXPECT_EQ(gseg::formatDuration(61), "1 min 01 s");
    EXPECT_EQ(gseg::formatDuration(3725), "1 h 02 min");
    EXPECT_EQ(gseg::formatDuration(-5), "0 s");
}

/// The message of checkOutputs() on `outputs`, "" if it accepts them.
std::string refusal(const std::vector<gseg::io::NamedPath>& inputs, const std::vector<gseg::io::NamedPath>& outputs,
                    gseg::io::OutputRules rules) {
    try {
        gseg::io::checkOutputs(inputs, outputs, rules);
        return "";
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
}

TEST(CheckOutputs, ExistingFilesNeedOverwriteAndFoldersMustTakeAFile) {
    const fs::path dir = gseg::test::freshDir("tool_common", "check_outputs");
    const std::string old = (dir / "old.csv").string(), in = (dir / "in.bin").string();
    std::ofstream(old) << "previous run";
    std::ofstream(in) << "input";
    const struct {
        std::string output;
        gseg::io::OutputRules rules;
        std::string expected;  ///< part of the message, "" to accept
    } cases[] = {
        {(dir / "new.csv").string(), {}, ""},
        {old, {}, "-o " + old + " exists: give -w (--overwrite) to replace it"},
        {old, {true, false}, ""},
        {in, {true, false}, "refusing to overwrite an input"},  // not even with -w
        {dir.string(), {true, false}, "is a folder, not a file"},
        {(dir / "missing/x.csv").string(), {}, "the folder " + (dir / "missing").string() + " does not exist"},
        {(dir / "missing/deeper/x.csv").string(), {false, true}, ""},  // made by the tool
        {"/proc/gseg_test.csv", {}, "cannot write in the folder /proc ("},  // even as root
        {"/proc/missing/x.csv", {false, true}, "cannot write in the folder /proc ("},
        {(dir / "old.csv/x").string(), {false, true}, "is not a folder"},
    };
    for (const auto& c : cases) {
        const std::string why = refusal({{"-i", in}}, {{"-o", c.output}}, c.rules);
        if (c.expected.empty()) EXPECT_EQ(why, "") << c.output;
        else EXPECT_NE(why.find(c.expected), std::string::npos) << c.output << ": " << why;
    }
    EXPECT_FALSE(fs::exists(dir / "missing")) << "the check makes no folder";
    EXPECT_EQ(gseg::test::readText(old), "previous run");
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), "probe"), "") << "no probe file left";
}

TEST(CheckOutputs, ThousandsOfFilesAreCheckedInLinearTime) {
    // gseg eval on all of SemanticKITTI writes a picture and a prediction per frame (2 x 23201).
    const fs::path dir = gseg::test::freshDir("tool_common", "many_outputs");
    std::vector<gseg::io::NamedPath> inputs, outputs;
    for (int i = 0; i < 20000; ++i) {
        inputs.push_back({"scan", (dir / ("in" + std::to_string(i % 10) + ".bin")).string()});
        outputs.push_back({"--labels-out-dir", (dir / ("f" + std::to_string(i) + ".pred")).string()});
    }
    for (int i = 0; i < 10; ++i) std::ofstream(dir / ("in" + std::to_string(i) + ".bin")) << "scan";
    const auto start = std::chrono::steady_clock::now();
    EXPECT_EQ(refusal(inputs, outputs, {false, true}), "");
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
    outputs.push_back(outputs[123]);
    EXPECT_NE(refusal(inputs, outputs, {}).find("name the same file " + outputs[123].path), std::string::npos);
}

// ---- Every tool ----

/// A small flat scene as a KITTI scan with SemanticKITTI labels (road): enough for every tool.
struct Fixture {
    fs::path dir, bin, label, sequence, tum;
    Fixture() {
        dir = gseg::test::freshDir("tool_common", "fixture_" + std::to_string(::getpid()));  // tests run in parallel
        sequence = dir / "seq";
        fs::create_directories(sequence / "velodyne");
        bin = sequence / "velodyne" / "000000.bin";
        label = dir / "000000.label";
        std::vector<float> xyzi;
        for (int i = -40; i < 40; ++i)
            for (int j = -40; j < 40; ++j)
                if (std::abs(i) > 2 || std::abs(j) > 2) xyzi.insert(xyzi.end(), {0.5f * float(i), 0.5f * float(j), -1.73f, 0.f});
        std::ofstream(bin, std::ios::binary).write(reinterpret_cast<const char*>(xyzi.data()), std::streamsize(xyzi.size() * 4));
        const std::vector<std::uint32_t> labels(xyzi.size() / 4, 40);  // road
        std::ofstream(label, std::ios::binary)
            .write(reinterpret_cast<const char*>(labels.data()), std::streamsize(labels.size() * 4));
        tum = dir / "stationary.tum";
        std::ofstream(tum) << "0 0 0 0 0 0 0 1\n";
    }
};

const Fixture& fixture() {
    static const Fixture f;
    return f;
}

const std::string kVlp16 = "/usr/share/mrpt/datasets/test_velodyne_VLP16.rawlog";

/// A tool with one run that writes `output` (`args` contains OUT where it goes).
struct ToolCase {
    std::string command;  ///< executable and sub-command
    std::string args;     ///< a successful run; OUT stands for the output
    std::string output;   ///< the file to look at, OUT-relative ("" for a tool writing no file)
};

std::vector<ToolCase> toolCases() {
    const Fixture& f = fixture();
    const std::string cfg = std::string(GSEG_SOURCE_DIR) + "/config/";
    return {
        {gseg::test::tool("gseg") + " segment", "-i " + f.bin.string() + " --labels-out OUT", ""},
        {gseg::test::tool("gseg") + " eval", "--scan " + f.bin.string() + " --labels " + f.label.string() + " --threads 1 --report OUT",
         "_table.md"},
        {gseg::test::tool("gseg") + " bench", "-i " + f.bin.string() + " --repeat 1", "-"},
        {gseg::test::tool("rawlog-gseg"), "-i " + kVlp16 + " -o OUT -c " + cfg + "vlp16.yaml", ""},
        {gseg::test::tool("rawlog-octomap"),
         "-i " + kVlp16 + " -o OUT --poses " + f.tum.string() + " --pose-tolerance 1e12 -c " + cfg + "vlp16.yaml --threads 1",
         "_ground.bt"},
        {gseg::test::tool("kitti2rawlog"), "-i " + f.sequence.string() + " -o OUT", ""},
    };
}

std::string replaceOut(std::string args, const std::string& out) {
    const std::size_t at = args.find("OUT");
    return at == std::string::npos ? args : args.replace(at, 3, out);
}

TEST(EveryTool, VersionAndHelpSayTheVersion) {
    std::vector<std::string> commands = {gseg::test::tool("gseg"), gseg::test::tool("gseg-observations2map")};
    for (const ToolCase& t : toolCases()) commands.push_back(t.command);
    for (const std::string& c : commands) {
        for (const char* option : {" --version", " --help"}) {
            const auto r = runCommand(c + option + " 2>&1");
            EXPECT_EQ(r.status, 0) << c << option << ": " << r.output;
            EXPECT_NE(r.output.find(std::string(" ") + GSEG_VERSION + "\n"), std::string::npos) << c << option << ": " << r.output;
            if (std::string(option) == " --help") {
                EXPECT_NE(r.output.find("--quiet"), std::string::npos) << c << ": " << r.output;
                EXPECT_NE(r.output.find("--verbose"), std::string::npos) << c << ": " << r.output;
            }
        }
    }
    const auto gseg = runCommand(gseg::test::tool("gseg") + " --version");
    EXPECT_EQ(gseg.output, std::string("gseg ") + GSEG_VERSION + "\n");
    const auto octomap = runCommand(gseg::test::tool("rawlog-octomap") + " --version");  // was "unexpected argument"
    EXPECT_EQ(octomap.output, std::string("rawlog-octomap (gseg) ") + GSEG_VERSION + "\n");
}

TEST(EveryTool, QuietPrintsNothingOnSuccessAndVerboseMore) {
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " is missing (apt-get install mrpt-common)";
    const fs::path dir = gseg::test::freshDir("tool_common", "quiet");
    int k = 0;
    for (const ToolCase& t : toolCases()) {
        const std::string out = (dir / ("q" + std::to_string(k++))).string();
        const auto quiet = runCommand(t.command + " --quiet " + replaceOut(t.args, out) + " 2>&1");
        EXPECT_EQ(quiet.status, 0) << t.command << ": " << quiet.output;
        EXPECT_EQ(quiet.output, "") << t.command;
        const std::string w = t.output == "-" ? " " : " -w ";  // gseg bench writes no file: no -w
        const auto normal = runCommand(t.command + w + replaceOut(t.args, out) + " 2>&1");
        const auto verbose = runCommand(t.command + w + "--verbose " + replaceOut(t.args, out) + " 2>&1");
        EXPECT_EQ(verbose.status, 0) << t.command << ": " << verbose.output;
        EXPECT_GT(verbose.output.size(), normal.output.size()) << t.command << ":\n" << verbose.output;
    }
}

TEST(EveryTool, AnExistingOutputIsRefusedWithoutOverwriteAndReplacedWithIt) {
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " is missing (apt-get install mrpt-common)";
    const fs::path dir = gseg::test::freshDir("tool_common", "overwrite");
    int k = 0;
    for (const ToolCase& t : toolCases()) {
        if (t.output == "-") continue;  // gseg bench writes no file
        const std::string out = (dir / ("o" + std::to_string(k++))).string(), file = out + t.output;
        std::ofstream(file) << "a previous run";
        const auto refused = runCommand(t.command + " " + replaceOut(t.args, out) + " 2>&1");
        EXPECT_EQ(refused.status, 2) << t.command << ": " << refused.output;
        EXPECT_NE(refused.output.find(file + " exists: give -w (--overwrite) to replace it"), std::string::npos)
            << t.command << ": " << refused.output;
        EXPECT_EQ(gseg::test::readText(file), "a previous run") << t.command;
        const auto replaced = runCommand(t.command + " -w " + replaceOut(t.args, out) + " 2>&1");
        EXPECT_EQ(replaced.status, 0) << t.command << ": " << replaced.output;
        EXPECT_NE(gseg::test::readText(file), "a previous run") << t.command;
        EXPECT_GT(fs::file_size(file), 0u) << t.command;
    }
}

TEST(EveryTool, AnUnwritableOutputFolderIsRefusedBeforeAnyWork) {
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " is missing (apt-get install mrpt-common)";
    for (const ToolCase& t : toolCases()) {
        if (t.output == "-") continue;
        const auto r = runCommand(t.command + " " + replaceOut(t.args, "/proc/gseg_out") + " 2>&1");
        EXPECT_EQ(r.status, 2) << t.command << ": " << r.output;
        EXPECT_NE(r.output.find("cannot write in the folder /proc"), std::string::npos) << t.command << ": " << r.output;
        EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << "one line, no work: " << r.output;
    }
}

TEST(EveryTool, TheObservations2mapWrapperRefusesAnExistingMapAndAnUnwritableFolder) {
    const fs::path dir = gseg::test::freshDir("tool_common", "o2m");
    const std::string wrapper = gseg::test::tool("gseg-observations2map"), ini = std::string(GSEG_SOURCE_DIR) + "/config/octomap_maps.ini";
    std::ofstream(dir / "in.simplemap") << "not used: refused before";
    const std::string file = (dir / "m_gseg_maps__CTraversabilityOctoMap_00_ground.bt").string();
    std::ofstream(file) << "a previous run";
    if (runCommand("command -v observations2map").status != 0) GTEST_SKIP() << "observations2map absent (mrpt-apps)";
    auto r = runCommand(wrapper + " -c " + ini + " -i " + (dir / "in.simplemap").string() + " -o " + (dir / "m").string() + " 2>&1");
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find(file + " exists: give -w (--overwrite) to replace it"), std::string::npos) << r.output;
    EXPECT_EQ(gseg::test::readText(file), "a previous run");
    r = runCommand(wrapper + " -q -w " + ini + " " + (dir / "in.simplemap").string() + " /proc/m 2>&1");
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("cannot write in the folder /proc"), std::string::npos) << r.output;
    r = runCommand(wrapper + " -q -v " + ini + " x y 2>&1");
    EXPECT_EQ(r.status, 2) << r.output;
}

}  // namespace
