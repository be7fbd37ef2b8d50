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

TEST(Contract, NonFiniteCoordinatesThrowNamingThePoint) {
    for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                            -std::numeric_limits<float>::infinity()}) {
        std::vector<float> xyz = {1, 0, -1.7, 2, 0, -1.7, 3, bad, -1.7, 4, 0, -1.7};
        gseg::GroundSegmenter seg;
        try {
            seg.segment(gseg::PointCloudView(xyz.data(), 4));
            ADD_FAILURE() << "no exception for " << bad;
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find("point 2"), std::string::npos) << e.what();
        }
    }
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
