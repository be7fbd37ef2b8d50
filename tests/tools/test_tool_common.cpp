// What every tool shares (#11 item 4): the progress reporter (gseg/progress.hpp), the output
// checks (gseg::io::checkOutputs) and, run on every tool, the options of common/cli.hpp:
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
#include <csignal>
#include <sys/inotify.h>
#include <sys/stat.h>
#include <sys/wait.h>
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

// rawlog-gseg printed every 100th scan off a terminal: minutes apart on a slow input, many lines
// a second on a fast one. Now one line per interval, fast or slow items alike.
/// Seconds per item.
class ProgressRate : public ::testing::TestWithParam<double> {};

TEST_P(ProgressRate, SteadyLinesWhateverTheItemRate) {
    const double secondsPerItem = GetParam();
    Captured out;
    gseg::Progress p(out.f, "tool", "frames", 0, 10.0, [&] { return out.now; });
    const int items = int(std::lround(120.0 / secondsPerItem));  // two minutes of work
    for (int k = 1; k <= items; ++k) {
        out.now = k * secondsPerItem;
        p.update(std::size_t(k), -1, k % 3 ? "" : "1 skipped");
    }
    const std::string t = out.text();
    const auto lines = std::count(t.begin(), t.end(), '\n');
    EXPECT_GE(lines, 9) << t;  // the first line + one per 10 s or so
    EXPECT_LE(lines, 13) << t;
}

INSTANTIATE_TEST_SUITE_P(SecondsPerItem, ProgressRate, ::testing::Values(0.01, 0.5, 7.0));

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
    // In a child whose stdout and stderr go to a file: nothing may reach either, on a terminal or not.
    const fs::path dir = gseg::test::freshDir("tool_common", "progress_quiet");
    const std::string captured = (dir / "printed.txt").string();
    for (int tty : {0, 1}) {
        const auto r = gseg::test::runInChild([&] {
            std::FILE* f = std::fopen(captured.c_str(), "w");
            if (!f) return 2;
            ::dup2(::fileno(f), 1);
            ::dup2(::fileno(f), 2);
            double now = 0;
            gseg::Progress p(nullptr, "tool", "scans", tty, 0.0, [&] { return now; });
            for (int k = 1; k <= 20; ++k) {
                now = k;
                p.update(std::size_t(k), k / 20.0, "note");
            }
            p.message("nothing");
            p.finish(20);
            std::fflush(nullptr);
            return 0;
        });
        EXPECT_TRUE(r.exited && r.code == 0);
        EXPECT_EQ(gseg::test::readText(captured), "") << "tty " << tty;
    }
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

/// One usage mistake of one tool and the one line it must answer (exit 2, before any work).
struct UsageCase {
    std::string tool;      ///< as it names itself ("gseg segment")
    std::string command;   ///< what runs it
    std::string args;
    std::string message;   ///< after "<tool>: ", before "; see <tool> --help"
};

