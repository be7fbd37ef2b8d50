// `gseg eval` end to end: report files, parallel == serial, the independent scorer, bad trees.
#include <gseg/eval/kitti_rings.hpp>
#include <gseg/io/kitti.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace fs = std::filesystem;

namespace {

const fs::path kDir = fs::path(GSEG_BINARY_DIR) / "tests" / "eval_tool";

using gseg::test::runGseg;

std::string slurp(const fs::path& p) { return gseg::test::readText(p.string()); }

// The CSV without its last column (ms), which differs between runs.
std::string withoutTimes(const std::string& csv) {
    std::istringstream in(csv);
    std::string out;
    for (std::string line; std::getline(in, line);) out += line.substr(0, line.rfind(',')) + "\n";
    return out;
}

// A CSV without its column `name` (timing).
std::string withoutColumn(const std::string& csv, const std::string& name) {
    std::istringstream in(csv);
    std::string out;
    long skip = -1;
    for (std::string line; std::getline(in, line);) {
        std::vector<std::string> cells;
        std::istringstream cs(line);
        for (std::string c; std::getline(cs, c, ',');) cells.push_back(c);
        if (skip < 0) skip = std::find(cells.begin(), cells.end(), name) - cells.begin();
        for (long k = 0; k < long(cells.size()); ++k)
            if (k != skip) out += cells[std::size_t(k)] + ",";
        out += "\n";
    }
    return out;
}

// A Markdown table without the last cell of each row (ms/scan).
std::string withoutLastCell(const std::string& markdown) {
    std::istringstream in(markdown);
    std::string out;
    for (std::string line; std::getline(in, line);)
        out += (line.rfind("| ", 0) == 0 ? line.substr(0, line.rfind(" | ", line.size() - 3)) : line) + "\n";
    return out;
}

void writeFloats(const fs::path& p, const std::vector<float>& v) {
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * 4));
}

}  // namespace

