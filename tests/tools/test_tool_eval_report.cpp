// `gseg eval`'s aggregation and reports on hand-made scores, and its configuration handling end to end.
// (The shared-data run, serial == parallel, the python cross-check and bad trees: test_tool_eval.cpp.)
#include "eval_report.hpp"

#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
using gseg::Counts;
using gseg::app::FrameRow;

namespace {

Counts counts(std::uint64_t tp, std::uint64_t fp, std::uint64_t fn) {
    Counts c;
    c.tp = tp, c.fp = fp, c.fn = fn;
    return c;
}

// Sequence 00: frames A and B; sequence 08: frame C (given first, to check the grouping order).
//   A: P 90 R 90, without vegetation P 80 R 100; every range limit P 90 R 100.
//   B: P 100 R 50; limits 10..50 m P 100 R 50, limits 60..100 m nothing (undefined, left out).
// So for 00, per limit: 10..50 m P 95 R 75, 60..100 m P 90 R 100 (B left out), hence over the ten
// limits P 92.5 ± 2.5, R 87.5 ± 12.5, and F1 of (95, 75) = 83.8235 and of (90, 100) = 94.7368,
// mean 89.2802 ± 5.4567.
std::vector<FrameRow> handMadeFrames() {
    FrameRow a, b, c;
    a.sequence = "00", a.name = "000000", a.points = 100, a.ms = 12.5;
    a.score.withVegetation = counts(90, 10, 10);
    a.score.withoutVegetation = counts(80, 20, 0);
    a.score.byRange.fill(counts(9, 1, 0));
    b.sequence = "00", b.name = "000001", b.points = 7, b.ms = 7.5;
    b.score.withVegetation = counts(1, 0, 1);
    b.score.withoutVegetation = counts(1, 0, 1);
    for (std::size_t k = 0; k < 5; ++k) b.score.byRange[k] = counts(1, 0, 1);
    c.sequence = "08", c.name = "000000", c.points = 4, c.ms = 3;
    c.score.withVegetation = c.score.withoutVegetation = counts(3, 1, 0);
    c.score.byRange.fill(counts(3, 1, 0));
    return {c, a, b};
}

std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string l; std::getline(in, l);) out.push_back(l);
    return out;
}

}  // namespace

TEST(EvalToolReport, SequenceSumsFrameMeansAndRangeMeanStd) {
    const auto seqs = gseg::app::summarise(handMadeFrames());
    ASSERT_EQ(seqs.size(), 2u);
    const auto& s = seqs[0];
    EXPECT_EQ(s.sequence, "00");
    EXPECT_EQ(s.frames, 2u);
    EXPECT_EQ(s.sum.tp, 91u);
    EXPECT_EQ(s.sum.fp, 10u);
    EXPECT_EQ(s.sum.fn, 11u);
    EXPECT_EQ(s.sumNoVeg.tp, 81u);
    EXPECT_EQ(s.sumNoVeg.fp, 20u);
    EXPECT_DOUBLE_EQ(s.p.mean, 95.0);  // mean of the frames' ratios, not the ratio of the sums
    EXPECT_DOUBLE_EQ(s.r.mean, 70.0);
    EXPECT_DOUBLE_EQ(s.pNoVeg.mean, 90.0);
    EXPECT_DOUBLE_EQ(s.rNoVeg.mean, 75.0);
    EXPECT_DOUBLE_EQ(s.ms, 10.0);
    EXPECT_DOUBLE_EQ(s.rangeP[0], 95.0);
    EXPECT_DOUBLE_EQ(s.rangeR[4], 75.0);
    EXPECT_DOUBLE_EQ(s.rangeP[5], 90.0);
    EXPECT_DOUBLE_EQ(s.rangeR[9], 100.0);
    EXPECT_DOUBLE_EQ(s.rangePStats.mean, 92.5);
    EXPECT_DOUBLE_EQ(s.rangePStats.stddev, 2.5);
    EXPECT_DOUBLE_EQ(s.rangeRStats.mean, 87.5);
    EXPECT_DOUBLE_EQ(s.rangeRStats.stddev, 12.5);
    EXPECT_NEAR(s.rangeF1Stats.mean, (14250.0 / 170 + 18000.0 / 190) / 2, 1e-9);
    EXPECT_NEAR(s.rangeF1Stats.stddev, (18000.0 / 190 - 14250.0 / 170) / 2, 1e-9);
    EXPECT_EQ(seqs[1].sequence, "08");
    EXPECT_DOUBLE_EQ(seqs[1].rangePStats.mean, 75.0);
    EXPECT_DOUBLE_EQ(seqs[1].rangePStats.stddev, 0.0);
}