std::vector<UsageCase> usageCases() {
    const std::string gseg = gseg::test::tool("gseg");
    std::vector<UsageCase> cases;
    struct Tool {
        std::string name, command, misspelt, meant, missingArgs, missing, lastOption = "-c", lastMessage = "-c/--config needs a value (FILE)";
    };
    const std::vector<Tool> tools = {
        // tool, command, a misspelt option (+ value), what it meant, a line missing what is needed, its message
        {"gseg segment", gseg + " segment", "--ply_out x.ply", "--ply-out", "--ply-out x.ply",
         "give the scan once: -i SCAN (or the old form, gseg segment SCAN)"},
        {"gseg eval", gseg + " eval", "--thraeds 2", "--threads", "--threads 2",
         "give either -i ROOT or --scan X.bin --labels X.label, and --threads 1..256"},
        {"gseg eval-map", gseg + " eval-map", "--mpa m.yaml", "--map", "--map m.yaml",
         "give the drive and the map once each: gseg eval-map DRIVE MAP.yaml (or -i DRIVE --map MAP.yaml)", "--map",
         "--map needs a value (MAP.yaml)"},
        {"gseg bench", gseg + " bench", "--repeet 2", "--repeat", "--repeat 2", "no scan to time: give -i SCAN (repeatable)"},
        {"rawlog-gseg", gseg::test::tool("rawlog-gseg"), "--sensr S", "--sensor", "-i in.rawlog",
         "missing required option -o/--output"},
        {"rawlog-octomap", gseg::test::tool("rawlog-octomap"), "--pose_tolerance 1", "--pose-tolerance", "-o out",
         "missing required option -i/--input"},
        {"kitti2rawlog", gseg::test::tool("kitti2rawlog"), "-input seq", "--input", "-i seq",
         "missing required option -o/--output", "--poses", "--poses needs a value (FILE)"},
        {"gseg-observations2map", gseg::test::tool("gseg-observations2map"), "--confg c.ini", "--config", "-c c.ini -i x",
         "missing required option -o/--output", "-c", "-c/--config needs a value (CONFIG.ini)"},
    };
    for (const Tool& t : tools) {
        const std::string misspelt = t.misspelt.substr(0, t.misspelt.find(' '));
        cases.push_back({t.name, t.command, "-i x --bogus", "unknown option '--bogus'"});
        cases.push_back({t.name, t.command, "-i x " + t.misspelt, "unknown option '" + misspelt + "' (did you mean '" + t.meant + "'?)"});
        cases.push_back({t.name, t.command, t.missingArgs, t.missing});
        cases.push_back({t.name, t.command, "-i x --quiet --quiet", "option -q/--quiet given twice"});
        cases.push_back({t.name, t.command, "-i x " + t.lastOption, "option " + t.lastMessage});
    }
    cases.push_back({"gseg", gseg, "segmnet", "unknown command 'segmnet' (did you mean 'segment'?)"});
    cases.push_back({"rawlog-gseg", gseg::test::tool("rawlog-gseg"), "-i x -o y z", "unexpected argument 'z' (this tool takes its inputs with options)"});
    cases.push_back({"rawlog-octomap", gseg::test::tool("rawlog-octomap"), "-i x -o y --quiet=yes", "option -q/--quiet takes no value"});
    return cases;
}

// #32: a configuration that still sets the retired key `threads` (one scan over several threads)
// runs with every tool that reads one, each saying once on stderr that the key is ignored.
TEST(EveryTool, AConfigurationWithTheRetiredKeyThreadsRunsWithOneWarning) {
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " is missing (apt-get install mrpt-common)";
    const fs::path dir = fs::path(GSEG_BINARY_DIR) / "tests" / "tool_common" / "retired_key";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string old = (dir / "old.yaml").string();
    std::ofstream(old) << "distToGround: auto\nthreads: 2\n";
    const std::string vlp16 = std::string(GSEG_SOURCE_DIR) + "/config/vlp16.yaml";
    int n = 0;
    for (const ToolCase& t : toolCases()) {
        if (t.command.find("kitti2rawlog") != std::string::npos) continue;  // reads no configuration
        std::string args = replaceOut(t.args, (dir / ("out" + std::to_string(n++))).string());
        if (const std::size_t at = args.find(vlp16); at != std::string::npos) args.replace(at, vlp16.size(), old);
        else args += " -c " + old;
        const auto r = runCommand("{ " + t.command + " " + args + " 2>" + (dir / "err.txt").string() + " >/dev/null; }");
        const std::string err = gseg::test::readText((dir / "err.txt").string());
        EXPECT_EQ(r.status, 0) << t.command << ": " << err;
        const std::string tool = t.command.substr(t.command.rfind('/') + 1);
        const std::string warning = tool + ": warning: " + old + ":2: 'threads' is ignored: ";
        const std::size_t at = err.find(warning);
        EXPECT_NE(at, std::string::npos) << t.command << ": " << err;
        EXPECT_EQ(err.find("'threads' is ignored", at + warning.size()), std::string::npos) << "said once: " << err;
    }
    EXPECT_EQ(n, 5);
}

