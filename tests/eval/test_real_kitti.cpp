// Real SemanticKITTI scans from ../shared/data: accuracy under the benchmark protocol, and the
// protocol itself against hand-computed counts and the independent scorer.
#include <gseg/ground_segmenter.hpp>
#include <gseg/io/kitti.hpp>
#include <gseg/eval/kitti_rings.hpp>
#include <gseg/eval/metrics.hpp>
#include <gseg/sensor_height.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace {

struct Frame {
    const char* scan;
    const char* label;
};
const Frame kFrames[] = {
    {"semantickitti/sequences/00/velodyne/000000.bin", "semantickitti/sequences/00/labels/000000.label"},
    {"semantickitti/sequences/00/velodyne/000001.bin", "semantickitti/sequences/00/labels/000001.label"},
    {"semantickitti/sequences/00/velodyne/000002.bin", "semantickitti/sequences/00/labels/000002.label"},
    {"semantickitti/sequences/08/velodyne/000000.bin", "semantickitti/sequences/08/labels/000000.label"},
};

// Every labelled scan of both shared folders, with floors 1 point under what this version measures
// (config/kitti_hdl64.yaml = the library defaults; `gseg eval` gives the same figures). Issue #20
// raised them where a frame gained and kept them where it lost up to 0.9 point (09/000009 and
// 10/000000 recall -0.1 / -0.2, 10/000009 -0.9, drive 00/000007 -0.7, 07 precision -0.1 / -0.2);
// the bridges (#20) raised 09/000000 and 10/000000, the only frames that gained 0.2 point or more.
struct Measured {
    const char* root;
    const char* seq;
    const char* frame;
    double p, r;  ///< [%] measured precision and recall
};
const Measured kAll[] = {
    {"semantickitti", "00", "000000", 99.4, 94.4},       {"semantickitti", "00", "000001", 99.3, 94.0},
    {"semantickitti", "00", "000002", 99.1, 94.5},       {"semantickitti", "08", "000000", 98.2, 92.5},
    {"semantickitti-extra", "02", "000000", 99.1, 95.0}, {"semantickitti-extra", "02", "000009", 98.4, 92.7},
    {"semantickitti-extra", "03", "000000", 97.1, 92.3}, {"semantickitti-extra", "03", "000009", 97.3, 88.6},
    {"semantickitti-extra", "04", "000000", 99.6, 93.3}, {"semantickitti-extra", "04", "000009", 99.2, 95.5},
    {"semantickitti-extra", "05", "000000", 96.4, 97.3}, {"semantickitti-extra", "05", "000009", 96.3, 95.4},
    {"semantickitti-extra", "06", "000000", 99.5, 94.7}, {"semantickitti-extra", "06", "000009", 99.0, 94.0},
    {"semantickitti-extra", "07", "000000", 92.4, 98.2}, {"semantickitti-extra", "07", "000009", 91.8, 98.5},
    {"semantickitti-extra", "09", "000000", 99.0, 92.1}, {"semantickitti-extra", "09", "000009", 98.9, 91.7},
    {"semantickitti-extra", "10", "000000", 99.9, 84.4}, {"semantickitti-extra", "10", "000009", 99.9, 85.2},
};

