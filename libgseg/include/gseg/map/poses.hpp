#pragma once
/// \file poses.hpp
/// Trajectory files: TUM (`t x y z qx qy qz qw`) and KITTI odometry (one row-major 3x4 matrix per
/// scan, camera-0 frame) with the sequence's `calib.txt` (`Tr`: velodyne to camera-0).
///
/// Frames: a KITTI pose P_k maps camera-0 of frame k into camera-0 of frame 0. The velodyne of
/// frame k in the velodyne frame of frame 0 (z up, ground near z = -1.73 m) is Tr^-1 * P_k * Tr.

#include <Eigen/Geometry>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace gseg::map {

/// One pose of a trajectory with its time stamp.
struct StampedPose {
    double t = 0;                                         ///< [s] time stamp (TUM: as written in the file)
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< pose in the trajectory's world frame
};

/// Kind of a trajectory file.
enum class PoseFileFormat { Tum, Kitti };

/// Reads a TUM trajectory: one `t x y z qx qy qz qw` per line; `#` comments and blank lines are
/// skipped. Throws std::runtime_error naming the file and line on a missing file, a token that is
/// not a finite number (named: "'nan' is not a finite number"), a line without 8 numbers, a zero
/// quaternion, or time stamps that are not increasing.
std::vector<StampedPose> readTumTrajectory(const std::string& path);

/// Reads a KITTI poses file: 12 numbers per line (row-major 3x4 [R | t]). Throws
/// std::runtime_error naming the file and line on a missing file, a token that is not a finite
/// number (named), a line without 12 numbers, or an R that is not a rotation (R^T R != I or det R != 1, within kRotationTolerance).
std::vector<Eigen::Isometry3d> readKittiPoses(const std::string& path);

/// Reads `Tr:` (velodyne to camera-0, 12 numbers) from a KITTI `calib.txt`. Throws
/// std::runtime_error naming the file (and line) if it is missing, has no valid `Tr:` line, or its
/// rotation is not one (an all-zero Tr, a scaled rotation).
Eigen::Isometry3d readKittiCalibTr(const std::string& path);

/// Largest time accepted in a KITTI `times.txt` [s since the drive started]: about 31.7 years.
/// (MRPT time stamps count 100 ns ticks in 64 bits: 1e13 s would wrap to 1970.)
constexpr double kMaxKittiTime = 1e9;

/// Reads a KITTI `times.txt`: one time [s] per line. Throws std::runtime_error naming the file and
/// line on anything but one finite number per line, a time outside 0 to kMaxKittiTime, or a time
/// before the previous one.
std::vector<double> readKittiTimes(const std::string& path);

/// Largest |R^T R - I| entry and |det R - 1| accepted for a rotation read from a file (the files
/// print 7 to 12 significant digits).
constexpr double kRotationTolerance = 1e-3;

/// Tr^-1 * P_k * Tr for every k: the velodyne poses in the frame of the first velodyne pose's
/// world (velodyne frame of frame 0 when P_0 is the identity).
std::vector<Eigen::Isometry3d> kittiToVelodyneFrame(const std::vector<Eigen::Isometry3d>& cameraPoses,
                                                    const Eigen::Isometry3d& tr);

/// Guesses the format from the first data line: 8 numbers TUM, 12 numbers KITTI. Throws
/// std::runtime_error naming the file if it is missing, empty, or neither.
PoseFileFormat detectPoseFileFormat(const std::string& path);

/// Index of the pose whose time stamp is nearest to `t`, if it lies within `tolerance` seconds.
/// `trajectory` must be sorted by time (readTumTrajectory() guarantees it).
std::optional<std::size_t> nearestPose(const std::vector<StampedPose>& trajectory, double t, double tolerance);

}  // namespace gseg::map