TEST(EveryTool, AUsageMistakeIsOneLineNamingTheOptionInTheSameWordsEverywhere) {
    // Was: "--bogus: no sequences/ folder" (gseg eval), "give the scan once" (gseg segment --bogus),
    // "Couldn't find match for argument (Argument: x.ply)" (--ply_out x.ply), "One or more required
    // arguments missing! ( )" (rawlog-gseg, rawlog-octomap, kitti2rawlog, even for kitti2rawlog --bogus).
    for (const UsageCase& c : usageCases()) {
        const auto r = runCommand(c.command + " " + c.args + " 2>&1");
        EXPECT_EQ(r.status, 2) << c.tool << " " << c.args << ": " << r.output;
        EXPECT_EQ(r.output, c.tool + ": " + c.message + "; see " + c.tool + " --help\n") << c.tool << " " << c.args;
    }
}

TEST(EveryTool, OptionsAreReadAsTheyAreMeant) {
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " is missing (apt-get install mrpt-common)";
    const fs::path dir = gseg::test::freshDir("tool_common", "spelling");
    const std::string gseg = gseg::test::tool("gseg"), bin = fixture().bin.string();
    // --name=value is --name value; switches go together (-qw); a value may start with '-'.
    auto r = runCommand(gseg + " segment --input=" + bin + " --labels-out=" + (dir / "a.labels").string() + " -qw 2>&1");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(r.output, "");
    EXPECT_TRUE(fs::exists(dir / "a.labels"));
    r = runCommand(gseg + " segment -i " + kVlp16 + " --index -1 2>&1");
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("--index needs N >= 0"), std::string::npos) << "-1 read as the value of --index: " << r.output;
    // --help wins over a mistake on the same line; a wrong value's type names the option.
    r = runCommand(gseg + " segment --bogus --help 2>&1");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("--ply-out"), std::string::npos) << r.output;
    r = runCommand(gseg + " segment -i " + bin + " --index abc 2>&1");
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_EQ(r.output, "gseg segment: option --index: cannot read 'abc' as its value; see gseg segment --help\n");
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

TEST(EveryTool, AnOutputThatIsASymbolicLinkIsWrittenThroughNotReplaced) {
    // #18 point 1: with -w the temporary was renamed onto the link (the link gone, its target unchanged).
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " is missing (apt-get install mrpt-common)";
    const fs::path dir = gseg::test::freshDir("tool_common", "symlink");
    int k = 0;
    for (const ToolCase& t : toolCases()) {
        if (t.output == "-") continue;
        const std::string out = (dir / ("o" + std::to_string(k++))).string(), file = out + t.output;
        const std::string target = out + "_target";
        std::ofstream(target) << "a previous run";
        fs::create_symlink(fs::path(target).filename(), file);
        const auto r = runCommand(t.command + " -w " + replaceOut(t.args, out) + " 2>&1");
        EXPECT_EQ(r.status, 0) << t.command << ": " << r.output;
        EXPECT_TRUE(fs::is_symlink(file)) << t.command << ": the link was replaced";
        EXPECT_NE(gseg::test::readText(target), "a previous run") << t.command << ": the link's target was not written";
        EXPECT_GT(fs::file_size(target), 0u) << t.command;
    }
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp"), "");
}

TEST(EveryTool, APipeBehindALinkGetsTheOutputAndTheLinkStays) {
    // #18 point 1: `-o /dev/stdout | cat > x` left x empty and replaced /dev/stdout with a file. The
    // test uses a link of its own to the same place (/proc/self/fd/1), not the system's /dev/stdout.
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " is missing (apt-get install mrpt-common)";
    const fs::path dir = gseg::test::freshDir("tool_common", "stdout");
    fs::create_symlink("/proc/self/fd/1", dir / "stdout");
    for (const ToolCase& t : toolCases()) {
        if (t.output != "") continue;  // the tools with one output file: rawlog-gseg, kitti2rawlog, gseg segment
        const std::string got = (dir / "got").string();
        const std::string code = (dir / "code").string();
        const auto r = runCommand("(" + t.command + " -q " + replaceOut(t.args, (dir / "stdout").string()) + "; echo $? > " +
                                  code + ") | cat > " + got);
        EXPECT_EQ(gseg::test::readText(code), "0\n") << t.command << ": " << r.output;
        // What came through is what the same run writes to a file (the tools give the same bytes).
        const std::string file = (dir / "file").string();
        const auto f = runCommand(t.command + " -q " + replaceOut(t.args, file) + " 2>&1");
        EXPECT_EQ(f.status, 0) << t.command << ": " << f.output;
        EXPECT_GT(fs::file_size(got), 500u) << t.command << ": nothing came through the pipe";
        EXPECT_TRUE(gseg::test::readText(got) == gseg::test::readText(file)) << t.command << ": not what it writes to a file";
        EXPECT_TRUE(fs::is_symlink(dir / "stdout")) << t.command;
        fs::remove(got), fs::remove(file);
    }
    // What came through is a whole rawlog: rawlog-gseg reads it back from a pipe.
    const auto r = runCommand("bash -c '" + gseg::test::tool("rawlog-gseg") + " -q -i " + kVlp16 + " -c " + GSEG_SOURCE_DIR +
                              "/config/vlp16.yaml -o " + (dir / "stdout").string() + " | " + gseg::test::tool("rawlog-gseg") +
                              " -i /dev/stdin -o " + (dir / "again.rawlog").string() + "' 2>&1");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("already split"), std::string::npos) << r.output;
}

