// The map scorer (gseg/eval/map_score.hpp): hand-placed drives with known answers, bad input, and
// the same figures as ../shared/tools/score_map.py on the shared drives (the scorer, and `gseg
// eval-map` end to end). The tool's own tests: tests/tools/test_tool_eval_map.cpp.
#include <gseg/io/ros_map.hpp>
#include <gseg/map/layer_file.hpp>
#include <gseg/eval/map_score.hpp>

#include <support/child.hpp>
#include <support/output_files.hpp>
#include <support/labelled_drive.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

namespace {

namespace fs = std::filesystem;
using gseg::io::RosMap;
using gseg::map::CellOutcome;
using gseg::map::DriveTruth;
using gseg::map::MapScore;
using gseg::map::Prediction;
using gseg::map::TruthClass;

constexpr std::uint32_t kRoad = 40, kTerrain = 72, kCar = 10, kBuilding = 50, kVegetation = 70;

using gseg::test::addCell;
using gseg::test::kIdentity12;
using gseg::test::Pt;
using gseg::test::writeBytes;
using gseg::test::writeText;

/// A drive folder: one scan per entry of `frames` (frame k named k), identity poses and Tr unless given.
fs::path writeDrive(const std::string& name, const std::vector<std::vector<Pt>>& frames, const std::string& poses = "",
                    const std::string& calib = gseg::test::kIdentityCalib) {
    return gseg::test::writeLabelledDrive("map_score", name, frames, poses, calib);
}

const gseg::map::ScoreGrid kGrid{0.2, 0.0, 0.0};

TruthClass truthAt(const DriveTruth& t, long long cx, long long cy, bool* found) {
    for (const auto& c : t.cells)
        if (c.cx == cx && c.cy == cy) return *found = true, c.truth;
    return *found = false, TruthClass::Traversable;
}

/// "obstacle", "traversable" or "unknown" for cell (cx, cy).
std::string truthName(const DriveTruth& t, long long cx, long long cy) {
    bool found = false;
    const TruthClass c = truthAt(t, cx, cy, &found);
    return !found ? "unknown" : c == TruthClass::Obstacle ? "obstacle" : "traversable";
}

// --- Truth per cell: hand-placed points -------------------------------------------------------

TEST(MapScoreTruth, GroundCellsWithThreePointsAreTraversableTwoAreNotScored) {
    std::vector<Pt> pts;
    addCell(pts, 0, 0, kRoad, 3, -1.7f);
    addCell(pts, 1, 0, kRoad, 2, -1.7f);
    addCell(pts, 2, 0, kTerrain | (7u << 16), 3, -1.7f);  // an instance id in the upper bits: still terrain
    const auto drive = gseg::map::readLabelledDrive(writeDrive("three_ground", {pts}).string());
    const DriveTruth t = gseg::map::computeTruth(drive, kGrid);
    EXPECT_EQ(truthName(t, 0, 0), "traversable");
    EXPECT_EQ(truthName(t, 1, 0), "unknown");
    EXPECT_EQ(truthName(t, 2, 0), "traversable");
    EXPECT_EQ(t.cells.size(), 2u);
    EXPECT_EQ(t.groundHeight.count(DriveTruth::cellKey(1, 0)), 0u);
    EXPECT_NEAR(t.groundHeight.at(DriveTruth::cellKey(0, 0)), -1.69, 1e-6);  // the upper median of -1.70, -1.69, -1.68
}

TEST(MapScoreTruth, ObstacleBandEdgesAreStrictAndFollowTheClearance) {
    // Ground at z = 0 in each cell; two non-ground points per cell at the heights named.
    const std::vector<std::pair<float, float>> pairs = {{0.29f, 0.29f}, {0.31f, 0.32f}, {1.98f, 1.99f}, {2.01f, 2.02f}, {0.29f, 0.31f}};
    std::vector<Pt> pts;
    for (std::size_t i = 0; i < pairs.size(); ++i) {
        addCell(pts, int(3 * i), 0, kRoad, 3, 0.f, 0.f);
        pts.push_back({0.6f * float(i) + 0.1f, 0.1f, pairs[i].first, kBuilding});
        pts.push_back({0.6f * float(i) + 0.1f, 0.1f, pairs[i].second, kVegetation});
    }
    const auto drive = gseg::map::readLabelledDrive(writeDrive("band_edges", {pts}).string());
    const DriveTruth t = gseg::map::computeTruth(drive, kGrid, 2.0);
    EXPECT_EQ(truthName(t, 0, 0), "traversable");  // both below ref + 0.3
    EXPECT_EQ(truthName(t, 3, 0), "obstacle");     // both just above
    EXPECT_EQ(truthName(t, 6, 0), "obstacle");     // both just under ref + clearance
    EXPECT_EQ(truthName(t, 9, 0), "traversable");  // both above the clearance: a canopy, passable
    EXPECT_EQ(truthName(t, 12, 0), "traversable"); // only one in the band
    const DriveTruth low = gseg::map::computeTruth(drive, kGrid, 1.5);
    EXPECT_EQ(truthName(low, 6, 0), "traversable");  // 1.98 m is above a 1.5 m clearance
    EXPECT_EQ(truthName(low, 3, 0), "obstacle");
}

TEST(MapScoreTruth, CellWithoutGroundTakesTheGroundWithinOneMetreElseItsLowestPoint) {
    std::vector<Pt> pts;
    addCell(pts, 0, 0, kRoad, 3, -1.0f, 0.f);  // ground at -1.0
    // 4 cells (0.8 m) away: no ground; points 0.5 and 0.6 m above the neighbour's ground but only
    // 0.1 m above its own lowest point: an obstacle only through the 1 m neighbourhood.
    addCell(pts, 4, 0, kCar, 2, -0.5f, 0.1f);
    // 6 cells (1.2 m) away: the same points, no ground within 1 m: its lowest point is the ground.
    addCell(pts, 0, 6, kCar, 2, -0.5f, 0.1f);
    // Far away with a low point of its own: 0.4 and 0.5 above it.
    addCell(pts, 20, 20, kCar, 3, -0.9f, 0.4f);
    const auto drive = gseg::map::readLabelledDrive(writeDrive("fallback", {pts}).string());
    const DriveTruth t = gseg::map::computeTruth(drive, kGrid);
    EXPECT_EQ(truthName(t, 4, 0), "obstacle");
    EXPECT_EQ(truthName(t, 0, 6), "unknown");
    EXPECT_EQ(truthName(t, 20, 20), "obstacle");  // -0.5 and -0.1 above -0.9 (the lowest point counts as its ground)
    // With several ground cells around, the upper median of their heights.
    std::vector<Pt> more;
    addCell(more, 0, 0, kRoad, 3, -1.0f, 0.f);
    addCell(more, 2, 0, kRoad, 3, -0.2f, 0.f);
    addCell(more, 0, 2, kRoad, 3, -0.3f, 0.f);  // medians -1.0, -0.3, -0.2: the upper median is -0.3
    addCell(more, 1, 1, kCar, 2, 0.05f, 0.f);     // 0.35 above -0.3: obstacle; 0.25 above -0.2 would not be
    addCell(more, 1, 4, kCar, 2, -0.05f, 0.f);    // 0.25 above -0.3: not
    const DriveTruth t2 = gseg::map::computeTruth(gseg::map::readLabelledDrive(writeDrive("fallback_median", {more}).string()), kGrid);
    EXPECT_EQ(truthName(t2, 1, 1), "obstacle");
    EXPECT_EQ(truthName(t2, 1, 4), "unknown");
}

TEST(MapScoreTruth, IgnoredClassesAreLeftOutEverywhere) {
    std::vector<Pt> pts;
    addCell(pts, 0, 0, kRoad, 3, 0.f);
    addCell(pts, 0, 0, 0, 5, 1.0f);    // unlabelled in the band: no obstacle
    addCell(pts, 0, 0, 1, 5, 1.0f);    // outlier
    addCell(pts, 0, 0, 252, 5, 1.0f);  // a moving car
    addCell(pts, 5, 5, 259, 5, -1.0f); // a cell of moving points only: unseen
    const auto drive = gseg::map::readLabelledDrive(writeDrive("ignored", {pts}).string());
    EXPECT_EQ(drive.points.size(), 3u);
    EXPECT_EQ(drive.pointsRead, 23u);
    const DriveTruth t = gseg::map::computeTruth(drive, kGrid);
    EXPECT_EQ(truthName(t, 0, 0), "traversable");
    EXPECT_EQ(t.seen.count(DriveTruth::cellKey(5, 5)), 0u);
}

TEST(MapScoreTruth, FramesArePlacedByTheirPosesThroughTr) {
    // Tr swaps axes (velodyne x -> camera z); frame 1's camera is 2 m along camera z (forward):
    // its points land 2 m further along velodyne x: Tr^-1 P Tr.
    const std::string tr = "0 -1 0 0 0 0 -1 0 1 0 0 0";
    std::vector<Pt> f0, f1;
    addCell(f0, 0, 0, kRoad, 3, -1.7f);
    addCell(f1, 0, 0, kRoad, 3, -1.7f);
    const auto dir = writeDrive("poses", {f0, f1}, std::string(kIdentity12) + "\n1 0 0 0 0 1 0 0 0 0 1 2\n",
                                std::string("Tr: ") + tr + "\n");
    const DriveTruth t = gseg::map::computeTruth(gseg::map::readLabelledDrive(dir.string()), kGrid);
    EXPECT_EQ(truthName(t, 0, 0), "traversable");
    EXPECT_EQ(truthName(t, 10, 0), "traversable");
    EXPECT_EQ(t.cells.size(), 2u);
}

// --- Scoring: a hand-made map on a known truth ------------------------------------------------

/// Truth: a row of 10 traversable cells (cy = 0) and a row of 10 obstacle cells (cy = 3), in a
/// folder of the calling test's own (ctest runs the tests that share it at once).
DriveTruth rowTruth() {
    std::vector<Pt> pts;
    for (int cx = 0; cx < 10; ++cx) {
        addCell(pts, cx, 0, kRoad, 3, -1.7f);
        addCell(pts, cx, 3, kRoad, 3, -1.7f);
        addCell(pts, cx, 3, kBuilding, 2, -1.0f);  // 0.7 m up: in the obstacle band, and in the baseline's
    }
    return gseg::map::computeTruth(gseg::map::readLabelledDrive(writeDrive(std::string("rows_") + ::testing::UnitTest::GetInstance()->current_test_info()->name(), {pts}).string()), kGrid);
}

TEST(MapScore, FiguresOfAHandMadeMapCountEveryOutcome) {
    const DriveTruth t = rowTruth();
    ASSERT_EQ(t.cells.size(), 20u);
    RosMap m = RosMap::unknown(8, 6, 0.2, 0.0, 0.0);  // cells cx >= 8 are outside the map: unknown
    for (int cx = 0; cx < 5; ++cx) m.value(cx, 0) = RosMap::kFree;  // 5 traversable found
    m.value(5, 0) = RosMap::kOccupied;                                // 1 blocked; 6, 7 unknown; 8, 9 outside
    for (int cx = 0; cx < 3; ++cx) m.value(cx, 3) = RosMap::kOccupied;  // 3 obstacles found
    m.value(3, 3) = RosMap::kFree;  // free next to an occupied cell: unsafe, not beyond one cell
    m.value(6, 3) = RosMap::kFree;  // free with no occupied neighbour: unsafe beyond one cell
    m.value(7, 3) = 100;            // occupancy 0.61: between the thresholds, unknown
    gseg::map::CellOutcomes out;
    const MapScore s = gseg::map::scoreMap(t, m, &out);
    EXPECT_EQ(s.outcomes[int(CellOutcome::TraversableFound)], 5u);
    EXPECT_EQ(s.outcomes[int(CellOutcome::TraversableBlocked)], 1u);
    EXPECT_EQ(s.outcomes[int(CellOutcome::TraversableUnknown)], 4u);
    EXPECT_EQ(s.outcomes[int(CellOutcome::ObstacleFound)], 3u);
    EXPECT_EQ(s.outcomes[int(CellOutcome::FalseTraversable)], 1u);
    EXPECT_EQ(s.outcomes[int(CellOutcome::FalseTraversableBeyond)], 1u);
    EXPECT_EQ(s.outcomes[int(CellOutcome::ObstacleUnknown)], 5u);
    EXPECT_DOUBLE_EQ(s.travPrecision, 100.0 * 5 / 7);
    EXPECT_DOUBLE_EQ(s.travRecall, 50.0);
    EXPECT_DOUBLE_EQ(s.travF1, 2 * (100.0 * 5 / 7) * 50.0 / (100.0 * 5 / 7 + 50.0));
    EXPECT_DOUBLE_EQ(s.obstacleRecall, 30.0);
    EXPECT_DOUBLE_EQ(s.unsafe, 20.0);
    EXPECT_DOUBLE_EQ(s.unsafeBeyondCell, 10.0);
    EXPECT_EQ(s.cellsScored, 20u);
    EXPECT_EQ(s.cellsSeen, 11u);  // 6 + 5 predicted free or occupied
    ASSERT_EQ(out.size(), 20u);
    // negate 1 reads the same grey values the other way round.
    RosMap n = m;
    n.negate = 1;
    for (auto& v : n.pixels) v = std::uint8_t(255 - v);
    const MapScore sn = gseg::map::scoreMap(t, n);
    EXPECT_DOUBLE_EQ(sn.travPrecision, s.travPrecision);
    EXPECT_EQ(sn.cellsSeen, s.cellsSeen);
}

TEST(MapScore, HeightBandBaselineUsesTheFixedGroundAtMinus173) {
    const DriveTruth t = rowTruth();
    const MapScore b = gseg::map::scoreHeightBand(t);
    EXPECT_DOUBLE_EQ(b.travRecall, 100.0);
    EXPECT_DOUBLE_EQ(b.obstacleRecall, 100.0);
    EXPECT_DOUBLE_EQ(b.unsafe, 0.0);
    EXPECT_EQ(b.cellsSeen, 20u);
}

TEST(MapScore, EmptyDenominatorsGiveNaNAsScoreMapPy) {
    std::vector<Pt> pts;
    addCell(pts, 0, 0, kRoad, 3, -1.7f);
    const DriveTruth t = gseg::map::computeTruth(gseg::map::readLabelledDrive(writeDrive("nan", {pts}).string()), kGrid);
    const MapScore s = gseg::map::scoreMap(t, RosMap::unknown(2, 2, 0.2, 0, 0));
    EXPECT_TRUE(std::isnan(s.travPrecision));  // nothing called free
    EXPECT_DOUBLE_EQ(s.travRecall, 0.0);
    EXPECT_TRUE(std::isnan(s.travF1));
    EXPECT_TRUE(std::isnan(s.obstacleRecall));  // no obstacle cell
}

TEST(MapScore, ElevationErrorOverCellsWithLabelledGround) {
    std::vector<Pt> pts;
    addCell(pts, 0, 0, kRoad, 3, -1.0f, 0.f);
    addCell(pts, 1, 0, kRoad, 3, -2.0f, 0.f);
    addCell(pts, 2, 0, kRoad, 3, 0.5f, 0.f);
    addCell(pts, 3, 0, kRoad, 2, 0.5f, 0.f);  // 2 points: no ground height
    const DriveTruth t = gseg::map::computeTruth(gseg::map::readLabelledDrive(writeDrive("elevation", {pts}).string()), kGrid);
    gseg::map::LayerGrid g(5, 1, 0.2, 0.0, 0.0);
    auto& e = g.add("elevation", "m", "ground height");
    e.values = {-1.05f, -1.8f, std::nanf(""), 0.5f, 0.f};  // errors -0.05, +0.2; NaN and cells without truth skipped
    const auto err = gseg::map::elevationError(g, t);
    EXPECT_EQ(err.cells, 2u);
    EXPECT_NEAR(err.rmse, std::sqrt((0.05 * 0.05 + 0.2 * 0.2) / 2), 1e-6);
    EXPECT_DOUBLE_EQ(err.within10cm, 50.0);
    // A finer layer grid: each layer cell compares with the truth cell its centre falls in.
    gseg::map::LayerGrid fine(2, 2, 0.1, 0.0, 0.0);
    fine.add("Elevation_m", "m", "").values = {-1.f, -1.f, -1.f, -0.95f};
    const auto ef = gseg::map::elevationError(fine, t);
    EXPECT_EQ(ef.cells, 4u);
    EXPECT_DOUBLE_EQ(ef.within10cm, 100.0);
    gseg::map::LayerGrid none(1, 1, 0.2, 0, 0);
    none.add("slope", "deg", "");
    EXPECT_THROW(gseg::map::elevationError(none, t), std::runtime_error);
    gseg::map::LayerGrid away(1, 1, 0.2, 100, 100);
    away.add("elevation", "m", "").values = {0.f};
    EXPECT_THROW(gseg::map::elevationError(away, t), std::runtime_error);
}

// --- Bad input ----------------------------------------------------------------------------------

std::string readError(const fs::path& dir) {
    try {
        gseg::map::readLabelledDrive(dir.string());
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "(no error)";
}

std::vector<Pt> someGround() {
    std::vector<Pt> pts;
    addCell(pts, 0, 0, kRoad, 3, -1.7f);
    return pts;
}

TEST(MapScoreBadInput, MissingTrIsRefusedNamingCalib) {
    const auto dir = writeDrive("no_tr", {someGround()}, "", std::string("P0: ") + kIdentity12 + "\n");
    const std::string e = readError(dir);
    EXPECT_NE(e.find("calib.txt"), std::string::npos) << e;
    EXPECT_NE(e.find("Tr:"), std::string::npos) << e;
}

TEST(MapScoreBadInput, FewerPosesThanFramesIsRefusedNamingPoses) {
    const auto dir = writeDrive("few_poses", {someGround(), someGround()}, std::string(kIdentity12) + "\n");
    const std::string e = readError(dir);
    EXPECT_NE(e.find("poses.txt: 1 poses, but scan 000001.bin needs line 2"), std::string::npos) << e;
}

TEST(MapScoreBadInput, LabelCountDifferentFromTheScanIsRefusedNamingTheLabelFile) {
    const auto dir = writeDrive("label_count", {someGround()});
    const std::uint32_t two[2] = {40, 40};
    writeBytes(dir / "labels" / "000000.label", two, sizeof two);
    const std::string e = readError(dir);
    EXPECT_NE(e.find("000000.label: 2 labels for 3 points"), std::string::npos) << e;
    fs::remove(dir / "labels" / "000000.label");
    const std::string missing = readError(dir);
    EXPECT_NE(missing.find("000000.label: cannot open"), std::string::npos) << missing;
}

TEST(MapScoreBadInput, NaNPointOrPoseIsRefusedNamingTheFile) {
    std::vector<Pt> pts = someGround();
    pts.push_back({std::nanf(""), 0.f, 0.f, kRoad});
    const std::string e = readError(writeDrive("nan_point", {pts}));
    EXPECT_NE(e.find("000000.bin: point 3 has a coordinate that is not a finite number"), std::string::npos) << e;
    const std::string p = readError(writeDrive("nan_pose", {someGround()}, "1 0 0 nan 0 1 0 0 0 0 1 0\n"));
    EXPECT_NE(p.find("poses.txt:1: 'nan' is not a finite number"), std::string::npos) << p;
}

TEST(MapScoreBadInput, NoScansOrAScanNotNamedByItsFrameIsRefused) {
    const auto dir = writeDrive("no_scans", {});
    EXPECT_NE(readError(dir).find("no scans"), std::string::npos) << readError(dir);
    const auto named = writeDrive("bad_name", {someGround()});
    fs::rename(named / "velodyne" / "000000.bin", named / "velodyne" / "first.bin");
    EXPECT_NE(readError(named).find("first.bin: the scan's name is not a frame number"), std::string::npos) << readError(named);
    EXPECT_NE(readError(named / "nowhere").find("velodyne: no such folder"), std::string::npos);
}

// --- The shared drives against score_map.py -----------------------------------------------------

/// `gseg eval-map` with `args` (shell words): exit status and stdout + stderr.
gseg::test::CommandResult evalMap(const std::string& args) {
    return gseg::test::runCommand("'" + gseg::test::tool("gseg") + "' eval-map " + args + " 2>&1");
}

/// A value of score_map.py's JSON: `"section": {... "key": value ...}`.
double jsonValue(const std::string& json, const std::string& section, const std::string& key) {
    const auto s = json.find("\"" + section + "\": {");
    if (s == std::string::npos) return -1e300;
    const auto k = json.find("\"" + key + "\": ", s);
    if (k == std::string::npos) return -1e300;
    return std::strtod(json.c_str() + k + key.size() + 4, nullptr);
}

void expectSameFigures(const std::string& json, const std::string& section, const MapScore& s, const std::string& what) {
    const std::pair<const char*, double> figures[] = {{"trav_P", s.travPrecision}, {"trav_R", s.travRecall}, {"trav_F1", s.travF1},
                                                      {"obst_R", s.obstacleRecall}, {"unsafe", s.unsafe}, {"unsafe1", s.unsafeBeyondCell}};
    for (const auto& [key, mine] : figures) {
        const double theirs = jsonValue(json, section, key);
        if (std::isnan(theirs)) EXPECT_TRUE(std::isnan(mine)) << what << " " << section << "." << key;
        else EXPECT_NEAR(mine, theirs, 0.01) << what << " " << section << "." << key << "\n" << json;
    }
    EXPECT_EQ(double(s.cellsScored), jsonValue(json, section, "cells_scored")) << what << " " << section;
    EXPECT_EQ(double(s.cellsSeen), jsonValue(json, section, "cells_seen")) << what << " " << section;
}

/// The maps of a drive made in the test, each exercising other branches of the scoring.
struct TestMap {
    std::string name;
    RosMap map;
    double clearance = 2.0;
};


std::vector<TestMap> testMaps(const gseg::map::LabelledDrive& drive) {
    std::vector<TestMap> maps;
    // The grid: 0.2 m, origin not a multiple of the cell, not covering the whole drive (cells outside).
    const double res = 0.2, ox = -30.13, oy = -25.07;
    const int w = 420, h = 300;
    const DriveTruth t = gseg::map::computeTruth(drive, {res, ox, oy});
    std::mt19937 rng(19);
    {  // the height-band rule written as a map
        TestMap m{"height_band", RosMap::unknown(w, h, res, ox, oy)};
        for (int cy = 0; cy < h; ++cy)
            for (int cx = 0; cx < w; ++cx) {
                const auto it = t.seen.find(DriveTruth::cellKey(cx, cy));
                if (it != t.seen.end()) m.map.value(cx, cy) = it->second.inBand >= 2 ? RosMap::kOccupied : RosMap::kFree;
            }
        maps.push_back(std::move(m));
    }
    // The truth itself, 15 % of its cells changed at random (free, occupied, unknown, a grey value
    // between the thresholds), and grey values elsewhere.
    TestMap truthMap{"perturbed_truth", RosMap::unknown(w, h, res, ox, oy)};
    const std::uint8_t others[4] = {RosMap::kFree, RosMap::kOccupied, RosMap::kUnknown, 120};
    for (const auto& c : t.cells) {
        if (c.cx < 0 || c.cy < 0 || c.cx >= w || c.cy >= h) continue;
        std::uint8_t v = c.truth == TruthClass::Obstacle ? RosMap::kOccupied : RosMap::kFree;
        if (rng() % 100 < 15) v = others[rng() % 4];
        truthMap.map.value(int(c.cx), int(c.cy)) = v;
    }
    maps.push_back(truthMap);
    {  // seeded random grey values everywhere
        TestMap m{"random", RosMap::unknown(w, h, res, ox, oy)};
        for (auto& v : m.map.pixels) v = std::uint8_t(rng() % 256);
        m.clearance = 1.5;
        maps.push_back(std::move(m));
    }
    {  // the perturbed truth offset by 3 cells along x and 2 along y: many unsafe cells beyond one cell
        TestMap m{"offset", truthMap.map};
        m.map.originX += 3 * res, m.map.originY -= 2 * res;
        maps.push_back(std::move(m));
    }
    {  // negate 1 and other thresholds: the grey values inverted
        TestMap m{"negate", truthMap.map};
        m.map.negate = 1, m.map.occupiedThresh = 0.55, m.map.freeThresh = 0.3;
        for (auto& v : m.map.pixels) v = std::uint8_t(255 - v);
        maps.push_back(std::move(m));
    }
    return maps;
}

class SharedDrive : public ::testing::TestWithParam<const char*> {};

TEST_P(SharedDrive, SameFiguresAsScoreMapPy) {
    const std::string rel = std::string("semantickitti-drives/sequences/") + GetParam() + "/poses.txt";
    const std::string poses = gseg::test::sharedData(rel);
    if (poses.empty()) GTEST_SKIP() << gseg::test::missingDataMessage(rel);
    const std::string seq = fs::path(poses).parent_path().string();
    const std::string scorer = std::string(GSEG_SHARED_DIR) + "/tools/score_map.py";
    if (!fs::exists(scorer)) GTEST_SKIP() << gseg::test::missingDataMessage("../tools/score_map.py");
    const gseg::map::LabelledDrive drive = gseg::map::readLabelledDrive(seq);  // once for every map
    EXPECT_EQ(drive.frames, 10u);
    const fs::path dir = gseg::test::freshDir("map_score", std::string("drive_") + GetParam());
    std::vector<TestMap> maps = testMaps(drive);
    std::string args;
    double clearance = 2.0;
    // The perturbed truth again, with an elevation layer: the labelled ground height plus seeded
    // errors away from the 0.1 m border, NaN and cells off the ground, on a grid a quarter cell off.
    maps.push_back(maps[1]);
    maps.back().name = "perturbed_truth_elevation";
    const std::string layersPath = (dir / "layers.tif").string();
    {
        const RosMap& m = maps[1].map;
        const DriveTruth t = gseg::map::computeTruth(drive, gseg::map::gridOf(m));
        gseg::map::LayerGrid layers(m.width, m.height, m.resolution, m.originX + 0.05, m.originY - 0.05);
        auto& e = layers.add("elevation", "m", "ground height");
        std::mt19937 rng(5);
        const float errors[6] = {0.f, 0.03f, -0.06f, 0.15f, -0.3f, 1.f};
        for (int cy = 0; cy < layers.height(); ++cy)
            for (int cx = 0; cx < layers.width(); ++cx) {
                const auto it = t.groundHeight.find(DriveTruth::cellKey(t.grid.cellX(layers.centreX(cx)), t.grid.cellY(layers.centreY(cy))));
                const unsigned k = rng() % 8;
                if (it != t.groundHeight.end() && k < 6) e.values[layers.index(cx, cy)] = float(it->second) + errors[k];
                else if (k == 6) e.values[layers.index(cx, cy)] = -1.7f;  // over cells without labelled ground
            }
        gseg::test::writeBytes(layersPath, gseg::map::encodeLayersGeoTiff(layers));
    }
    for (TestMap& m : maps) {
        if (m.name == "perturbed_truth_elevation") args += " --elevation '" + layersPath + "'";
        gseg::test::writeRosMap((dir / m.name).string(), m.map);
        m.map = gseg::io::readRosMap((dir / (m.name + ".yaml")).string());  // what score_map.py reads
        if (m.clearance != clearance) args += " --clearance " + std::to_string(m.clearance), clearance = m.clearance;
        args += " '" + (dir / (m.name + ".yaml")).string() + "'";
    }
    // score_map.py itself (imported unchanged), the drive read once for all maps.
    const auto py = gseg::test::runCommand("python3 '" GSEG_SOURCE_DIR "/tests/score_map_batch.py' '" + scorer + "' '" + seq + "'" + args);
    ASSERT_EQ(py.status, 0) << py.output;
    std::vector<std::string> lines;
    std::istringstream in(py.output);
    for (std::string l; std::getline(in, l);)
        if (!l.empty() && l[0] == '{') lines.push_back(l);
    ASSERT_EQ(lines.size(), maps.size()) << py.output;
    bool anyBeyond = false, anyUnknown = false, anyBlocked = false;
    for (std::size_t i = 0; i < maps.size(); ++i) {
        const DriveTruth t = gseg::map::computeTruth(drive, gseg::map::gridOf(maps[i].map), maps[i].clearance);
        const MapScore s = gseg::map::scoreMap(t, maps[i].map);
        expectSameFigures(lines[i], "map", s, maps[i].name);
        expectSameFigures(lines[i], "height_band", gseg::map::scoreHeightBand(t), maps[i].name);
        anyBeyond |= s.outcomes[int(CellOutcome::FalseTraversableBeyond)] > 0;
        anyUnknown |= s.outcomes[int(CellOutcome::TraversableUnknown)] > 0 && s.outcomes[int(CellOutcome::ObstacleUnknown)] > 0;
        anyBlocked |= s.outcomes[int(CellOutcome::TraversableBlocked)] > 0;
        if (maps[i].name == "perturbed_truth_elevation") {
            const auto e = gseg::map::elevationError(gseg::map::readLayersGeoTiff(layersPath), t);
            EXPECT_NEAR(e.rmse, jsonValue(lines[i], "map", "elev_rmse"), 1e-4) << lines[i];
            EXPECT_NEAR(e.within10cm, jsonValue(lines[i], "map", "elev_within_10cm"), 0.01) << lines[i];
            EXPECT_EQ(double(e.cells), jsonValue(lines[i], "map", "elev_cells")) << lines[i];
            EXPECT_GT(e.cells, 1000u);
        }
        if (maps[i].name == "perturbed_truth") {
            EXPECT_GT(s.cellsScored, s.cellsSeen) << "cells outside the map";
        }
    }
    EXPECT_TRUE(anyBeyond && anyUnknown && anyBlocked) << "every branch exercised";
    // The tool end to end on one map: its CSV against score_map.py's figures.
    const auto tool = evalMap("'" + seq + "' '" + (dir / "perturbed_truth.yaml").string() + "' -q --elevation '" + layersPath +
                              "' --report '" + (dir / "r").string() + "'");
    ASSERT_EQ(tool.status, 0) << tool.output;
    const std::string csv = gseg::test::readText((dir / "r_map_score.csv").string());
    const auto row = csv.find("\nmap,");
    ASSERT_NE(row, std::string::npos) << csv;
    std::vector<double> values;  // the map's row after its name
    std::istringstream fields(csv.substr(row + 5, csv.find('\n', row + 1) - row - 5));
    for (std::string f; std::getline(fields, f, ',');) values.push_back(std::strtod(f.c_str(), nullptr));
    ASSERT_EQ(values.size(), 18u) << csv;
    const std::string& last = lines.back();
    const char* keys[] = {"trav_P", "trav_R", "trav_F1", "obst_R", "unsafe", "unsafe1", "cells_scored", "cells_seen"};
    for (int k = 0; k < 8; ++k) EXPECT_NEAR(values[std::size_t(k)], jsonValue(last, "map", keys[k]), 0.01) << keys[k] << "\n" << csv;
    EXPECT_NEAR(values[15], jsonValue(last, "map", "elev_rmse"), 1e-4) << csv;
    EXPECT_NEAR(values[16], jsonValue(last, "map", "elev_within_10cm"), 0.01) << csv;
    EXPECT_EQ(values[17], jsonValue(last, "map", "elev_cells")) << csv;
}

INSTANTIATE_TEST_SUITE_P(Drives, SharedDrive, ::testing::Values("00", "05", "07"));

}  // namespace
