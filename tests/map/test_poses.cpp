// Trajectory readers: TUM, KITTI poses + calib, frame conversion, time matching, bad files.
#include <gseg/map/poses.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace {

using namespace gseg::map;

std::string writeTemp(const std::string& name, const std::string& text) {
    return gseg::test::writeTestFile("poses", name, text);
}

TEST(Poses, TumReadsPositionAndQuaternion) {
    const auto p = writeTemp("a.tum", "# t x y z qx qy qz qw\n1.0 1 2 3 0 0 0 1\n\n1.1 4 5 6 0 0 0.7071068 0.7071068\n");
    const auto t = readTumTrajectory(p);
    ASSERT_EQ(t.size(), 2u);
    EXPECT_DOUBLE_EQ(t[0].t, 1.0);
    EXPECT_TRUE(t[0].pose.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
    // 90 degrees about z: x axis goes to y.
    EXPECT_TRUE((t[1].pose.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-6));
    EXPECT_EQ(detectPoseFileFormat(p), PoseFileFormat::Tum);
}

TEST(Poses, NearestPoseWithinTolerance) {
    std::vector<StampedPose> t(3);
    t[0].t = 0.0, t[1].t = 0.1, t[2].t = 0.2;
    EXPECT_EQ(nearestPose(t, 0.104, 0.01).value(), 1u);
    EXPECT_EQ(nearestPose(t, 0.196, 0.01).value(), 2u);
    EXPECT_EQ(nearestPose(t, -0.005, 0.01).value(), 0u);
    EXPECT_FALSE(nearestPose(t, 0.15, 0.01).has_value());
    EXPECT_FALSE(nearestPose(t, 0.5, 0.01).has_value());
}

TEST(Poses, BadFilesNameTheLine) {
    const auto short_ = writeTemp("b.tum", "1.0 1 2 3 0 0 0 1\n2.0 1 2 3 0 0 1\n");
    try {
        readTumTrajectory(short_);
        FAIL() << "no throw";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(":2:"), std::string::npos) << e.what();
    }
    EXPECT_THROW(readTumTrajectory(writeTemp("c.tum", "2.0 1 2 3 0 0 0 1\n1.0 1 2 3 0 0 0 1\n")), std::runtime_error);
    EXPECT_THROW(readTumTrajectory(writeTemp("d.tum", "1.0 1 2 3 0 0 0 0\n")), std::runtime_error);
    EXPECT_THROW(readKittiPoses(writeTemp("e.txt", "1 0 0 0 0 1 0 0 0 0 1\n")), std::runtime_error);
    EXPECT_THROW(readKittiCalibTr(writeTemp("f.txt", "P0: 1 2 3\n")), std::runtime_error);
    EXPECT_THROW(readKittiPoses("/nonexistent/poses.txt"), std::runtime_error);
    EXPECT_THROW(detectPoseFileFormat(writeTemp("g.txt", "1 2 3\n")), std::runtime_error);
}