TEST(EveryTool, AnEmptyOutputNameIsRefusedBeforeAnyWork) {
    // #18 point 10: `-o ""` did all the work, then failed at the rename.
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " is missing (apt-get install mrpt-common)";
    for (const ToolCase& t : toolCases()) {
        if (t.output == "-") continue;
        const auto r = runCommand(t.command + " " + replaceOut(t.args, "''") + " 2>&1");
        EXPECT_EQ(r.status, 2) << t.command << ": " << r.output;
        EXPECT_NE(r.output.find(" is empty"), std::string::npos) << t.command << ": " << r.output;
        EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << "one line, no work: " << r.output;
    }
}

TEST(EveryTool, ASignalWhileOutputsArePutInPlaceLeavesAllNewNoMix) {
    // #18 point 4: interrupted at its third rename, rawlog-octomap left three new files, three old
    // ones and six hidden backups. strace delivers SIGTERM right after the N-th rename.
    if (runCommand("command -v strace").status != 0) GTEST_SKIP() << "strace is not installed (apt-get install strace)";
    if (runCommand("strace -o /dev/null true").status != 0) GTEST_SKIP() << "strace cannot trace here (ptrace refused)";
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " is missing (apt-get install mrpt-common)";
    const fs::path dir = gseg::test::freshDir("tool_common", "renames");
    const Fixture& f = fixture();
    const std::string cfg = std::string(GSEG_SOURCE_DIR) + "/config/";
    struct Case {
        std::string command, args;
        std::vector<std::string> files;  ///< OUT-relative
        std::vector<std::size_t> renames;  ///< after which rename SIGTERM comes (1-based)
    };
    const std::vector<Case> cases = {
        {gseg::test::tool("gseg") + " segment", "-i " + f.bin.string() + " --labels-out OUT.labels --ply-out OUT.ply --png-out OUT.png --scene-out OUT.3Dscene",
         {".labels", ".ply", ".png", ".3Dscene"}, {2, 4}},
        {gseg::test::tool("gseg") + " eval", "--scan " + f.bin.string() + " --labels " + f.label.string() + " --threads 1 --report OUT",
         {"_frames.csv", "_sequences.csv", "_table.md", "_range.png"}, {3}},
        {gseg::test::tool("rawlog-octomap"),
         "-i " + kVlp16 + " -o OUT --poses " + f.tum.string() + " --pose-tolerance 1e12 -c " + cfg + "vlp16.yaml --threads 1",
         {"_ground.bt", "_obstacles.bt", "_traversability.ot", "_traversability.png", "_traversability.ply", "_traversability.3Dscene",
          "_costmap.pgm", "_costmap.yaml", "_layers.tif", "_layer_elevation.png", "_layer_slope.png", "_layer_step.png", "_layer_roughness.png", "_layer_clearance.png", "_layer_class.png", "_layer_cost.png"},
         {1, 2, 3, 4, 5, 6, 7, 8, 9, 16}},
        {gseg::test::tool("kitti2rawlog"), "-i " + f.sequence.string() + " --poses " + (dir / "kitti_poses.txt").string() +
         " -o OUT.rawlog --simplemap OUT.simplemap", {".rawlog", ".simplemap"}, {1}},
    };
    std::ofstream(dir / "kitti_poses.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n";
    int k = 0;
    for (const Case& c : cases) {
        const std::string out = (dir / ("o" + std::to_string(k++))).string();
        std::string all = c.args;  // OUT stands more than once
        for (std::size_t p = all.find("OUT"); p != std::string::npos; p = all.find("OUT")) all.replace(p, 3, out);
        for (const std::size_t n : c.renames) {
            for (const auto& file : c.files) std::ofstream(out + file) << "old";
            const auto r = runCommand("strace -f -o /dev/null -e trace=rename -e inject=rename:signal=SIGTERM:when=" +
                                      std::to_string(n) + " " + c.command + " -q -w " + all + " 2>&1");
            EXPECT_NE(r.status, 0) << c.command << " at rename " << n << ": " << r.output;
            std::size_t fresh = 0, old = 0;
            for (const auto& file : c.files) {
                const std::string now = gseg::test::readText(out + file);
                fresh += now.size() > 3;
                old += now == "old";
            }
            EXPECT_TRUE(fresh == c.files.size() || old == c.files.size())
                << c.command << ", SIGTERM at rename " << n << ": " << fresh << " new, " << old << " old: " << r.output;
            EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp") + gseg::test::entriesContaining(dir.string(), ".bak"), "")
                << c.command << ", SIGTERM at rename " << n;
        }
    }
}

/// Starts rawlog-gseg with `args` (its input a FIFO nobody writes yet: it waits there) and returns
/// once a file whose name contains `name` (its temporary) was created in `dir`: no sleeps.
pid_t startAndAwaitTemporary(const std::vector<std::string>& args, const fs::path& dir, const std::string& name) {
    const int watch = ::inotify_init1(IN_CLOEXEC);
    EXPECT_GE(watch, 0);
    EXPECT_GE(::inotify_add_watch(watch, dir.c_str(), IN_CREATE), 0);
    ::alarm(120);  // a tool that never made its temporary would leave read() below blocked
    const pid_t pid = gseg::test::spawnTool("rawlog-gseg", args, (dir / "a.txt").string());
    EXPECT_GT(pid, 0);
    alignas(inotify_event) char events[4096];
    std::string created;
    while (created.find(name) == std::string::npos) {
        const ssize_t n = ::read(watch, events, sizeof events);
        if (n <= 0) break;
        for (ssize_t at = 0; at < n;) {
            const auto* e = reinterpret_cast<const inotify_event*>(events + at);
            if (e->len) created += std::string(e->name) + " ";
            at += ssize_t(sizeof(inotify_event) + e->len);
        }
    }
    ::close(watch);
    return pid;
}

TEST(EveryTool, TwoRunsWritingOneNewOutputWithoutOverwriteCannotBothSucceed) {
    // #18 point 5: both passed the "exists?" check, both said "wrote same.rawlog", one result was lost.
    // Run A makes its temporary, then waits for its input (a FIFO the test holds); run B writes the
    // output meanwhile; then A gets its input: it must fail and leave B's file.
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " is missing (apt-get install mrpt-common)";
    const fs::path dir = gseg::test::freshDir("tool_common", "race");
    const std::string fifo = (dir / "in.fifo").string(), same = (dir / "same.rawlog").string();
    const std::string cfg = std::string(GSEG_SOURCE_DIR) + "/config/vlp16.yaml";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    pid_t a = -1;
    ASSERT_NO_FATAL_FAILURE(a = startAndAwaitTemporary({"-q", "-i", fifo, "-o", same, "-c", cfg}, dir, "same.rawlog"));
    const auto b = runCommand(gseg::test::tool("rawlog-gseg") + " -q -i " + kVlp16 + " -o " + same + " -c " + cfg + " 2>&1");
    EXPECT_EQ(b.status, 0) << b.output;
    const std::string written = gseg::test::readText(same);
    ASSERT_GT(written.size(), 1000u);
    const auto feed = runCommand("cat " + kVlp16 + " > " + fifo);
    EXPECT_EQ(feed.status, 0);
    int status = 0;
    ASSERT_EQ(::waitpid(a, &status, 0), a);
    ::alarm(0);
    const std::string err = gseg::test::readText((dir / "a.txt").string());
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << err;
    EXPECT_NE(err.find("was created by another program while this run worked: not replaced"), std::string::npos) << err;
    EXPECT_TRUE(gseg::test::readText(same) == written) << "run A replaced run B's output";
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp"), "");
}

TEST(EveryTool, TheTemporaryOfAKilledRunIsRemovedByTheNextRunToThatOutput) {
    // #18 point 9: SIGKILL cannot be caught; its temporaries stayed forever.
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " is missing (apt-get install mrpt-common)";
    const fs::path dir = gseg::test::freshDir("tool_common", "killed");
    const std::string fifo = (dir / "in.fifo").string(), out = (dir / "split.rawlog").string();
    const std::string cfg = std::string(GSEG_SOURCE_DIR) + "/config/vlp16.yaml";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    pid_t a = -1;
    ASSERT_NO_FATAL_FAILURE(a = startAndAwaitTemporary({"-q", "-i", fifo, "-o", out, "-c", cfg}, dir, "split.rawlog"));
    ::kill(a, SIGKILL);
    int status = 0;
    ASSERT_EQ(::waitpid(a, &status, 0), a);
    ::alarm(0);
    ASSERT_TRUE(WIFSIGNALED(status));
    EXPECT_NE(gseg::test::entriesContaining(dir.string(), "split.rawlog"), "") << "the killed run's temporary";
    const auto r = runCommand(gseg::test::tool("rawlog-gseg") + " -q -i " + kVlp16 + " -o " + out + " -c " + cfg + " 2>&1");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), "split.rawlog"), "split.rawlog");
}

