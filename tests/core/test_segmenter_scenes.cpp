// GroundSegmenter on simulated scans with exact labels: each scene asserts precision and recall.
#include <gseg/ground_segmenter.hpp>
#include <gseg/sensor_height.hpp>
#include <support/lidar_sim.hpp>
#include <support/scenes.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

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

// A fixed distToGround that the scan contradicts is said (the tools check their first scan). On
// these flat scenes the seed's widening tolerance still finds the ground; on real scans it often
// does not (the VLP-16 scan of mrpt-common with the KITTI height: 0.6 % ground, test_ground_filter).
TEST(Scenes, AWrongFixedSensorHeightIsSaid) {
    for (const double h : {0.8, 2.5}) {
        Scene s;
        s.addFlatGround(h);
        s.addBox(8, -2, -h, 10, 0, -h + 1.5);
        const SimScan scan = simulate(s, Lidar::hdl64());
        const gseg::PointCloudView cloud(scan.xyz.data(), scan.size());
        const std::string wrong = gseg::checkDistToGround(cloud, 1.723, 0.3);
        EXPECT_NE(wrong.find("the ground lies " + std::string(h < 1 ? "0.80" : "2.50") + " m below the sensor"),
                  std::string::npos) << wrong;
        EXPECT_NE(wrong.find("distToGround is 1.723 m"), std::string::npos) << wrong;
        EXPECT_EQ(gseg::checkDistToGround(cloud, h, 0.3), "") << "the right height, sensor at " << h << " m";
        EXPECT_EQ(gseg::checkDistToGround(cloud, h + 0.25, 0.3), "") << "within the seed tolerance";
    }
    // No estimate (a few points, no floor to vote): nothing to say.
    const std::vector<float> few = {5, 0, -1.7f, 6, 1, -1.7f, 7, -1, -1.7f};
    EXPECT_EQ(gseg::checkDistToGround(gseg::PointCloudView(few.data(), 3), 1.723, 0.3), "");
}