TEST(EvalToolReport, FramesCsvHasOneExactRowPerFrameInInputOrder) {
    const auto rows = lines(gseg::app::framesCsv(handMadeFrames()));
    ASSERT_EQ(rows.size(), 4u);
    EXPECT_EQ(rows[0], "sequence,frame,points,TP,FP,FN,precision,recall,F1,precision_noveg,recall_noveg,ms");
    EXPECT_EQ(rows[1], "08,000000,4,3,1,0,75.0000,100.0000,85.7143,75.0000,100.0000,3.000");
    EXPECT_EQ(rows[2], "00,000000,100,90,10,10,90.0000,90.0000,90.0000,80.0000,100.0000,12.500");
    EXPECT_EQ(rows[3], "00,000001,7,1,0,1,100.0000,50.0000,66.6667,100.0000,50.0000,7.500");
}

TEST(EvalToolReport, SequencesCsvCarriesSumsMeansAndTheTenLimits) {
    const auto rows = lines(gseg::app::sequencesCsv(gseg::app::summarise(handMadeFrames())));
    ASSERT_EQ(rows.size(), 3u);
    EXPECT_EQ(rows[0].rfind("sequence,frames,TP,FP,FN,precision,recall,F1,", 0), 0u) << rows[0];
    EXPECT_NE(rows[0].find(",P<100m,R<100m"), std::string::npos);
    EXPECT_EQ(rows[1].rfind("00,2,91,10,11,95.0000,70.0000,", 0), 0u) << rows[1];
    EXPECT_NE(rows[1].find(",92.5000,2.5000,87.5000,12.5000,89.2802,5.4567,10.000,95.0000,75.0000,"),
              std::string::npos)
        << rows[1];
    EXPECT_EQ(rows[1].substr(rows[1].size() - 16), "90.0000,100.0000") << rows[1];
    // Same number of cells in the header and the rows.
    const auto cells = [](const std::string& l) { return std::count(l.begin(), l.end(), ','); };
    EXPECT_EQ(cells(rows[0]), cells(rows[1]));
    EXPECT_EQ(cells(rows[0]), cells(rows[2]));
}

TEST(EvalToolReport, MarkdownTableLikeThePapersTableII) {
    const auto rows = lines(gseg::app::markdownTable(gseg::app::summarise(handMadeFrames())));
    ASSERT_GE(rows.size(), 5u);
    EXPECT_EQ(rows[0], "| Seq. | frames | Pr. (%) | Rc. (%) | F1 (%) | Pr. no range cut | Rc. no range cut | ms/scan |");
    EXPECT_EQ(rows[2], "| 00 | 2 | 92.50 ± 2.50 | 87.50 ± 12.50 | 89.28 ± 5.46 | 95.00 | 70.00 | 10.0 |");
    EXPECT_EQ(rows[3], "| 08 | 1 | 75.00 ± 0.00 | 100.00 ± 0.00 | 85.71 ± 0.00 | 75.00 | 100.00 | 3.0 |");
    // Mean over the two sequences: P (92.5 + 75) / 2, R (87.5 + 100) / 2, F1 (89.2802 + 85.7143) / 2.
    EXPECT_EQ(rows[4], "| **mean** | 2 seq. | **83.75** | **93.75** | **87.50** | 85.00 | 85.00 | 6.5 |");
}

TEST(EvalToolReport, RowsSurviveTheBytesBetweenRanksExactly) {
    // What rank 0 gathers from the others under MPI: every count, the breakdown and the time, bit for bit.
    std::vector<FrameRow> rows = handMadeFrames();
    rows[0].ms = 0.1 + 0.2;  // not representable in decimal
    rows[1].breakdown.falseByClass = {{10, 5}, {50, 7}};
    rows[1].breakdown.missedByClass = {{72, 123456789012345ull}};
    rows[1].breakdown.falseByHeight[3] = 4, rows[1].breakdown.falseByRange[4] = 2, rows[1].breakdown.missedByRange[0] = 9;
    rows[1].breakdown.falseGround = 12, rows[1].breakdown.missedGround = 123456789012345ull, rows[1].breakdown.trueGround = 1;
    rows[2].score.points = 4, rows[2].score.byRange[9].tn = 99;
    gseg::io::ByteWriter out;
    for (const FrameRow& r : rows) gseg::app::writeRow(out, r);
    gseg::io::ByteReader in(out.bytes());
    std::vector<FrameRow> back;
    while (!in.done()) back.push_back(gseg::app::readRow(in));
    ASSERT_EQ(back.size(), rows.size());
    EXPECT_EQ(back[0].ms, rows[0].ms);
    EXPECT_EQ(back[1].breakdown.missedByClass, rows[1].breakdown.missedByClass);
    EXPECT_EQ(back[2].score.byRange[9].tn, 99u);
    const auto seqs = gseg::app::summarise(rows), seqsBack = gseg::app::summarise(back);
    EXPECT_EQ(gseg::app::framesCsv(back), gseg::app::framesCsv(rows));
    EXPECT_EQ(gseg::app::sequencesCsv(seqsBack), gseg::app::sequencesCsv(seqs));
    EXPECT_EQ(gseg::app::breakdownCsv(back, seqsBack), gseg::app::breakdownCsv(rows, seqs));
    // A message cut short is an error, not a made-up frame.
    const std::string cut = out.bytes().substr(0, out.bytes().size() - 3);
    gseg::io::ByteReader short_(cut);
    EXPECT_THROW(for (int i = 0; i < 3; ++i) gseg::app::readRow(short_), std::runtime_error);
}