// The 30 consecutive frames of ../shared/data/semantickitti-drives (sequences 00 urban, 05
// residential, 07 dense urban: frames 0-9 each), measured likewise (issue #20).
const Measured kDrives[] = {
    {"semantickitti-drives", "00", "000000", 99.4, 94.4},
    {"semantickitti-drives", "00", "000001", 99.3, 94.0},
    {"semantickitti-drives", "00", "000002", 99.1, 94.5},
    {"semantickitti-drives", "00", "000003", 99.0, 94.0},
    {"semantickitti-drives", "00", "000004", 98.6, 94.3},
    {"semantickitti-drives", "00", "000005", 99.1, 94.4},
    {"semantickitti-drives", "00", "000006", 98.4, 92.9},
    {"semantickitti-drives", "00", "000007", 98.7, 94.5},
    {"semantickitti-drives", "00", "000008", 98.5, 94.5},
    {"semantickitti-drives", "00", "000009", 98.1, 95.3},
    {"semantickitti-drives", "05", "000000", 96.4, 97.3},
    {"semantickitti-drives", "05", "000001", 95.7, 97.0},
    {"semantickitti-drives", "05", "000002", 95.7, 95.8},
    {"semantickitti-drives", "05", "000003", 95.6, 95.4},
    {"semantickitti-drives", "05", "000004", 95.6, 95.4},
    {"semantickitti-drives", "05", "000005", 95.6, 95.5},
    {"semantickitti-drives", "05", "000006", 95.6, 95.6},
    {"semantickitti-drives", "05", "000007", 95.6, 95.6},
    {"semantickitti-drives", "05", "000008", 96.0, 95.6},
    {"semantickitti-drives", "05", "000009", 96.3, 95.4},
    {"semantickitti-drives", "07", "000000", 92.4, 98.2},
    {"semantickitti-drives", "07", "000001", 91.9, 98.3},
    {"semantickitti-drives", "07", "000002", 91.4, 98.1},
    {"semantickitti-drives", "07", "000003", 91.6, 98.0},
    {"semantickitti-drives", "07", "000004", 92.1, 98.3},
    {"semantickitti-drives", "07", "000005", 92.4, 98.6},
    {"semantickitti-drives", "07", "000006", 91.5, 98.3},
    {"semantickitti-drives", "07", "000007", 91.2, 98.3},
    {"semantickitti-drives", "07", "000008", 91.8, 98.2},
    {"semantickitti-drives", "07", "000009", 91.8, 98.5},
};

gseg::Params kittiParams() { return gseg::Params(); }  // = config/kitti_hdl64.yaml

struct Scored {
    double p, r, f1;
};

/// A sparser sensor's scan taken out of each frame (gseg::eval::kittiThinned): every `ring`-th ring,
/// every `point`-th point along the rings (`gseg eval --ring-step --point-step`).
struct Thinning {
    unsigned ring = 1, point = 1;
};

/// Scores every frame of `frames` (default kAll) with `segment`, thinned by `thin`; false (and a
/// skip message) if a folder is absent.
template <typename Segment, std::size_t N = sizeof(kAll) / sizeof(kAll[0])>
bool scoreAll(Segment&& segment, std::vector<Scored>& out, std::string& missing, const Measured (&frames)[N] = kAll,
              Thinning thin = {}) {
    for (const Measured& m : frames) {
        const std::string base = std::string(m.root) + "/sequences/" + m.seq;
        const std::string scan = gseg::test::sharedData(base + "/velodyne/" + m.frame + ".bin");
        const std::string label = gseg::test::sharedData(base + "/labels/" + m.frame + ".label");
        if (scan.empty() || label.empty()) {
            missing = gseg::test::missingDataMessage(base + "/velodyne/" + m.frame + ".bin");
            return false;
        }
        auto pts = gseg::io::readKittiBin(scan);
        auto labels = gseg::io::readKittiLabels(label, pts.size() / 4);
        gseg::eval::thinKittiScan(pts, labels, thin.ring, thin.point);
        const gseg::PointCloudView cloud(pts.data(), pts.size() / 4, 16);
        const gseg::Result r = segment(cloud);
        EXPECT_EQ(r.labels.size(), cloud.size()) << "every point labelled";
        const auto s = gseg::scoreFrame(cloud, labels, r.labels).withVegetation;
        out.push_back({s.precision(), s.recall(), s.f1()});
    }
    return true;
}

}  // namespace

/// Checks every frame against its floor (1 point under what was measured) and returns the means
/// (P, R, F1) over the frames; `what` names them in the printout, e.g. "drives ".
/// Means (P, R, F1) over the frames.
Scored meanOf(const std::vector<Scored>& got) {
    Scored sum{0, 0, 0};
    for (const Scored& s : got) sum.p += s.p, sum.r += s.r, sum.f1 += s.f1;
    const double n = double(got.size());
    return {sum.p / n, sum.r / n, sum.f1 / n};
}

