#pragma once
/// \file observation_points.hpp
/// Points of MRPT LiDAR observations, as x, y, z, intensity floats.
///
/// Frames: the *sensor frame* is the observation's own; the *levelled frame* has its origin at the
/// sensor and axes of the vehicle (the rotation of `sensorPose` applied, not its translation), so
/// with a level vehicle z points up and the ground lies at z = -(sensor height). That is the frame
/// GroundSegmenter expects (Params::distToGround = sensor height above the ground).

#include <gseg/point_cloud.hpp>

#include <mrpt/core/Clock.h>

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace mrpt::obs {
class CObservation;
class CObservationPointCloud;
}
namespace mrpt::poses {
class CPose3D;
}

namespace gseg::mrpt {

/// True for the observation kinds gseg segments: CObservationVelodyneScan,
/// CObservationPointCloud, CObservation3DRangeScan and CObservationRotatingScan.
bool isLidarObservation(const ::mrpt::obs::CObservation& obs);

/// x, y, z, intensity (4 floats per point) in the sensor frame. A Velodyne scan's point cloud is
/// generated from its packets only if it has none; a 3D range scan is unprojected; a rotating
/// scan's range image gives one point per non-zero range (beam angles from the default
/// calibration of its lidarModel: VLP-16, HDL-32, HDL-64). Throws std::invalid_argument naming the
/// class for any other kind (a 2D laser scan has no ground to segment), for a scan with neither
/// points nor packets/range image, and for malformed ones (point vectors of different lengths, a
/// range image whose size disagrees with its header, an unknown lidarModel).
std::vector<float> sensorFramePoints(const ::mrpt::obs::CObservation& obs);

/// Rotates 4-float points from the sensor frame into the levelled frame (see above).
void levelPoints(std::vector<float>& xyzi, const ::mrpt::poses::CPose3D& sensorPose);

/// x, y, z (3 floats a point) of `points` moved by `pose` (e.g. world from sensor); a point with a
/// NaN stays NaN. The drive's context (#31) labels scans in the world frame.
std::vector<float> transformedPoints(const gseg::PointCloudView& points, const ::mrpt::poses::CPose3D& pose);

/// sensorFramePoints() then levelPoints() with the observation's own sensorPose.
std::vector<float> levelledPoints(const ::mrpt::obs::CObservation& obs);

/// The other way: x, y, z, intensity floats (4 per point, sensor frame) as an MRPT point-cloud
/// observation (CPointsMapXYZI, the floats unchanged) mounted at `sensorPose` on the vehicle, with
/// `label` and the time stamp `t`. kitti2rawlog's scans and the Python map builder's are made here.
std::shared_ptr<::mrpt::obs::CObservationPointCloud> pointCloudObservation(const float* xyzi, std::size_t points,
                                                                          const ::mrpt::poses::CPose3D& sensorPose,
                                                                          const std::string& label, ::mrpt::Clock::time_point t);

}  // namespace gseg::mrpt