TEST(EvalToolReport, UndefinedFiguresShowAsNotAvailable) {
    FrameRow f;  // nothing predicted ground, no ground: every ratio undefined
    f.sequence = "03", f.name = "000000";
    const auto seqs = gseg::app::summarise({f});
    ASSERT_EQ(seqs.size(), 1u);
    EXPECT_TRUE(std::isnan(seqs[0].rangePStats.mean));
    EXPECT_NE(gseg::app::markdownTable(seqs).find("| 03 | 1 | n/a | n/a | n/a | n/a | n/a |"), std::string::npos);
}

namespace {

using gseg::test::runGseg;

std::string slurp(const fs::path& p) { return gseg::test::readText(p.string()); }

std::string withoutLastColumn(const std::string& csv) {
    std::string out;
    for (const auto& l : lines(csv)) out += l.substr(0, l.rfind(',')) + "\n";
    return out;
}

const fs::path kDir = fs::path(GSEG_BINARY_DIR) / "tests" / "tool_eval";

}  // namespace

// --help says: without --config, eval uses the one default (gseg::mrpt::defaultConfig(): the library
// defaults with distToGround: auto), exactly config/auto_height.yaml; config/kitti_hdl64.yaml fixes 1.723 m.
TEST(EvalToolConfig, DefaultEqualsAutoHeightYamlAndKittiHdl64Runs) {
    const std::string root = gseg::test::sharedData("semantickitti");
    if (root.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti");
    const fs::path dir = kDir / "config";
    fs::remove_all(dir);
    fs::create_directories(dir);
    int status = -1;
    std::string out = runGseg("eval", "'" + root + "' --threads 2 --report '" + (dir / "default").string() + "'", status);
    ASSERT_EQ(status, 0) << out;
    EXPECT_NE(out.find("4 frames evaluated, 3 skipped, 0 without a height estimate"), std::string::npos) << out;
    EXPECT_NE(out.find("distToGround: auto, estimated per scan (fallback 1.723 m) [the default: no configuration file]"),
              std::string::npos) << out;
    out = runGseg("eval", "'" + root + "' --threads 2 --config '" GSEG_SOURCE_DIR "/config/auto_height.yaml' --report '" +
                      (dir / "yaml").string() + "'",
                  status);
    ASSERT_EQ(status, 0) << out;
    const std::string def = withoutLastColumn(slurp(dir / "default_frames.csv"));
    EXPECT_EQ(std::count(def.begin(), def.end(), '\n'), 5);
    EXPECT_EQ(def, withoutLastColumn(slurp(dir / "yaml_frames.csv")));

    // A fixed height (the KITTI sensor is ~1.73 m up: similar scores), said in the summary.
    out = runGseg("eval", "'" + root + "' --threads 2 --config '" GSEG_SOURCE_DIR "/config/kitti_hdl64.yaml'", status);
    ASSERT_EQ(status, 0) << out;
    EXPECT_NE(out.find("4 frames evaluated, 3 skipped\n"), std::string::npos) << out;
    EXPECT_NE(out.find("distToGround: 1.723 m, fixed [" GSEG_SOURCE_DIR "/config/kitti_hdl64.yaml]"), std::string::npos) << out;
    EXPECT_NE(out.find("| **mean** | 2 seq. |"), std::string::npos) << out;

    // A bad config: one line naming the file, nothing written.
    std::ofstream(dir / "bad.yaml") << "cellSizeX: -1\n";
    out = runGseg("eval", "'" + root + "' --config '" + (dir / "bad.yaml").string() + "' --report '" +
                      (dir / "bad").string() + "'",
                  status);
    EXPECT_EQ(status, 1) << out;
    EXPECT_NE(out.find("gseg eval: "), std::string::npos) << out;
    EXPECT_FALSE(fs::exists(dir / "bad_frames.csv"));
}

TEST(EvalToolConfig, EveryFrameSkippedIsAnError) {
    const fs::path seq = kDir / "allbad/sequences/02";
    fs::remove_all(kDir / "allbad");
    fs::create_directories(seq / "velodyne");
    fs::create_directories(seq / "labels");
    const std::vector<float> pts(4 * 50, 1.0f);
    std::ofstream(seq / "velodyne/000000.bin", std::ios::binary)
        .write(reinterpret_cast<const char*>(pts.data()), std::streamsize(pts.size() * sizeof(float)));
    std::ofstream(seq / "labels/000000.label", std::ios::binary).write("\0\0\0\0", 4);  // 1 label for 50 points
    int status = -1;
    const std::string out =
        runGseg("eval", "'" + (kDir / "allbad").string() + "' --report '" + (kDir / "allbad/r").string() + "'", status);
    EXPECT_EQ(status, 1) << out;
    EXPECT_NE(out.find("skipped 02/000000"), std::string::npos) << out;
    EXPECT_NE(out.find("0 frames evaluated, 1 skipped"), std::string::npos) << out;
    EXPECT_NE(out.find("gseg eval: no frame could be scored"), std::string::npos) << out;
    EXPECT_FALSE(fs::exists(kDir / "allbad/r_frames.csv"));
}

namespace {

/// The number after `key` in `text` (e.g. key "P=" in "P=96.848+-0.891"), NaN if absent.
double numberAfter(const std::string& text, const std::string& key, std::size_t from = 0) {
    const std::size_t at = text.find(key, from);
    return at == std::string::npos ? NAN : std::stod(text.substr(at + key.size()));
}

std::vector<std::string> cells(const std::string& line) {
    std::vector<std::string> out;
    std::istringstream in(line);
    for (std::string c; std::getline(in, c, ',');) out.push_back(c);
    return out;
}

}  // namespace

// One-frame sequence 08: the sequence figures (without vegetation, range-limited mean ± std) equal
// what the independent python scorer prints for the same predictions (it rounds to 3 decimals).
TEST(EvalToolConfig, SequenceFiguresMatchTheIndependentScorer) {
    const std::string scan = gseg::test::sharedData("semantickitti/sequences/08/velodyne/000000.bin");
    const std::string label = gseg::test::sharedData("semantickitti/sequences/08/labels/000000.label");
    if (scan.empty() || label.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/08");
    if (std::system("python3 --version > /dev/null 2>&1") != 0) GTEST_SKIP() << "python3 is not installed";
    const fs::path dir = kDir / "scorer";
    fs::remove_all(dir);
    int status = -1;
    const std::string out = runGseg("eval", "'" + gseg::test::sharedData("semantickitti") + "' --sequences 08 --report '" +
                                        (dir / "r").string() + "' --labels-out-dir '" + (dir / "pred").string() + "'",
                                    status);
    ASSERT_EQ(status, 0) << out;
    const auto py = gseg::test::runCommand("python3 '" GSEG_SHARED_DIR "/tools/eval_labels.py' '" + scan + "' '" +
                                           label + "' '" + (dir / "pred/08_000000.pred").string() + "'");
    ASSERT_EQ(py.status, 0) << py.output;
    const auto rows = lines(slurp(dir / "r_sequences.csv"));
    ASSERT_EQ(rows.size(), 2u);
    const auto head = cells(rows[0]), row = cells(rows[1]);
    ASSERT_EQ(head.size(), row.size());
    const auto col = [&](const std::string& name) {
        const auto it = std::find(head.begin(), head.end(), name);
        return it == head.end() ? NAN : std::stod(row[std::size_t(it - head.begin())]);
    };
    const std::size_t noVeg = py.output.find("W/O VEG"), dist = py.output.find("DIST<d");
    ASSERT_NE(noVeg, std::string::npos) << py.output;
    ASSERT_NE(dist, std::string::npos) << py.output;
    EXPECT_NEAR(col("precision"), numberAfter(py.output, "P="), 6e-4);
    EXPECT_NEAR(col("recall"), numberAfter(py.output, "R="), 6e-4);
    EXPECT_NEAR(col("precision_noveg"), numberAfter(py.output, "P=", noVeg), 6e-4);
    EXPECT_NEAR(col("recall_noveg"), numberAfter(py.output, "R=", noVeg), 6e-4);
    EXPECT_NEAR(col("range_precision_mean"), numberAfter(py.output, "P=", dist), 6e-4);
    EXPECT_NEAR(col("range_precision_std"), numberAfter(py.output, "+-", dist), 6e-4);
    EXPECT_NEAR(col("range_recall_mean"), numberAfter(py.output, "R=", dist), 6e-4);
    EXPECT_NEAR(col("range_recall_std"), numberAfter(py.output, "+-", py.output.find("R=", dist)), 6e-4);
}
