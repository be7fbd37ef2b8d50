// The contract of GroundSegmenter: one label per point, determinism, views, bad input.
#include <gseg/ground_segmenter.hpp>
#include <support/lidar_sim.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <thread>

namespace {

gseg::test::SimScan busyScene(std::uint32_t seed = 7) {
    gseg::test::Scene s;
    s.addRamp(1.73, 10, 12, gseg::test::Truth::Ground);
    s.addBox(5, -3, -1.73, 7, -1, -0.2);
    s.addBox(-8, 2, -1.73, -6, 5, 1.0);
    s.addBox(-20, -30, -1.73, 20, -29, 2.0);
    gseg::test::Lidar l;
    l.seed = seed;
    return simulate(s, l);
}

gseg::PointCloudView view(const gseg::test::SimScan& s) { return {s.xyz.data(), s.size()}; }

}  // namespace

TEST(Contract, OneLabelPerPointAndCountsAddUp) {
    const auto scan = busyScene();
    gseg::GroundSegmenter seg;
    const gseg::Result r = seg.segment(view(scan));
    ASSERT_EQ(r.labels.size(), scan.size());
    std::size_t ground = 0;
    for (std::uint8_t l : r.labels) {
        ASSERT_LE(l, 1);
        ground += l;
    }
    EXPECT_EQ(ground, r.numGround);
    EXPECT_EQ(r.numGround + r.numNonGround, scan.size());
    EXPECT_EQ(r.phase1.inputPoints, scan.size());
    EXPECT_EQ(r.phase2.inputPoints, r.phase1.groundPoints);
    EXPECT_EQ(r.phase2.groundPoints, r.numGround);
    std::size_t cellPoints = 0;
    for (const auto& c : r.phase1.cells) cellPoints += c.numPoints;
    EXPECT_EQ(cellPoints, scan.size());  // every point sits in exactly one Phase I cell
}

TEST(Contract, SameLabelsOnEveryCallAndWithoutHistory) {
    const auto a = busyScene(7), b = busyScene(8);
    gseg::GroundSegmenter reused;
    const auto first = reused.segment(view(a)).labels;
    reused.segment(view(b));  // something else in between
    EXPECT_EQ(reused.segment(view(a)).labels, first);
    gseg::GroundSegmenter fresh;
    EXPECT_EQ(fresh.segment(view(a)).labels, first);
}

TEST(Contract, SameLabelsFromTwoThreads) {
    const auto scan = busyScene();
    const auto expected = gseg::GroundSegmenter().segment(view(scan)).labels;
    std::vector<std::uint8_t> out[2];
    std::thread t0([&] { out[0] = gseg::GroundSegmenter().segment(view(scan)).labels; });
    std::thread t1([&] { out[1] = gseg::GroundSegmenter().segment(view(scan)).labels; });
    t0.join();
    t1.join();
    EXPECT_EQ(out[0], expected);
    EXPECT_EQ(out[1], expected);
}

TEST(Contract, StridedViewOverXyziGivesTheSameLabels) {
    const auto scan = busyScene();
    std::vector<float> xyzi;
    for (std::size_t i = 0; i < scan.size(); ++i)
        xyzi.insert(xyzi.end(), {scan.xyz[3 * i], scan.xyz[3 * i + 1], scan.xyz[3 * i + 2], 42.f});
    gseg::GroundSegmenter seg;
    EXPECT_EQ(seg.segment(gseg::PointCloudView(xyzi.data(), scan.size(), 16)).labels, seg.segment(view(scan)).labels);
}

TEST(Contract, DiagnosticsOffGivesTheSameLabels) {
    const auto scan = busyScene();
    gseg::GroundSegmenter seg;
    const auto with = seg.segment(view(scan), true);
    const auto without = seg.segment(view(scan), false);
    EXPECT_EQ(with.labels, without.labels);
    EXPECT_FALSE(with.phase1.cells.empty());
    EXPECT_TRUE(without.phase1.cells.empty());
}

TEST(Contract, EmptyCloudThrows) {
    gseg::GroundSegmenter seg;
    EXPECT_THROW(seg.segment(gseg::PointCloudView()), std::invalid_argument);
}