TEST(EveryTool, TheRawlogToolsReadAPipe) {
    // #17: `cat drive.rawlog | rawlog-octomap -i /dev/stdin` failed ("cannot open the rawlog"), while
    // rawlog-gseg read it: the map layer had a reader of its own. One reader now, the same files.
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " is missing (apt-get install mrpt-common)";
    const fs::path dir = gseg::test::freshDir("tool_common", "pipe_in");
    const Fixture& f = fixture();
    const std::string args = " --poses " + f.tum.string() + " --pose-tolerance 1e12 -c " + GSEG_SOURCE_DIR +
                             "/config/vlp16.yaml --threads 1 -q";
    const std::string octomap = gseg::test::tool("rawlog-octomap");
    auto r = runCommand(octomap + " -i " + kVlp16 + " -o " + (dir / "file").string() + args + " 2>&1");
    ASSERT_EQ(r.status, 0) << r.output;
    r = runCommand("cat " + kVlp16 + " | " + octomap + " -i /dev/stdin -o " + (dir / "pipe").string() + args + " 2>&1");
    ASSERT_EQ(r.status, 0) << r.output;
    for (const char* s : {"_ground.bt", "_obstacles.bt", "_traversability.ot", "_traversability.png", "_traversability.ply",
                          "_traversability.3Dscene", "_costmap.pgm", "_costmap.yaml", "_layers.tif", "_layer_elevation.png", "_layer_slope.png", "_layer_step.png", "_layer_roughness.png", "_layer_clearance.png", "_layer_class.png", "_layer_cost.png"}) {
        std::string a = gseg::test::readText((dir / "file").string() + s);
        EXPECT_GT(a.size(), 100u) << s;
        if (std::string(s) == "_costmap.yaml" && a.find("file_costmap.pgm") != std::string::npos)  // names its own PGM
            a.replace(a.find("file_costmap.pgm"), 4, "pipe");
        EXPECT_TRUE(a == gseg::test::readText((dir / "pipe").string() + s)) << s << " differs when read from a pipe";
    }
    r = runCommand("cat " + kVlp16 + " | " + gseg::test::tool("rawlog-gseg") + " -q -i /dev/stdin -o " +
                   (dir / "split.rawlog").string() + " -c " + GSEG_SOURCE_DIR + "/config/vlp16.yaml 2>&1");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_GT(fs::file_size(dir / "split.rawlog"), 1000u);
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