TEST(Poses, KittiSequence00InVelodyneFrame) {
    const std::string poses = gseg::test::sharedData("semantickitti/sequences/00/poses.txt");
    const std::string calib = gseg::test::sharedData("semantickitti/sequences/00/calib.txt");
    if (poses.empty() || calib.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/00/poses.txt");
    EXPECT_EQ(detectPoseFileFormat(poses), PoseFileFormat::Kitti);
    const auto cam = readKittiPoses(poses);
    ASSERT_EQ(cam.size(), 6u);
    const auto velo = kittiToVelodyneFrame(cam, readKittiCalibTr(calib));
    EXPECT_TRUE(velo[0].isApprox(Eigen::Isometry3d::Identity(), 1e-6));
    // The car drives forward (camera z = velodyne x), about 0.7 m per frame, on a level road.
    const Eigen::Vector3d t5 = velo[5].translation();
    EXPECT_NEAR(t5.x(), 3.5, 0.3);
    EXPECT_LT(std::abs(t5.y()), 0.3);
    EXPECT_LT(std::abs(t5.z()), 0.15);
    EXPECT_NEAR(t5.x(), cam[5].translation().z(), 0.1);
}

/// The message of what `f` throws ("" if nothing).
template <class F>
std::string errorOf(F&& f) {
    try {
        f();
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "";
}

TEST(Poses, RotationsThatAreNotRotationsNameFileAndLine) {
    // #9 item 10: a scaled rotation or an all-zero Tr silently scaled or collapsed the map.
    const auto scaled = writeTemp("scaled.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n2 0 0 1 0 2 0 0 0 0 2 0\n");
    std::string e = errorOf([&] { readKittiPoses(scaled); });
    EXPECT_NE(e.find(scaled + ":2: the 3x3 part is not a rotation"), std::string::npos) << e;
    const auto zero = writeTemp("zero_calib.txt", "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr: 0 0 0 0 0 0 0 0 0 0 0 0\n");
    e = errorOf([&] { readKittiCalibTr(zero); });
    EXPECT_NE(e.find(zero + ":2: the 3x3 part is not a rotation"), std::string::npos) << e;
    const auto mirrored = writeTemp("mirror.txt", "-1 0 0 0 0 1 0 0 0 0 1 0\n");  // orthonormal, det -1
    EXPECT_NE(errorOf([&] { readKittiPoses(mirrored); }).find(":1:"), std::string::npos);
    // Printed with 7 digits, as in KITTI's files: accepted.
    const auto printed = writeTemp("printed.txt", "9.999978e-01 5.272628e-04 -2.066935e-03 -4.690294e-02 "
                                                  "-5.296506e-04 9.999992e-01 -1.154865e-03 -2.839928e-02 "
                                                  "2.066324e-03 1.155958e-03 9.999971e-01 8.586941e-01\n");
    EXPECT_EQ(readKittiPoses(printed).size(), 1u);
}

TEST(Poses, TimesMustBeFiniteAndInOrder) {
    const auto good = writeTemp("times_ok.txt", "0.000000e+00\n1.037359e-01\n\n2.073381e-01\n");
    EXPECT_EQ(readKittiTimes(good).size(), 3u);
    struct Case {
        std::string text, where;
    };
    for (const Case& c : {Case{"0.0\n0.1\nnan\n", ":3:"}, Case{"0.0\ninf\n", ":2:"}, Case{"0.0\n0.2\n0.1\n", ":3:"},
                          Case{"0.0\n0.1 0.2\n", ":2:"}, Case{"0.0\nabc\n", ":2:"}}) {
        const auto path = writeTemp("times_bad.txt", c.text);
        const std::string e = errorOf([&] { readKittiTimes(path); });
        EXPECT_NE(e.find(path + c.where), std::string::npos) << c.text << " -> " << e;
    }
}

// #18 point 6: a time MRPT's 100 ns time stamps cannot hold (1e13 s wraps to 1970) is refused
// with its file and line, as are negative times.
TEST(Poses, TimesBeyondWhatATimeStampHoldsOrNegativeAreRefused) {
    EXPECT_EQ(readKittiTimes(writeTemp("times_max.txt", "0\n1e9\n")).back(), kMaxKittiTime);
    for (const char* text : {"0.0\n1e13\n", "0.0\n1e18\n", "0.0\n1e30\n", "0.0\n1000000001\n", "-0.1\n0.0\n"}) {
        const auto path = writeTemp("times_range.txt", text);
        const std::string e = errorOf([&] { readKittiTimes(path); });
        EXPECT_NE(e.find(path + (text[0] == '-' ? ":1: time -0.1" : ":2: time 1")), std::string::npos) << text << " -> " << e;
        EXPECT_NE(e.find("is outside 0 to 1000000000 s"), std::string::npos) << e;
    }
}

// #18 point 10: a number that does not parse is named as such, not as a wrong count.
TEST(Poses, ATokenThatIsNotAFiniteNumberIsNamedWithItsLine) {
    const std::string row = "1 0 0 0 0 1 0 0 0 0 1 0\n";
    struct Case {
        std::string text, expected;
    };
    for (const Case& c : {Case{row + "1 0 0 nan 0 1 0 0 0 0 1 0\n", ":2: 'nan' is not a finite number"},
                          Case{row + "1 0 0 inf 0 1 0 0 0 0 1 0\n", ":2: 'inf' is not a finite number"},
                          Case{"1 0 0 0 0 1 0 0 0 0 1 0x\n", ":1: '0x' is not a number"},
                          Case{"1 0 0 0 0 1 0 0 0 0 1 1e999\n", ":1: '1e999' is not a finite number"},
                          Case{"1 0 0 0 0 1 0 0 0 0 1\n", ":1: expected 12 numbers (row-major 3x4 KITTI pose), found 11"}}) {
        const auto path = writeTemp("poses_nan.txt", c.text);
        const std::string e = errorOf([&] { readKittiPoses(path); });
        EXPECT_NE(e.find(path + c.expected), std::string::npos) << c.text << " -> " << e;
    }
    const auto tum = writeTemp("nan.tum", "1.0 1 2 NaN 0 0 0 1\n");
    EXPECT_NE(errorOf([&] { readTumTrajectory(tum); }).find(":1: 'NaN' is not a finite number"), std::string::npos);
    const auto calib = writeTemp("calib_nan.txt", "Tr: 1 0 0 0 0 1 0 0 0 0 1 nan\n");
    EXPECT_NE(errorOf([&] { readKittiCalibTr(calib); }).find(":1: 'nan' is not a finite number"), std::string::npos);
}

}  // namespace