TEST(Contract, NonFinitePointsAreNonGroundCountedAndDoNotDisturbTheRest) {
    // A driver's no-return points (NaN) and infinities spread through a real-looking scan.
    const auto scan = busyScene();
    const gseg::Result clean = gseg::GroundSegmenter().segment(view(scan));
    std::vector<float> xyz = scan.xyz;
    std::vector<std::size_t> bad;
    for (std::size_t i = 0; i < scan.size(); i += 97) {
        const float v = i % 3 == 0 ? std::numeric_limits<float>::quiet_NaN()
                                   : (i % 3 == 1 ? std::numeric_limits<float>::infinity() : -std::numeric_limits<float>::infinity());
        xyz[3 * i + i % 3] = v;
        bad.push_back(i);
    }
    const gseg::Result r = gseg::GroundSegmenter().segment(gseg::PointCloudView(xyz.data(), scan.size()));
    ASSERT_EQ(r.labels.size(), scan.size());
    EXPECT_EQ(r.numNonFinite, bad.size());
    for (std::size_t i : bad) EXPECT_EQ(r.labels[i], 0) << i;
    EXPECT_EQ(r.numGround + r.numNonGround, scan.size());
    // The other points barely notice (the removed ones are missing from their cells).
    std::size_t differ = 0;
    for (std::size_t i = 0; i < scan.size(); ++i) differ += r.labels[i] != clean.labels[i];
    EXPECT_LT(differ, scan.size() / 50);
    // A cloud of nothing but NaN is labelled, not refused.
    const std::vector<float> nan(3 * 5, std::numeric_limits<float>::quiet_NaN());
    const gseg::Result allBad = gseg::GroundSegmenter().segment(gseg::PointCloudView(nan.data(), 5));
    EXPECT_EQ(allBad.numNonFinite, 5u);
    EXPECT_EQ(allBad.numGround, 0u);
}

TEST(Contract, NonFiniteTestReadsOnlyXyzWhateverTheStrideAndReachesTheLastPoint) {
    // A KITTI-like layout (stride 16) whose fourth float is NaN everywhere: it is not a coordinate.
    // Bad points in the last group of four and as the very last point.
    const auto scan = busyScene();
    const std::size_t n = scan.size();
    std::vector<float> xyz = scan.xyz;
    xyz[3 * (n - 5) + 1] = std::numeric_limits<float>::quiet_NaN();
    xyz[3 * (n - 1) + 2] = std::numeric_limits<float>::infinity();
    std::vector<float> xyzi(4 * n, std::numeric_limits<float>::quiet_NaN());
    for (std::size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) xyzi[4 * i + a] = xyz[3 * i + a];
    const gseg::Result packed = gseg::GroundSegmenter().segment(gseg::PointCloudView(xyz.data(), n));
    const gseg::Result strided = gseg::GroundSegmenter().segment(gseg::PointCloudView(xyzi.data(), n, 16));
    EXPECT_EQ(packed.numNonFinite, 2u);
    EXPECT_EQ(strided.numNonFinite, 2u);
    EXPECT_EQ(packed.labels, strided.labels);
    EXPECT_EQ(strided.labels[n - 5], 0);
    EXPECT_EQ(strided.labels[n - 1], 0);
}

TEST(Contract, AnotherHeightPerCallEqualsASegmenterMadeWithIt) {
    const auto scan = busyScene();
    gseg::Params p;
    p.distToGround = 1.6;
    const gseg::Result a = gseg::GroundSegmenter(p).segment(view(scan));
    const gseg::Result b = gseg::GroundSegmenter().segment(view(scan), 1.6);
    EXPECT_EQ(a.labels, b.labels);
    EXPECT_THROW(gseg::GroundSegmenter().segment(view(scan), std::numeric_limits<double>::quiet_NaN()),
                 std::invalid_argument);
}

TEST(Contract, TinyCloudsAreLabelledNotDropped) {
    for (std::size_t n : {1u, 2u, 5u}) {
        std::vector<float> xyz;
        for (std::size_t i = 0; i < n; ++i) xyz.insert(xyz.end(), {float(i), 0.f, -1.7f});
        const auto r = gseg::GroundSegmenter().segment(gseg::PointCloudView(xyz.data(), n));
        EXPECT_EQ(r.labels.size(), n);
        EXPECT_EQ(r.numNonGround, n);  // too few points to classify: non-ground, documented
    }
}

TEST(Contract, AbsurdlyFarPointDoesNotBreakTheGrid) {
    auto scan = busyScene();
    const auto expected = gseg::GroundSegmenter().segment(view(scan)).labels;
    scan.xyz.insert(scan.xyz.end(), {3.0e9f, -2.0e9f, 1.0e8f});
    scan.truth.push_back(gseg::test::Truth::NonGround);
    const auto r = gseg::GroundSegmenter().segment(view(scan)).labels;
    ASSERT_EQ(r.size(), expected.size() + 1);
    EXPECT_EQ(r.back(), 0);
    EXPECT_TRUE(std::equal(expected.begin(), expected.end(), r.begin()));
}

TEST(Contract, InvalidParametersThrowAtConstruction) {
    gseg::Params p;
    p.cellSizeX = -1.5;
    EXPECT_THROW(gseg::GroundSegmenter{p}, std::invalid_argument);
    p = gseg::Params();
    p.slopeThresholdDegrees = std::nan("");
    EXPECT_THROW(gseg::GroundSegmenter{p}, std::invalid_argument);
}