// Sensors that do not see the ground near the robot: the seed disc (robotRadius +
// centroidSearchRadius: 7.7 m, 10.7 m with the VLP-16's 8 m) holds no ground. A VLP-16 3 m up
// first meets the ground 11.2 m out; a forward-looking solid-state sensor 1.73 m up 7.8 m out,
// with only the wheels of a car beside it nearer. Both found no ground at all before the seed reached beyond the blind zone.
TEST(Scenes, GroundBeyondTheSensorsBlindZone) {
    struct Case {
        const char* name;
        Lidar lidar;
        double height, radius, minPrecision, minRecall;
    };
    const Case cases[] = {{"VLP-16 at 3 m", Lidar::vlp16(), 3.0, 8.0, 0.97, 0.55},
                          {"solid-state at 1.73 m", Lidar::solidState(), 1.73, 5.0, 0.97, 0.8},
                          {"solid-state at 2.5 m", Lidar::solidState(), 2.5, 5.0, 0.99, 0.8}};
    for (const Case& c : cases) {
        Scene s;
        s.addFlatGround(c.height);
        s.addCar(5, 3, -c.height), s.addCar(-12, -4, -c.height), s.addCar(6, -6, -c.height);
        s.addBox(-3, 8, -c.height, 12, 8.5, -c.height + 2.0);  // a wall on the left
        const SimScan scan = simulate(s, c.lidar);
        float nearestGround = 1e9f;
        for (std::size_t i = 0; i < scan.size(); ++i)
            if (scan.truth[i] == Truth::Ground) nearestGround = std::min(nearestGround, std::hypot(scan.xyz[3 * i], scan.xyz[3 * i + 1]));
        EXPECT_GT(nearestGround, 2.7 + c.radius) << c.name << ": the scene must hide the ground from the seed disc";
        const Outcome o = run(scan, c.height, c.radius);
        EXPECT_GE(o.all.precision, c.minPrecision) << c.name;
        EXPECT_GE(o.all.recall, c.minRecall) << c.name;
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

// --- the scenes of tests/support/scenes.cpp: what real drives contain -------------------------

namespace {

Outcome runScene(const gseg::test::NamedScan& n) { return run(n.scan, n.sensorHeight, n.searchRadius); }

// With distToGround: auto (config/auto_height.yaml): the height (and tilt) estimated from the scan.
struct AutoOutcome {
    Outcome o;
    gseg::HeightDecision decision;
};
AutoOutcome runAuto(const gseg::test::NamedScan& n) {
    gseg::Params p;
    p.centroidSearchRadius = n.searchRadius;
    gseg::AutoHeightSegmenter seg(p);
    gseg::AutoHeightResult r = seg.segment(gseg::PointCloudView(n.scan.xyz.data(), n.scan.size()));
    AutoOutcome a{{{}, std::move(r.result)}, std::move(r.decision)};
    a.o.all = gseg::test::groundPR(n.scan, a.o.result.labels);
    return a;
}

}  // namespace

TEST(Scenes, CarsParkedBesideTheSensorAreNeverGround) {
    // Cars 1.6 m to the right and 2.2 m to the left: the sensor sees their roofs and bonnets from
    // above and cannot see the road under itself.
    const auto n = gseg::test::scene("car_beside");
    const Outcome o = runScene(n);
    EXPECT_LT(groundShareIn(n.scan, o.result.labels, {-2.1, -3.5, -1.2}, {2.5, -1.5, 0.0}), 0.005);  // right car above 0.5 m
    EXPECT_LT(groundShareIn(n.scan, o.result.labels, {0.4, 2.1, -1.2}, {5.0, 4.1, 0.0}), 0.005);     // left car
    EXPECT_GE(o.all.precision, 0.995);
    EXPECT_GE(o.all.recall, 0.85);
}

TEST(Scenes, TrafficJamRoadBetweenTheCarsIsGroundTheCarsAreNot) {
    const auto n = gseg::test::scene("traffic_jam");
    const Outcome o = runScene(n);
    EXPECT_GE(o.all.precision, 0.96);  // measured 97.2 %: only car sills within 0.3 m of the road
    EXPECT_GE(o.all.recall, 0.78);     // measured 81.4 %: road visible only in the gaps
    // Nothing of a car body 0.5 m or more above the road is ground.
    std::size_t high = 0;
    for (std::size_t i = 0; i < n.scan.size(); ++i)
        high += o.result.labels[i] && n.scan.truth[i] == Truth::NonGround && n.scan.xyz[3 * i + 2] > -1.73f + 0.5f;
    EXPECT_EQ(high, 0u);
}

TEST(Scenes, FlatBedTruckBedAndCabAreNotGround) {
    const auto n = gseg::test::scene("flatbed_truck");
    const Outcome o = runScene(n);
    EXPECT_LT(groundShareIn(n.scan, o.result.labels, {-3, 2.0, -1.1}, {6, 4.5, 1.3}), 0.005);
    EXPECT_GE(o.all.precision, 0.98);
    EXPECT_GE(o.all.recall, 0.87);
}

TEST(Scenes, WallWithALedgeOneMetreUpIsNotGround) {
    const auto n = gseg::test::scene("wall_ledge");
    const Outcome o = runScene(n);
    EXPECT_LT(groundShareIn(n.scan, o.result.labels, {-15, 4.0, -1.2}, {15, 5.5, 1.3}), 0.005);  // ledge top and wall
    EXPECT_GE(o.all.precision, 0.98);
    EXPECT_GE(o.all.recall, 0.9);
}

TEST(Scenes, HedgeAndBushTopsAreNotGround) {
    const auto n = gseg::test::scene("hedge");
    const Outcome o = runScene(n);
    EXPECT_LT(groundShareIn(n.scan, o.result.labels, {-20, -5.0, -1.3}, {20, -3.5, 0.0}), 0.005);  // hedge above 0.4 m
    EXPECT_LT(groundShareIn(n.scan, o.result.labels, {8, 3, -1.3}, {10, 5, 0.0}), 0.005);         // bush
    EXPECT_GE(o.all.precision, 0.9);  // measured 93.3 %: the foot of the foliage, within 0.3 m of the ground
    EXPECT_GE(o.all.recall, 0.87);
}

TEST(Scenes, CurbAndSidewalkRightBesideTheRobotAreGround) {
    const auto n = gseg::test::scene("curb_near");
    const Outcome o = runScene(n);
    EXPECT_GT(groundShareIn(n.scan, o.result.labels, {-10, 2.6, -1.7}, {10, 12, -1.4}), 0.95);  // sidewalk near the robot
    EXPECT_EQ(o.all.precision, 1.0);
    EXPECT_GE(o.all.recall, 0.9);
}

TEST(Scenes, HillsAreGround) {
    for (const char* name : {"hills_gentle", "hills_steep"}) {
        const auto n = gseg::test::scene(name);
        const Outcome o = runScene(n);
        EXPECT_EQ(o.all.precision, 1.0) << name;
        EXPECT_GE(o.all.recall, 0.85) << name;
    }
}

TEST(Scenes, ReflectionsBelowTheRoadAreNeverGroundAndAreFlagged) {
    const auto n = gseg::test::scene("reflections");  // 2000 points 1 to 3 m below the road
    const Outcome o = runScene(n);
    std::size_t reflections = 0, flagged = 0, groundFlagged = 0;
    for (std::size_t i = 0; i < n.scan.size(); ++i) {
        const bool below = n.scan.xyz[3 * i + 2] < -1.73f - 0.9f;
        reflections += below;
        EXPECT_FALSE(below && o.result.labels[i]) << "reflection " << i << " labelled ground";
    }
    for (std::uint32_t i : o.result.belowGround) {
        flagged += n.scan.xyz[3 * i + 2] < -1.73f - 0.9f;
        groundFlagged += o.result.labels[i];
    }
    EXPECT_EQ(reflections, 2000u);
    EXPECT_GE(flagged, 1900u);  // those within two columns of ground that the sensor saw
    EXPECT_EQ(flagged, o.result.belowGround.size());  // nothing else is flagged
    EXPECT_EQ(groundFlagged, 0u);
    EXPECT_TRUE(std::is_sorted(o.result.belowGround.begin(), o.result.belowGround.end()));
    // The road above the reflections stays ground: nearly as much as on the same flat road without
    // them (measured 91.0 % against 92.9 %). Issue #20: Phase II's floating check, if it saw every
    // reflection below a column, would drop the road above them (to 62 %).
    const Outcome flat = runScene(gseg::test::scene("flat"));
    EXPECT_GE(o.all.recall, flat.all.recall - 0.03);
}

TEST(Scenes, AutoHeightLowMountedVlp16IsEstimatedNotRefused) {
    const auto n = gseg::test::scene("vlp16_low");  // 0.5 m up
    const AutoOutcome a = runAuto(n);
    EXPECT_EQ(a.decision.source, gseg::HeightDecision::Source::Estimated) << a.decision.describe();
    EXPECT_NEAR(a.decision.height, 0.5, 0.05);
    EXPECT_GE(a.o.all.precision, 0.98);
    EXPECT_GE(a.o.all.recall, 0.85);
}

TEST(Scenes, AutoHeightLevelsAFiveDegreeMountingTilt) {
    const auto n = gseg::test::scene("tilted_5deg");  // pitched 5 deg, rolled 2 deg
    const AutoOutcome a = runAuto(n);
    EXPECT_EQ(a.decision.source, gseg::HeightDecision::Source::Estimated);
    EXPECT_NEAR(a.decision.tiltDegrees, std::hypot(5.0, 2.0), 0.5);
    EXPECT_NEAR(a.decision.height, 1.73, 0.1);
    EXPECT_GE(a.o.all.precision, 0.995);
    EXPECT_GE(a.o.all.recall, 0.92);  // measured 94.8 %; unlevelled with the true height: 90.5 %
}

TEST(Scenes, AutoHeightOnEveryScene) {
    // No scene is refused, and auto costs little against the true height.
    for (const auto& n : gseg::test::allScenes()) {
        const AutoOutcome a = runAuto(n);
        const Outcome fixed = runScene(n);
        EXPECT_EQ(a.decision.source, gseg::HeightDecision::Source::Estimated) << n.name;
        EXPECT_GE(a.o.all.precision, fixed.all.precision - 0.01) << n.name;
        EXPECT_GE(a.o.all.recall, fixed.all.recall - 0.03) << n.name;
    }
}

TEST(Scenes, NothingHalfAMetreAboveFlatGroundIsEverGround) {
    // Every scene on level ground: no obstacle point 0.5 m or more above the road is ground, with the
    // true height or with distToGround: auto.
    for (const char* name : {"flat", "car_beside", "traffic_jam", "flatbed_truck", "wall_ledge", "hedge", "curb_near",
                             "hdl32_street", "reflections", "vlp16_low"}) {
        const auto n = gseg::test::scene(name);
        const Outcome fixed = runScene(n);
        const AutoOutcome a = runAuto(n);
        std::size_t high = 0, highAuto = 0;
        for (std::size_t i = 0; i < n.scan.size(); ++i) {
            const bool raised = n.scan.truth[i] == Truth::NonGround && n.scan.xyz[3 * i + 2] > -n.sensorHeight + 0.5;
            high += raised && fixed.result.labels[i];
            highAuto += raised && a.o.result.labels[i];
        }
        EXPECT_EQ(high, 0u) << name;
        EXPECT_EQ(highAuto, 0u) << name;
    }
}

TEST(Scenes, OtherSensorsA32BeamStreetAndAForwardLookingSolidStateOnVegetatedHills) {
    const auto street = gseg::test::scene("hdl32_street");  // 1.84 m up
    const AutoOutcome s = runAuto(street);
    EXPECT_NEAR(s.decision.height, 1.84, 0.05);
    EXPECT_GE(s.o.all.precision, 0.96);  // measured 97.3 %: wheels and the hedge's foot
    EXPECT_GE(s.o.all.recall, 0.85);
    const auto hills = gseg::test::scene("solid_state_hills");  // 1 m up, 120 deg field of view
    const AutoOutcome h = runAuto(hills);
    EXPECT_EQ(h.decision.source, gseg::HeightDecision::Source::Estimated);
    EXPECT_GE(h.o.all.precision, 0.975);  // measured 98.5 %
    EXPECT_GE(h.o.all.recall, 0.9);       // measured 94.1 %
}

// --- issue #20: the ground beside the road, rough terrain, sparse sensors ----------------------

namespace {

struct RecallCase {
    const char* name;
    double precision, recall;          ///< floors with the true sensor height
    double beside;                     ///< floor of the recall beside the road (|y| >= 4.3 m; gravel: everywhere)
    double autoPrecision, autoRecall;  ///< floors with distToGround: auto
};

// Share of the truth-ground points with |y| >= minAbsY (beside the road) labelled ground.
double besideRoadRecall(const gseg::test::NamedScan& n, const std::vector<std::uint8_t>& labels, double minAbsY) {
    std::size_t truth = 0, found = 0;
    for (std::size_t i = 0; i < n.scan.size(); ++i)
        if (n.scan.truth[i] == Truth::Ground && std::abs(n.scan.xyz[3 * i + 1]) >= minAbsY)
            ++truth, found += labels[i] != 0;
    return truth ? double(found) / double(truth) : 0.0;
}

}  // namespace

TEST(Scenes, GroundBesideTheRoadRoughTerrainAndSparseSensors) {
    // Floors about half a point under what this version measures (printed). What is missed is far
    // out: on every scene the ground beyond the range where the rings lie more than the search
    // radius apart (HDL-64E at 1.73 m: about 35 m; HDL-32E at 1.84 m: about 25 m) is reached only
    // where a bridge (bridgeRadius) finds it level with the ground before it, and on the HDL-32E
    // part of the terrain 20-30 m out is reached by Phase I but stopped by Phase II's height gate
    // between single-ring (line) cells. Issue #20's analysis: loosening either costs
    // precision on the real scans. Floors raised with issue #20's rules (sparseRecoveryThreshold and
    // the floating check's window); grass_verge_5cm gave 0.3 of precision for 1.4 of recall.
    const RecallCase cases[] = {
        // name                   P      R      beside  auto P  auto R    (measured P / R / beside; auto P / R)
        {"grass_verge_5cm", 0.978, 0.950, 0.905, 0.980, 0.950},      // 98.08 / 95.66 / 91.42; 98.37 / 95.63
        {"grass_verge_15cm", 0.977, 0.950, 0.935, 0.975, 0.960},     // 98.23 / 95.43 / 93.89; 98.09 / 96.82
        {"embankment_12", 0.990, 0.970, 0.950, 0.990, 0.965},        // 99.32 / 97.62 / 95.86; 99.26 / 96.95
        {"gravel_road", 0.995, 0.940, 0.900, 0.995, 0.940},          // 99.82 / 94.72 / 90.79; 99.79 / 94.67
        {"hdl32_road_terrain", 0.995, 0.933, 0.890, 0.995, 0.933},   // 99.91 / 93.79 / 89.42; 99.91 / 93.85
        {"vlp16_rolling_grass", 0.990, 0.880, 0.830, 0.990, 0.880},  // 99.54 / 88.80 / 83.75; 99.50 / 88.63
    };
    for (const RecallCase& c : cases) {
        const auto n = gseg::test::scene(c.name);
        const Outcome o = runScene(n);
        const AutoOutcome a = runAuto(n);
        const double beside = besideRoadRecall(n, o.result.labels, 4.3);
        std::printf("%-20s true height: P %.4f R %.4f (beside the road %.4f); auto (%.3f m): P %.4f R %.4f\n", c.name,
                    o.all.precision, o.all.recall, beside, a.decision.height, a.o.all.precision, a.o.all.recall);
        EXPECT_GE(o.all.precision, c.precision) << c.name;
        EXPECT_GE(o.all.recall, c.recall) << c.name;
        EXPECT_GE(beside, c.beside) << c.name;
        EXPECT_EQ(a.decision.source, gseg::HeightDecision::Source::Estimated) << c.name;
        EXPECT_GE(a.o.all.precision, c.autoPrecision) << c.name;
        EXPECT_GE(a.o.all.recall, c.autoRecall) << c.name;
        // On the level roads nothing 0.7 m or more above the road (car roofs and bonnets, hedge
        // tops, the wall) is ever ground. (The VLP-16's bushes stand on hills: no road level.)
        if (std::string(c.name) == "vlp16_rolling_grass") continue;
        std::size_t high = 0;
        for (std::size_t i = 0; i < n.scan.size(); ++i)
            high += n.scan.truth[i] == Truth::NonGround && o.result.labels[i] && n.scan.xyz[3 * i + 2] > -n.sensorHeight + 0.7;
        EXPECT_EQ(high, 0u) << c.name;
    }
}

// --- issue #20's rules, each on a scene that fails without it ------------------------------------

namespace {

Outcome runWith(const gseg::test::NamedScan& n, const std::vector<std::pair<const char*, const char*>>& keys) {
    gseg::Params p;
    p.distToGround = n.sensorHeight;
    p.centroidSearchRadius = n.searchRadius;
    for (const auto& [k, v] : keys) p.set(k, v);
    gseg::GroundSegmenter seg(p);
    Outcome o{{}, seg.segment(gseg::PointCloudView(n.scan.xyz.data(), n.scan.size()))};
    o.all = gseg::test::groundPR(n.scan, o.result.labels);
    return o;
}

// The scene turned by `quarters` x 90 deg about the sensor's vertical axis (labels unchanged).
gseg::test::NamedScan turned(gseg::test::NamedScan n, int quarters) {
    for (int q = 0; q < quarters; ++q)
        for (std::size_t i = 0; i < n.scan.size(); ++i) {
            const float x = n.scan.xyz[3 * i], y = n.scan.xyz[3 * i + 1];
            n.scan.xyz[3 * i] = -y, n.scan.xyz[3 * i + 1] = x;
        }
    return n;
}

}  // namespace

TEST(Scenes, TheFloatingCheckSeesWhatStandsBelowInEveryQuadrant) {
    // Phase II's floating check looks up, per column, what Phase I rejected below a cell. Its key
    // once cast signed column indices to unsigned, so the sorted lookup missed in some quadrants:
    // the hedge turned by 90 deg then had a point 0.5 m or more above the road called ground, and
    // precision was 0.1 point lower in every orientation (93.31 / 93.32 / 92.92 / 94.10 %).
    for (int q = 0; q < 4; ++q) {
        const auto n = turned(gseg::test::scene("hedge"), q);
        const Outcome o = runScene(n);
        std::size_t high = 0;
        for (std::size_t i = 0; i < n.scan.size(); ++i)
            high += o.result.labels[i] && n.scan.truth[i] == Truth::NonGround && n.scan.xyz[3 * i + 2] > -n.sensorHeight + 0.5;
        EXPECT_EQ(high, 0u) << q * 90 << " deg";
        EXPECT_GE(o.all.precision, 0.929) << q * 90 << " deg";  // measured 93.46 / 93.66 / 92.98 / 94.24 %
    }
}

TEST(Scenes, AVergeAStepAboveTheRoadIsNotFloatingOnTheRoadBelowIt) {
    // floatingMinHeight / floatingIgnoresLowOutliers: a Phase I cell holding the road and a verge
    // 15 cm above it fits its plane to one of them; the road's points below that plane are not
    // something the verge stands on. Counting them (every rejected point below a cell) drops the
    // verges: recall 95.0 -> 88.0 %.
    const auto n = gseg::test::scene("grass_verge_15cm");
    const Outcome o = runScene(n);
    const Outcome naive = runWith(n, {{"floatingMinHeight", "0"}, {"floatingIgnoresLowOutliers", "false"}});
    EXPECT_GE(o.all.recall, 0.945);
    EXPECT_GE(besideRoadRecall(n, o.result.labels, 4.3), 0.93);
    EXPECT_LT(naive.all.recall, o.all.recall - 0.05);  // the rule is what keeps the verges
}

TEST(Scenes, SparseCellsOnAGroundNeighboursPlaneAreGround) {
    // sparseRecoveryThreshold: Phase II cells with fewer than minPointsPerCell points (rough gravel
    // splits a ring between 0.2 m slabs) are ground where their points lie on an adjacent ground
    // cell's plane. Without: recall 92.56 %, beside nothing gained; precision unchanged.
    const auto n = gseg::test::scene("gravel_road");
    const Outcome o = runScene(n);
    const Outcome off = runWith(n, {{"sparseRecoveryThreshold", "0"}});
    EXPECT_GE(o.all.recall, 0.94);   // measured 94.72 %
    EXPECT_LT(off.all.recall, 0.93);
    EXPECT_GE(o.all.precision, off.all.precision - 0.001);
    EXPECT_GT(o.result.phase2.recoveredPoints, 0u);
}

TEST(Scenes, BridgesReachTheTerrainTheExpansionStoppedShortOf) {
    // bridgeRadius / bridgeGate / bridgeGapGate / bridgeMaxDrop / bridgeMaxAngleDegrees: once Phase
    // II's expansion stops, a Phase I ground cell it never reached is reached from the nearest ground
    // cell within 10 m where it lies within 0.1 m of that cell's plane, at most 0.1 m above (0.15 m
    // across a gap wider than the search radius) and 0.3 m below its height, and the two planes agree
    // within 10 deg. The HDL-32E's terrain beside the road, 20-30 m out, is a step above the road
    // between single-ring cells and its far rings lie more than the search radius apart: without
    // bridges recall 89.57 % (beside the road 82.48 %), with them 93.79 % (89.42 %; 92.31 % without
    // bridgeGapGate), precision 99.90 -> 99.91 %. A kerb beside the robot: 93.63 -> 96.38 %.
    // Without the normals' agreement the solid-state sensor on vegetated hills (auto height) lost
    // 0.24 points of precision to bushes' tops for no recall.
    for (const char* name : {"hdl32_road_terrain", "curb_near", "solid_state_hills"}) {
        const auto n = gseg::test::scene(name);
        const Outcome o = runScene(n);
        const Outcome off = runWith(n, {{"bridgeRadius", "0"}});
        std::printf("%-20s bridges: P %.4f R %.4f; none: P %.4f R %.4f\n", name, o.all.precision, o.all.recall,
                    off.all.precision, off.all.recall);
        EXPECT_GE(o.all.precision, off.all.precision - 0.0005) << name;
        EXPECT_GE(o.all.recall, off.all.recall) << name;
        if (std::string(name) == "solid_state_hills") {
            const AutoOutcome a = runAuto(n);
            EXPECT_GE(a.o.all.precision, 0.978) << name;  // measured 97.89 % (without the angle 97.65 %)
        } else {
            EXPECT_GT(o.all.recall, off.all.recall + 0.02) << name;  // the rule is what reaches them
        }
    }
    const auto n = gseg::test::scene("hdl32_road_terrain");
    EXPECT_GE(besideRoadRecall(n, runScene(n).result.labels, 4.3), 0.89);  // measured 89.42 %; none: 82.48 %
}

TEST(Scenes, BridgesFollowTheGroundDownWhereItsPlaneSaysSo) {
    // bridgeMaxDrop: a bridge may lead up to 0.3 m down (still within bridgeGate of the plane it
    // starts from): the far rings of a road falling at 10 deg, which a height gate of 0.1 m across a
    // 5-10 m gap stops. Ramp down: recall 90.85 -> 92.00 % (with 0.1: 90.85 %); HDL-32E terrain
    // 91.60 -> 92.31 %. Measured in height alone (not along the plane), a drop of 0.3 m led down
    // the faces of bushes on the solid-state sensor's hills: precision 97.89 -> 97.75 % (auto).
    for (const char* name : {"ramp_down_10", "hdl32_road_terrain"}) {
        const auto n = gseg::test::scene(name);
        const Outcome o = runScene(n);
        const Outcome level = runWith(n, {{"bridgeMaxDrop", "0"}});
        EXPECT_GE(o.all.precision, level.all.precision - 0.0005) << name;
        EXPECT_GT(o.all.recall, level.all.recall + 0.005) << name;
    }
    const auto hills = gseg::test::scene("solid_state_hills");
    EXPECT_GE(runAuto(hills).o.all.precision, 0.978);
}

TEST(Scenes, BridgesAcrossAGapBetweenFarRingsTakeTheGroundsRiseOverIt) {
    // bridgeGapGate: where the nearest ground cell lies farther than centroidSearchRadius (rings
    // farther apart than the search radius, which the expansion never compared), the bridge's gate
    // above it is 0.15 m instead of 0.1: the rise of ground beside a road over 5-10 m. The
    // HDL-32E's terrain rings 20-40 m out: recall 92.31 -> 93.79 % at the same precision.
    const auto n = gseg::test::scene("hdl32_road_terrain");
    const Outcome o = runScene(n);
    const Outcome near = runWith(n, {{"bridgeGapGate", "0"}});
    std::printf("gap gate: P %.4f R %.4f; bridgeGate alone: P %.4f R %.4f\n", o.all.precision, o.all.recall,
                near.all.precision, near.all.recall);
    EXPECT_GE(o.all.precision, near.all.precision - 0.0005);
    EXPECT_GT(o.all.recall, near.all.recall + 0.01);
    for (const char* name : {"grass_verge_15cm", "hedge", "solid_state_hills", "traffic_jam"}) {
        const auto m = gseg::test::scene(name);  // no scene with cars, hedges, bushes loses precision
        EXPECT_GE(runScene(m).all.precision, runWith(m, {{"bridgeGapGate", "0"}}).all.precision - 0.0005) << name;
    }
}

TEST(Scenes, AHugeBridgeRadiusEndsAndActsAsOneReachingEverything) {
    // The bridges' nearest-ground search walks rings of columns outward only as far as the
    // centroids reach: a bridgeRadius of 1e12 m ends, with the labels of one that already covers the
    // whole scene (hdl32_road_terrain lies within 100 m of the sensor).
    const auto n = gseg::test::scene("hdl32_road_terrain");
    const Outcome huge = runWith(n, {{"bridgeRadius", "1e12"}});
    const Outcome whole = runWith(n, {{"bridgeRadius", "1000"}});
    EXPECT_EQ(huge.result.labels, whole.result.labels);
    EXPECT_GE(huge.all.recall, runScene(n).all.recall);  // reaches at least what 10 m reaches
}
