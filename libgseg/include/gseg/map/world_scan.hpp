#pragma once
/// \file world_scan.hpp
/// From an MRPT observation and the robot pose to ground and obstacle points in the world frame,
/// with the sensor's world position as ray origin. The scan's mounting (`sensorPose`) is applied
/// to the points and to the origin (MRPT 2.5.8's COctoMap applies it to the origin only).

#include <gseg/mrpt/scan_parts.hpp>
#include <gseg/mrpt/segment_scan.hpp>
#include <gseg/point_cloud.hpp>

#include <Eigen/Core>

#include <string>
#include <vector>

namespace mrpt::obs {
class CObservation;
}
namespace mrpt::poses {
class CPose3D;
}

namespace gseg::map {

/// What segmenting a scan says besides its points; carried as it is from the WorldScan to the
/// ScanResult (map_builder.hpp). Empty for a rawlog-gseg pair's parts (not segmented again).
struct ScanNotes {
    std::size_t reflections = 0;  ///< points left out: more than belowGroundMargin below the ground (Result::belowGround)
    std::string heightNote;       ///< distToGround: auto could not estimate this scan: what was used instead
    std::string heightWarning;    ///< checkHeight: the scan contradicts the fixed distToGround (gseg::checkDistToGround())
};

/// One scan in the world frame.
struct WorldScan {
    std::vector<float> ground;     ///< x, y, z triples [m], world frame
    std::vector<float> obstacles;  ///< x, y, z triples [m], world frame
    Eigen::Vector3d sensorOrigin = Eigen::Vector3d::Zero();  ///< [m] sensor position, world frame
    ScanNotes notes;
    PointCloudView groundView() const { return PointCloudView(ground.data(), ground.size() / 3); }
    PointCloudView obstaclesView() const { return PointCloudView(obstacles.data(), obstacles.size() / 3); }
};

/// What an observation written by `rawlog-gseg` holds: its sensor label ends in `_ground` or
/// `_obstacles` (gseg/mrpt/scan_parts.hpp). Anything else is Raw (to be segmented).
using gseg::mrpt::ScanPart;
ScanPart scanPartOf(const ::mrpt::obs::CObservation& obs);

/// Where the per-scan work of one scan spent its time [s] (MapBuilder sums them into PhaseTimes).
struct ScanTimes {
    double segmentation = 0;  ///< points out of the observation, sensor height, segmentation
    double transform = 0;     ///< into the world frame
    double rayCasting = 0;    ///< into the scan's update (castScan())
};

/// Segments a 3D LiDAR observation (in its levelled frame, see observation_points.hpp) with the
/// configured height policy (gseg::mrpt::ScanSegmenter: fixed, or `distToGround: auto` per scan
/// with the configured fallback; notes.heightNote says when the fallback was used) and puts both classes
/// into the world frame with `robotPose` + the observation's sensorPose. Points without a return
/// and reflections below the ground (Result::belowGround) go into neither class. `check`: when a
/// fixed height is checked against the scan (notes.heightWarning; costs about one segmentation: the map
/// builder checks the first scan of a drive). `times`: its segmentation and transform seconds are
/// added to. Throws std::invalid_argument for a non-LiDAR observation or an empty scan.
WorldScan segmentToWorld(const ::mrpt::obs::CObservation& obs, const ::mrpt::poses::CPose3D& robotPose,
                         gseg::mrpt::ScanSegmenter& segmenter, ScanTimes* times = nullptr,
                         gseg::mrpt::HeightCheck check = gseg::mrpt::HeightCheck::Never);

/// Appends every point of `obs` (one class already) in the world frame to `out` (x, y, z
/// triples) and returns the sensor's world position.
Eigen::Vector3d appendWorldPoints(const ::mrpt::obs::CObservation& obs, const ::mrpt::poses::CPose3D& robotPose,
                                  std::vector<float>& out);

}  // namespace gseg::map
