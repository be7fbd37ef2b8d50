#pragma once
/// \file observation_points.hpp
/// Points of MRPT LiDAR observations, as x, y, z, intensity floats.
///
/// Frames: the *sensor frame* is the observation's own; the *levelled frame* has its origin at the
/// sensor and axes of the vehicle (the rotation of `sensorPose` applied, not its translation), so
/// with a level vehicle z points up and the ground lies at z = -(sensor height). That is the frame
/// GroundSegmenter expects (Params::distToGround = sensor height above the ground).

#include <string>
#include <vector>

namespace mrpt::obs {
class CObservation;
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

/// sensorFramePoints() then levelPoints() with the observation's own sensorPose.
std::vector<float> levelledPoints(const ::mrpt::obs::CObservation& obs);

}  // namespace gseg::mrpt