template <std::size_t N>
Scored checkFloors(const std::vector<Scored>& got, const Measured (&frames)[N], const char* what) {
    for (std::size_t i = 0; i < got.size(); ++i) {
        const Measured& m = frames[i];
        std::printf("%s%s/%s: P %.2f R %.2f F1 %.2f\n", what, m.seq, m.frame, got[i].p, got[i].r, got[i].f1);
        EXPECT_GE(got[i].p, m.p - 1.0) << m.seq << "/" << m.frame;
        EXPECT_GE(got[i].r, m.r - 1.0) << m.seq << "/" << m.frame;
    }
    return meanOf(got);
}

TEST(Metrics, HandComputedCounts) {
    // z values pick the vegetation rule: -1.2975 is the boundary (z < thr is ground).
    const std::vector<float> xyz = {
        1, 0, -1.7,   // 0 road, predicted ground            -> TP
        1, 0, -1.7,   // 1 road, predicted non-ground        -> FN
        1, 0, 0.5,    // 2 car (10), predicted ground        -> FP
        1, 0, -1.3,   // 3 vegetation below thr, predicted   -> TP (low vegetation is ground)
        1, 0, -1.29,  // 4 vegetation just above thr, pred. -> FP (float(-1.2975) itself lies below it)
        1, 0, -1.7,   // 5 unlabelled (0), predicted ground  -> TP, never FN
        1, 0, -1.7,   // 6 outlier (1), predicted non-ground -> nothing
        15, 0, -1.7,  // 7 terrain at 15 m, predicted        -> TP (only from the 20 m limit on)
        10, 0, -1.7,  // 8 sidewalk exactly 10 m, not pred.  -> FN (belongs to the 20 m limit)
    };
    const std::vector<std::uint32_t> labels = {40, 40 | (7u << 16), 10, 70, 70, 0, 1, 72, 48};
    const std::vector<std::uint8_t> pred = {1, 0, 1, 1, 1, 1, 0, 1, 0};
    const auto s = gseg::scoreFrame(gseg::PointCloudView(xyz.data(), 9), labels, pred);
    EXPECT_EQ(s.withVegetation.tp, 4u);
    EXPECT_EQ(s.withVegetation.fp, 2u);
    EXPECT_EQ(s.withVegetation.fn, 2u);
    EXPECT_EQ(s.withVegetation.tn, 1u);
    EXPECT_DOUBLE_EQ(s.withVegetation.precision(), 100.0 * 4 / 6);
    // Without vegetation: vegetation is don't-care (predicted: counted as TP like unlabelled).
    EXPECT_EQ(s.withoutVegetation.tp, 5u);  // 0, 7 (ground) + 3, 4 (vegetation) + 5 (unlabelled)
    EXPECT_EQ(s.withoutVegetation.fp, 1u);  // the car
    EXPECT_EQ(s.withoutVegetation.fn, 2u);
    // Range limit 10 m: points 0-6 (range 1 m); 7 and 8 excluded.
    EXPECT_EQ(s.byRange[0].tp, 3u);
    EXPECT_EQ(s.byRange[0].fn, 1u);
    EXPECT_EQ(s.byRange[1].tp, 4u);  // 20 m: + point 7
    EXPECT_EQ(s.byRange[1].fn, 2u);  //        + point 8
    EXPECT_TRUE(std::isnan(gseg::Counts().precision()));
    EXPECT_THROW(gseg::scoreFrame(gseg::PointCloudView(xyz.data(), 9), labels, {1, 0}), std::invalid_argument);
    const auto ms = gseg::meanStd({1.0, 3.0, std::nan("")});
    EXPECT_DOUBLE_EQ(ms.mean, 2.0);
    EXPECT_DOUBLE_EQ(ms.stddev, 1.0);
    EXPECT_EQ(ms.count, 2u);
}

