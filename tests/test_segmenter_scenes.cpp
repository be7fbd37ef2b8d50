// GroundSegmenter on simulated scans with exact labels: each scene asserts precision and recall.
#include <gseg/ground_segmenter.hpp>
#include <support/lidar_sim.hpp>

#include <gtest/gtest.h>

#include <array>

using gseg::test::Lidar;
using gseg::test::Scene;
using gseg::test::SimScan;
using gseg::test::Truth;

namespace {

struct Outcome {
    gseg::test::PR all;
    gseg::Result result;
};

Outcome run(const SimScan& scan, double sensorHeight, double searchRadius = 5.0) {
    gseg::Params p;
    p.distToGround = sensorHeight;
    p.centroidSearchRadius = searchRadius;
    gseg::GroundSegmenter seg(p);
    Outcome o{{}, seg.segment(gseg::PointCloudView(scan.xyz.data(), scan.size()))};
    o.all = gseg::test::groundPR(scan, o.result.labels);
    return o;
}

// Share of the points inside the box [lo, hi] that are labelled ground.
double groundShareIn(const SimScan& scan, const std::vector<std::uint8_t>& labels, std::array<double, 3> lo,
                     std::array<double, 3> hi) {
    std::size_t n = 0, g = 0;
    for (std::size_t i = 0; i < scan.size(); ++i) {
        const float* p = &scan.xyz[3 * i];
        bool in = true;
        for (int a = 0; a < 3; ++a) in = in && p[a] >= lo[a] && p[a] <= hi[a];
        n += in, g += in && labels[i];
    }
    EXPECT_GT(n, 20u) << "the scene has too few points in the region under test";
    return n ? double(g) / double(n) : 0.0;
}

}  // namespace

TEST(Scenes, FlatGroundIsGround) {
    Scene s;
    s.addFlatGround(1.73);
    const SimScan scan = simulate(s, Lidar::hdl64());
    const Outcome o = run(scan, 1.73);
    EXPECT_EQ(o.all.precision, 1.0);  // there is nothing else
    // Within 25 m nearly all; beyond ~35 m this sensor's rings lie more than centroidSearchRadius
    // (5 m) apart on open flat ground, so the expansion cannot bridge them (a limit of the method).
    EXPECT_GT(groundShareIn(scan, o.result.labels, {-25, -25, -2}, {25, 25, -1.5}), 0.99);
    EXPECT_GE(o.all.recall, 0.9);
}

TEST(Scenes, BoxesAndWallAreObstacles) {
    Scene s;
    s.addFlatGround(1.73);
    s.addBox(8, -2, -1.73, 10, 0, -0.23);       // a 1.5 m crate ahead
    s.addBox(-12, 4, -1.73, -10, 6, 0.5);       // a tall box behind-left
    s.addBox(-30, -40, -1.73, 30, -39.5, 3.0);  // a wall along the right side
    const SimScan scan = simulate(s, Lidar::hdl64());
    const Outcome o = run(scan, 1.73);
    EXPECT_GE(o.all.precision, 0.99);
    EXPECT_GE(o.all.recall, 0.93);
    EXPECT_LT(groundShareIn(scan, o.result.labels, {8, -2, -1.4}, {10, 0, -0.2}), 0.02);
    EXPECT_LT(groundShareIn(scan, o.result.labels, {-12, 4, -1.4}, {-10, 6, 0.5}), 0.02);
    EXPECT_LT(groundShareIn(scan, o.result.labels, {-30, -40, -1.4}, {30, -39.4, 3}), 0.02);
}

TEST(Scenes, CarBodyIsObstacleAndRoadUnderBumperIsGround) {
    Scene s;
    s.addFlatGround(1.73);
    s.addBox(6, 2, -1.43, 10.5, 3.8, -0.23);  // car body, 0.3 m above the road
    for (double x : {6.5, 9.7})               // wheels
        for (double y : {2.1, 3.5}) s.addBox(x, y, -1.73, x + 0.6, y + 0.2, -1.43);
    const SimScan scan = simulate(s, Lidar::hdl64());
    const Outcome o = run(scan, 1.73);
    EXPECT_LT(groundShareIn(scan, o.result.labels, {6, 2, -1.5}, {10.5, 3.8, -0.2}), 0.03);
    // The road right in front of and beside the car stays ground.
    EXPECT_GT(groundShareIn(scan, o.result.labels, {3, 1, -1.9}, {6, 4, -1.6}), 0.9);
    EXPECT_GE(o.all.precision, 0.98);
}

TEST(Scenes, OverhangAboveRoadIsNotGroundAndRoadBelowIs) {
    Scene s;
    s.addFlatGround(1.73);
    s.addBox(10, -6, 0.3, 16, 6, 0.9);  // a canopy / low bridge deck 2 m above the road
    const SimScan scan = simulate(s, Lidar::hdl64());
    const Outcome o = run(scan, 1.73);
    EXPECT_LT(groundShareIn(scan, o.result.labels, {10, -6, 0.2}, {16, 6, 1.0}), 0.01);
    EXPECT_GT(groundShareIn(scan, o.result.labels, {10, -6, -1.9}, {16, 6, -1.5}), 0.9);
}