TEST(EvalTool, SharedKittiReportsAgreeSerialParallelAndWithTheIndependentScorer) {
    const std::string root = gseg::test::sharedData("semantickitti");
    if (root.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti");
    for (const char* d : {"serial", "parallel", "pred"}) fs::remove_all(kDir / d);  // not "bad": BadTrees may run now
    int status = -1;
    const std::string serial = runGseg("eval", "'" + root + "' --threads 1 --report '" + (kDir / "serial/k").string() +
                                       "' --labels-out-dir '" + (kDir / "pred").string() + "'", status);
    ASSERT_EQ(status, 0) << serial;
    const std::string parallel = runGseg("eval", "'" + root + "' --threads 2 --report '" + (kDir / "parallel/k").string() + "'",
                                         status);
    ASSERT_EQ(status, 0) << parallel;
    // 00/000003..000005 have no labels: reported by name and skipped.
    EXPECT_NE(serial.find("4 frames evaluated, 3 skipped"), std::string::npos) << serial;
    EXPECT_NE(serial.find("skipped 00/000005"), std::string::npos) << serial;
    for (const char* f : {"k_frames.csv", "k_sequences.csv", "k_table.md", "k_range.png"})
        EXPECT_GT(fs::file_size(kDir / "serial" / f), 100u) << f;
    const std::string csv = slurp(kDir / "serial/k_frames.csv");
    EXPECT_EQ(withoutTimes(csv), withoutTimes(slurp(kDir / "parallel/k_frames.csv")));
    EXPECT_NE(slurp(kDir / "serial/k_table.md").find("| **mean** |"), std::string::npos);

    // Each frame's counts equal the independent scorer's on the same predictions.
    if (std::system("python3 --version > /dev/null 2>&1") != 0) GTEST_SKIP() << "python3 is not installed";
    std::istringstream rows(csv);
    std::string line;
    std::getline(rows, line);  // header
    int checked = 0;
    while (std::getline(rows, line)) {
        std::vector<std::string> c;
        std::istringstream cells(line);
        for (std::string cell; std::getline(cells, cell, ',');) c.push_back(cell);
        ASSERT_GE(c.size(), 6u);
        const std::string seq = root + "/sequences/" + c[0];
        const std::string cmd = "python3 '" GSEG_SHARED_DIR "/tools/eval_labels.py' '" + seq + "/velodyne/" + c[1] +
                                ".bin' '" + seq + "/labels/" + c[1] + ".label' '" +
                                (kDir / "pred" / (c[0] + "_" + c[1] + ".pred")).string() + "'";
        const auto scored = gseg::test::runCommand(cmd);
        const std::string& out = scored.output;
        ASSERT_EQ(scored.status, 0) << out;
        const std::string want = "TP=" + c[3] + " FP=" + c[4] + " FN=" + c[5] + " ";
        EXPECT_NE(out.find(want), std::string::npos) << want << " not in " << out;
        ++checked;
    }
    EXPECT_EQ(checked, 4);
}

TEST(EvalTool, SingleScanMode) {
    const std::string scan = gseg::test::sharedData("semantickitti/sequences/08/velodyne/000000.bin");
    const std::string label = gseg::test::sharedData("semantickitti/sequences/08/labels/000000.label");
    if (scan.empty() || label.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/08");
    int status = -1;
    const std::string out = runGseg("eval", "--scan '" + scan + "' --labels '" + label + "'", status);
    EXPECT_EQ(status, 0) << out;
    EXPECT_NE(out.find("1 frames evaluated, 0 skipped"), std::string::npos) << out;
}

// --ring-step / --point-step: the frame scored (and its predictions) is the thinned scan of
// gseg::eval::kittiThinned, and absurd steps are usage errors.
TEST(EvalTool, ThinnedScansScoreTheKeptPointsOnly) {
    const std::string scan = gseg::test::sharedData("semantickitti/sequences/08/velodyne/000000.bin");
    const std::string label = gseg::test::sharedData("semantickitti/sequences/08/labels/000000.label");
    if (scan.empty() || label.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/08");
    const std::vector<float> pts = gseg::io::readKittiBin(scan);
    const std::size_t kept = gseg::eval::kittiThinned(pts.data(), pts.size() / 4, 2, 3).size();
    ASSERT_GT(kept, pts.size() / 4 / 8);
    ASSERT_LT(kept, pts.size() / 4 / 5);
    const fs::path dir = kDir / "thinned";
    fs::remove_all(dir);
    int status = -1;
    const std::string out = runGseg("eval", "--scan '" + scan + "' --labels '" + label + "' --ring-step 2 --point-step 3 "
                                    "--report '" + (dir / "r").string() + "' --labels-out-dir '" + (dir / "pred").string() + "'",
                                    status);
    ASSERT_EQ(status, 0) << out;
    EXPECT_NE(out.find("thinned: --ring-step 2, --point-step 3"), std::string::npos) << out;
    const std::string csv = slurp(dir / "r_frames.csv");
    const std::string row = csv.substr(csv.find('\n') + 1);
    EXPECT_EQ(row.rfind("scan,000000," + std::to_string(kept) + ",", 0), 0u) << csv;
    EXPECT_EQ(fs::file_size(dir / "pred" / "scan_000000.pred"), kept);
    for (const char* bad : {"--ring-step 0", "--ring-step 65", "--point-step 0"}) {
        const std::string msg = runGseg("eval", "--scan '" + scan + "' --labels '" + label + "' " + bad, status);
        EXPECT_EQ(status, 2) << bad << ": " << msg;
        EXPECT_NE(msg.find("--ring-step and --point-step take 1..64"), std::string::npos) << msg;
    }
}

TEST(EvalTool, BadTrees) {
    int status = -1;
    fs::remove_all(kDir / "bad");
    fs::create_directories(kDir / "bad/empty");
    std::string out = runGseg("eval", "'" + (kDir / "bad/empty").string() + "'", status);
    EXPECT_EQ(status, 1);
    EXPECT_NE(out.find("no sequences/ folder"), std::string::npos) << out;

    // One good frame, one truncated label file, one label/point count mismatch.
    const fs::path seq = kDir / "bad/root/sequences/01";
    std::vector<float> pts;
    for (int i = 0; i < 400; ++i) pts.insert(pts.end(), {float(i % 20) * 0.5f, float(i / 20) * 0.5f, -1.7f, 0.f});
    for (const char* f : {"000000", "000001", "000002"}) writeFloats(seq / "velodyne" / (std::string(f) + ".bin"), pts);
    fs::create_directories(seq / "labels");
    const std::vector<std::uint32_t> labels(400, 40);
    std::ofstream(seq / "labels/000000.label", std::ios::binary).write(reinterpret_cast<const char*>(labels.data()), 1600);
    std::ofstream(seq / "labels/000001.label", std::ios::binary).write(reinterpret_cast<const char*>(labels.data()), 1598);
    std::ofstream(seq / "labels/000002.label", std::ios::binary).write(reinterpret_cast<const char*>(labels.data()), 1200);
    out = runGseg("eval", "'" + (kDir / "bad/root").string() + "' --report '" + (kDir / "bad/out/r").string() + "'", status);
    EXPECT_EQ(status, 0) << out;
    EXPECT_NE(out.find("1 frames evaluated, 2 skipped"), std::string::npos) << out;
    EXPECT_NE(out.find("skipped 01/000001"), std::string::npos) << out;
    EXPECT_NE(out.find("not a multiple of 4"), std::string::npos) << out;
    EXPECT_NE(out.find("300 labels for 400 points"), std::string::npos) << out;
    EXPECT_TRUE(fs::exists(kDir / "bad/out/r_table.md"));

    out = runGseg("eval", "'" + (kDir / "bad/root").string() + "' --sequences 07", status);
    EXPECT_EQ(status, 1);
    EXPECT_NE(out.find("no scans"), std::string::npos) << out;
    runGseg("eval", "", status);
    EXPECT_EQ(status, 2);
}

// #18 point 10: a sequence asked for that gives no frame is named, and so is one whose velodyne/
// cannot be listed (a symbolic link loop); the other sequences are still evaluated, exit 3.
TEST(EvalTool, SequencesWithoutFramesOrWithAnUnlistableFolderAreNamedAndTheOthersEvaluated) {
    const fs::path root = kDir / "seqs";
    fs::remove_all(root);
    std::vector<float> pts;
    for (int i = 0; i < 400; ++i) pts.insert(pts.end(), {float(i % 20) * 0.5f, float(i / 20) * 0.5f, -1.7f, 0.f});
    writeFloats(root / "sequences/00/velodyne/000000.bin", pts);
    const std::vector<std::uint32_t> labels(400, 40);
    fs::create_directories(root / "sequences/00/labels");
    std::ofstream(root / "sequences/00/labels/000000.label", std::ios::binary)
        .write(reinterpret_cast<const char*>(labels.data()), 1600);
    fs::create_directories(root / "sequences/05/velodyne");  // no frames
    fs::create_directories(root / "sequences/06");
    fs::create_symlink("loop", root / "sequences/06/loop");
    fs::create_symlink("loop", root / "sequences/06/velodyne");  // velodyne -> loop -> loop
    int status = -1;
    std::string out = runGseg("eval", "'" + root.string() + "' --sequences 00,05", status);
    EXPECT_EQ(status, 3) << out;
    EXPECT_NE(out.find("gseg eval: sequence 05: no scans (*.bin) in " + (root / "sequences/05/velodyne").string()),
              std::string::npos) << out;
    EXPECT_NE(out.find("1 frames evaluated, 0 skipped, 1 sequence(s) without frames"), std::string::npos) << out;
    out = runGseg("eval", "'" + root.string() + "' --sequences 00,07", status);
    EXPECT_EQ(status, 3) << out;
    EXPECT_NE(out.find("gseg eval: sequence 07: no folder " + (root / "sequences/07/velodyne").string()), std::string::npos)
        << out;
    // Every sequence: 06 is named with the folder and the reason, 00 is evaluated.
    out = runGseg("eval", "'" + root.string() + "'", status);
    EXPECT_EQ(status, 3) << out;
    EXPECT_NE(out.find("gseg eval: sequence 06: no folder " + (root / "sequences/06/velodyne").string() +
                       " (Too many levels of symbolic links)"),
              std::string::npos) << out;
    EXPECT_NE(out.find("1 frames evaluated"), std::string::npos) << out;
    // Nothing to evaluate at all: an error naming what was wrong.
    out = runGseg("eval", "'" + root.string() + "' --sequences 05,06", status);
    EXPECT_EQ(status, 1) << out;
    EXPECT_NE(out.find("sequence 05: no scans"), std::string::npos) << out;
    EXPECT_NE(out.find("sequence 06: no folder"), std::string::npos) << out;
    fs::remove_all(root);
}

TEST(EvalTool, BreakdownCountsAgreeWithTheScoresAndDrawOnePicturePerFrame) {
    const std::string root = gseg::test::sharedData("semantickitti");
    if (root.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti");
    const fs::path dir = kDir / "breakdown";
    fs::remove_all(dir);
    int status = -1;
    const std::string out = runGseg("eval", "'" + root + "' --threads 2 --breakdown --report '" + (dir / "r").string() + "'", status);
    ASSERT_EQ(status, 0) << out;
    EXPECT_NE(out.find("failure breakdown, all frames:"), std::string::npos) << out;
    EXPECT_NE(out.find("false ground by height above the local labelled ground"), std::string::npos) << out;
    // Per frame: false ground summed over classes = FP, missed ground over classes = FN.
    std::map<std::string, std::pair<long, long>> fpfn, fromBreakdown, rangeSums;
    std::istringstream frames(slurp(dir / "r_frames.csv"));
    std::string line;
    std::getline(frames, line);
    while (std::getline(frames, line)) {
        std::istringstream f(line);
        std::string seq, frame, points, tp, fp, fn;
        std::getline(f, seq, ','), std::getline(f, frame, ','), std::getline(f, points, ',');
        std::getline(f, tp, ','), std::getline(f, fp, ','), std::getline(f, fn, ',');
        fpfn[seq + "/" + frame] = {std::stol(fp), std::stol(fn)};
    }
    ASSERT_EQ(fpfn.size(), 4u);
    std::istringstream rows(slurp(dir / "r_breakdown.csv"));
    std::getline(rows, line);
    EXPECT_EQ(line, "sequence,frame,kind,bin,points");
    while (std::getline(rows, line)) {
        std::istringstream f(line);
        std::string seq, frame, kind, bin, n;
        std::getline(f, seq, ','), std::getline(f, frame, ','), std::getline(f, kind, ','), std::getline(f, bin, ',');
        std::getline(f, n, ',');
        const std::string key = seq + "/" + frame;
        if (kind == "false_by_class") fromBreakdown[key].first += std::stol(n);
        if (kind == "missed_by_class") fromBreakdown[key].second += std::stol(n);
        if (kind == "false_by_range") rangeSums[key].first += std::stol(n);
        if (kind == "missed_by_range") rangeSums[key].second += std::stol(n);
    }
    long allFp = 0;
    for (const auto& [key, counts] : fpfn) {
        EXPECT_EQ(fromBreakdown[key], counts) << key;
        EXPECT_EQ(rangeSums[key], counts) << key;
        allFp += counts.first;
        const fs::path png = dir / "r_breakdown" / (key.substr(0, 2) + "_" + key.substr(3) + ".png");
        ASSERT_TRUE(fs::exists(png)) << png;
        EXPECT_EQ(slurp(png).substr(1, 3), "PNG");
    }
    EXPECT_EQ(fromBreakdown["all/all"].first, allFp);
}

TEST(EvalTool, TwoMpiRanksWriteTheReportsOfASerialRun) {
    GSEG_TEST_MPIRUN_OR_SKIP(mpirun, 2);
    const std::string root = gseg::test::sharedData("semantickitti");
    if (root.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti");
    const fs::path dir = kDir / "mpi";
    fs::remove_all(dir);
    const std::string args = " eval '" + root + "' -c '" GSEG_SOURCE_DIR "/config/kitti_hdl64.yaml' --threads 1 --breakdown --report '";
    auto serial = gseg::test::runCommand("'" + gseg::test::tool("gseg") + "'" + args + (dir / "serial/k").string() + "'");
    ASSERT_EQ(serial.status, 0) << serial.output;
    auto ranks = gseg::test::runCommand(mpirun + "'" + gseg::test::tool("gseg") + "'" + args + (dir / "mpi/k").string() + "'");
    ASSERT_EQ(ranks.status, 0) << ranks.output;
    // The 7 frames (3 without labels) were split: rank 1 evaluated some of them.
    EXPECT_NE(ranks.output.find("7 frames split over 2 processes by their points: 4, 3"), std::string::npos) << ranks.output;
    for (const char* f : {"000003", "000004", "000005"})
        EXPECT_NE(ranks.output.find(std::string("skipped 00/") + f + ": no label file"), std::string::npos) << ranks.output;
    EXPECT_NE(ranks.output.find("4 frames evaluated, 3 skipped"), std::string::npos) << ranks.output;
    auto both = [&](const std::string& name) {
        return std::make_pair(slurp(dir / "serial" / name), slurp(dir / "mpi" / name));
    };
    const auto frames = both("k_frames.csv"), sequences = both("k_sequences.csv"), table = both("k_table.md");
    EXPECT_EQ(withoutColumn(frames.first, "ms"), withoutColumn(frames.second, "ms"));
    EXPECT_EQ(withoutColumn(frames.first, "ms").substr(0, 27), "sequence,frame,points,TP,FP") << "the same CSV, ms left out";
    EXPECT_EQ(std::count(frames.second.begin(), frames.second.end(), '\n'), 5) << frames.second;
    EXPECT_EQ(withoutColumn(sequences.first, "ms"), withoutColumn(sequences.second, "ms"));
    EXPECT_EQ(withoutLastCell(table.first), withoutLastCell(table.second));
    EXPECT_NE(withoutLastCell(table.second).find("| 08 | 1 | 98.40"), std::string::npos) << table.second;
    for (const char* exact : {"k_breakdown.csv", "k_range.png", "k_breakdown/00_000000.png", "k_breakdown/08_000000.png"}) {
        const auto [one, two] = both(exact);
        EXPECT_GT(one.size(), 100u) << exact;
        EXPECT_TRUE(one == two) << exact << " differs";
    }
    EXPECT_EQ(std::distance(fs::directory_iterator(dir / "mpi/k_breakdown"), fs::directory_iterator()), 4)
        << "one picture per scored frame, drawn by the rank that had it";
}

TEST(EvalTool, UnderMpiAnErrorIsOneLineFromRankZeroAndOneExitCode) {
    GSEG_TEST_MPIRUN_OR_SKIP(mpirun, 2);
    const std::string gseg = "'" + gseg::test::tool("gseg") + "'";
    auto r = gseg::test::runCommand(mpirun + gseg + " eval '" + (kDir / "mpi_missing_root").string() + "' --threads 1");
    EXPECT_NE(r.status, 0);
    EXPECT_EQ(r.output.find("gseg eval: "), r.output.rfind("gseg eval: ")) << "printed by one rank only: " << r.output;
    EXPECT_NE(r.output.find("no sequences/ folder"), std::string::npos) << r.output;
    r = gseg::test::runCommand(mpirun + gseg + " segment nothing.bin");
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.output.find("gseg segment runs in one process"), std::string::npos) << r.output;
}