TEST(RealKitti, PrecisionAndRecallOnBothSharedFolders) {
    gseg::GroundSegmenter seg(kittiParams());
    std::vector<Scored> got;
    std::string missing;
    if (!scoreAll([&](const gseg::PointCloudView& c) { return seg.segment(c, false); }, got, missing))
        GTEST_SKIP() << missing;
    const Scored mean = checkFloors(got, kAll, "");
    std::printf("mean over %zu scans: P %.2f R %.2f F1 %.2f\n", got.size(), mean.p, mean.r, mean.f1);
    // Issue #8's bar (the authors' code: P 97.3 / F1 94.4, Patchwork++ 95.9 / 94.9); measured
    // P 97.88 / R 92.90 / F1 95.25.
    EXPECT_GE(mean.p, 97.5);
    EXPECT_GE(mean.f1, 95.0);
}

TEST(RealKitti, AutoHeightOnBothSharedFoldersNeverRefusesAndStaysPrecise) {
    gseg::AutoHeightSegmenter seg(kittiParams());  // config/auto_height.yaml
    std::vector<Scored> got;
    std::string missing;
    std::size_t estimated = 0;
    const auto run = [&](const gseg::PointCloudView& c) {
        gseg::AutoHeightResult r = seg.segment(c, false);
        estimated += r.decision.source == gseg::HeightDecision::Source::Estimated;
        EXPECT_NEAR(r.decision.height, 1.76, 0.15) << r.decision.describe();  // measured 1.69-1.89
        return std::move(r.result);
    };
    if (!scoreAll(run, got, missing)) GTEST_SKIP() << missing;
    const Scored mean = meanOf(got);
    std::printf("auto height, mean over %zu scans: P %.2f F1 %.2f\n", got.size(), mean.p, mean.f1);
    EXPECT_EQ(estimated, got.size());
    EXPECT_GE(mean.p, 97.0);  // measured 97.78
    EXPECT_GE(mean.f1, 94.5);  // measured 95.25
}

TEST(RealKitti, PrecisionAndRecallOnTheThirtyDriveFrames) {
    gseg::GroundSegmenter seg(kittiParams());
    std::vector<Scored> got;
    std::string missing;
    if (!scoreAll([&](const gseg::PointCloudView& c) { return seg.segment(c, false); }, got, missing, kDrives))
        GTEST_SKIP() << missing;
    const Scored mean = checkFloors(got, kDrives, "drives ");
    std::printf("mean over %zu drive frames: P %.2f R %.2f F1 %.2f\n", got.size(), mean.p, mean.r, mean.f1);
    EXPECT_GE(mean.p, 95.0);  // measured 95.36 (dense urban 07: 91.2-92.3)
    EXPECT_GE(mean.f1, 95.3);  // measured 95.59
}

TEST(RealKitti, AutoHeightOnTheThirtyDriveFramesNeverRefusesAndStaysPrecise) {
    gseg::AutoHeightSegmenter seg(kittiParams());  // config/auto_height.yaml
    std::vector<Scored> got;
    std::string missing;
    std::size_t estimated = 0;
    const auto run = [&](const gseg::PointCloudView& c) {
        gseg::AutoHeightResult r = seg.segment(c, false);
        estimated += r.decision.source == gseg::HeightDecision::Source::Estimated;
        return std::move(r.result);
    };
    if (!scoreAll(run, got, missing, kDrives)) GTEST_SKIP() << missing;
    const Scored mean = meanOf(got);
    std::printf("auto height, mean over %zu drive frames: P %.2f F1 %.2f\n", got.size(), mean.p, mean.f1);
    EXPECT_EQ(estimated, got.size());
    EXPECT_GE(mean.p, 95.0);  // measured 95.45
    EXPECT_GE(mean.f1, 95.3);  // measured 95.60
}