TEST(Scenes, CurbAndSidewalkAreGround) {
    Scene s;
    gseg::test::Plane road, walk, face;
    road.offset = -1.73, road.hi[1] = 4;
    walk.offset = -1.58, walk.lo[1] = 4;  // a 0.15 m curb 4 m to the left
    face.n[0] = 0, face.n[1] = 1, face.n[2] = 0, face.offset = 4, face.lo[2] = -1.73, face.hi[2] = -1.58;
    face.truth = Truth::DontCare;
    s.planes = {road, walk, face};
    const SimScan scan = simulate(s, Lidar::hdl64());
    const Outcome o = run(scan, 1.73);
    EXPECT_GT(groundShareIn(scan, o.result.labels, {-20, 4.2, -1.7}, {20, 20, -1.4}), 0.9);  // sidewalk
    EXPECT_GE(o.all.recall, 0.93);
}

TEST(Scenes, GentleSlopesAreGroundSteepOnesAreNot) {
    for (const double deg : {10.0, 20.0}) {
        Scene s;
        s.addRamp(1.73, 6, deg, Truth::Ground);
        const SimScan scan = simulate(s, Lidar::hdl64());
        const Outcome o = run(scan, 1.73);
        EXPECT_GE(o.all.recall, 0.9) << deg << " deg";
        EXPECT_GT(groundShareIn(scan, o.result.labels, {9, -10, -5}, {30, 10, 20}), 0.85) << deg << " deg";
    }
    Scene s;
    s.addRamp(1.73, 6, 45.0, Truth::NonGround);  // steeper than slopeThresholdDegrees (30)
    const SimScan scan = simulate(s, Lidar::hdl64());
    const Outcome o = run(scan, 1.73);
    // Only its foot, within a plane-inlier distance and a thin cell of the road, may pass as ground.
    EXPECT_LT(groundShareIn(scan, o.result.labels, {6, -10, -1.33}, {30, 10, 30}), 0.03);
    EXPECT_GE(o.all.precision, 0.95);
}

TEST(Scenes, ObstaclesAtNegativeCoordinates) {
    // Everything behind and to the right of the sensor (x < 0, y < 0): floor indexing must not fold
    // these cells onto the ones in front.
    Scene s;
    s.addFlatGround(1.73);
    s.addBox(-9, -9, -1.73, -7, -7, 0.0);
    s.addBox(-0.9, -15, -1.73, -0.1, -13, 0.0);  // straddles x = 0 from the negative side
    const SimScan scan = simulate(s, Lidar::hdl64());
    const Outcome o = run(scan, 1.73);
    EXPECT_LT(groundShareIn(scan, o.result.labels, {-9, -9, -1.4}, {-7, -7, 0}), 0.02);
    EXPECT_LT(groundShareIn(scan, o.result.labels, {-0.9, -15, -1.4}, {-0.1, -13, 0}), 0.05);
    // The mirrored region in front stays ground (a truncating index would mix it up).
    EXPECT_GT(groundShareIn(scan, o.result.labels, {7, 7, -1.9}, {9, 9, -1.5}), 0.9);
}

TEST(Scenes, OtherSensorHeights) {
    for (const double h : {0.8, 2.5}) {
        Scene s;
        s.addFlatGround(h);
        s.addBox(8, -2, -h, 10, 0, -h + 1.5);
        const Outcome o = run(simulate(s, Lidar::hdl64()), h);
        EXPECT_GE(o.all.precision, 0.99) << "sensor at " << h << " m";
        EXPECT_GE(o.all.recall, 0.9) << "sensor at " << h << " m";
    }
}

TEST(Scenes, Vlp16) {
    Scene s;
    s.addFlatGround(0.8);
    s.addBox(6, -2, -0.8, 8, 0, 0.7);
    const SimScan scan = simulate(s, Lidar::vlp16());
    // At 0.8 m the -5 and -3 deg rings lie 9 and 15 m out: the search radius must bridge 6 m.
    const Outcome o = run(scan, 0.8, 8.0);
    EXPECT_GE(o.all.precision, 0.99);
    // Two rings 0.25 m apart on the box's face straddle a horizontal plane within the inlier
    // distance (0.125 m) of both: the lowest 0.3 m of a face standing on the ground can pass.
    EXPECT_LT(groundShareIn(scan, o.result.labels, {6, -2, -0.5}, {8, 0, 0.7}), 0.01);
    // Rings up to -3 deg (15 m) are reached; the -1 deg ring at 46 m is 30 m beyond the last one.
    EXPECT_GT(groundShareIn(scan, o.result.labels, {-20, -20, -1}, {20, 20, -0.6}), 0.95);
}