// Issue #20's sparse rings, on real scans: the 50 labelled frames thinned to a sparser sensor's
// (every 2nd ring: a 32-beam sensor's vertical spacing; every 4th: 16 rings, about an HDL-32E's
// 1.33 deg; every 2nd point along the rings), scored under the benchmark protocol like the full
// scans. Means over frames, floors 0.3 points under what this version measures (`gseg eval ROOT
// --ring-step N --point-step M`, README "Sparser sensors").
TEST(RealKitti, SparserSensorsCutOutOfTheSharedScansKeepPrecisionAndRecall) {
    struct Case {
        Thinning thin;
        const char* name;
        Scored scans, drives;  // measured means (P, R, F1)
    };
    const Case cases[] = {
        {{2, 1}, "every 2nd ring", {97.98, 91.79, 94.67}, {95.42, 95.77, 95.54}},
        {{4, 1}, "every 4th ring", {97.30, 90.56, 93.68}, {93.97, 95.24, 94.52}},
        {{1, 2}, "every 2nd point", {97.95, 92.59, 95.10}, {95.45, 95.92, 95.63}},
    };
    gseg::GroundSegmenter seg(kittiParams());
    const auto run = [&](const gseg::PointCloudView& c) { return seg.segment(c, false); };
    for (const Case& c : cases) {
        std::vector<Scored> scans, drives;
        std::string missing;
        if (!scoreAll(run, scans, missing, kAll, c.thin) || !scoreAll(run, drives, missing, kDrives, c.thin))
            GTEST_SKIP() << missing;
        const Scored a = meanOf(scans), b = meanOf(drives);
        std::printf("%s: 20 scans P %.2f R %.2f F1 %.2f, drives P %.2f R %.2f F1 %.2f\n", c.name, a.p, a.r, a.f1, b.p,
                    b.r, b.f1);
        EXPECT_GE(a.p, c.scans.p - 0.3) << c.name;
        EXPECT_GE(a.r, c.scans.r - 0.3) << c.name;
        EXPECT_GE(b.p, c.drives.p - 0.3) << c.name;
        EXPECT_GE(b.r, c.drives.r - 0.3) << c.name;
    }
}

TEST(RealKitti, ScoresMatchTheIndependentScorer) {
    const std::string scanPath = gseg::test::sharedData(kFrames[3].scan);
    const std::string labelPath = gseg::test::sharedData(kFrames[3].label);
    const std::string scorer = std::string(GSEG_SHARED_DIR) + "/tools/eval_labels.py";
    if (scanPath.empty() || labelPath.empty()) GTEST_SKIP() << gseg::test::missingDataMessage(kFrames[3].scan);
    if (std::system("python3 --version > /dev/null 2>&1") != 0) GTEST_SKIP() << "python3 is not installed";
    const auto pts = gseg::io::readKittiBin(scanPath);
    const gseg::PointCloudView cloud(pts.data(), pts.size() / 4, 16);
    const auto labels = gseg::io::readKittiLabels(labelPath, cloud.size());
    const auto r = gseg::GroundSegmenter(kittiParams()).segment(cloud, false);
    const std::string pred = std::string(GSEG_BINARY_DIR) + "/tests/real_kitti_pred.bin";
    gseg::io::writeFileAtomic(pred, r.labels.data(), r.labels.size());
    const std::string cmd = "python3 '" + scorer + "' '" + scanPath + "' '" + labelPath + "' '" + pred + "'";
    const auto scored = gseg::test::runCommand(cmd);
    const std::string& out = scored.output;
    ASSERT_EQ(scored.status, 0) << out;
    const auto s = gseg::scoreFrame(cloud, labels, r.labels);
    auto expectCounts = [&](const char* tag, const gseg::Counts& c) {
        const std::string want = " TP=" + std::to_string(c.tp) + " FP=" + std::to_string(c.fp) +
                                 " FN=" + std::to_string(c.fn) + " TN=" + std::to_string(c.tn);
        const auto line = out.find(tag);
        ASSERT_NE(line, std::string::npos) << out;
        EXPECT_NE(out.substr(line, out.find('\n', line) - line).find(want), std::string::npos)
            << tag << " expected" << want << " in:\n" << out;
    };
    expectCounts("W/ VEG :", s.withVegetation);
    expectCounts("W/O VEG:", s.withoutVegetation);
}
