#include <gseg/map/world_scan.hpp>

#include <gseg/mrpt/observation_points.hpp>

#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <gseg/sensor_height.hpp>

#include <chrono>
#include <stdexcept>

namespace gseg::map {
namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

Eigen::Vector3d originOf(const ::mrpt::obs::CObservation& obs, const ::mrpt::poses::CPose3D& robotPose) {
    ::mrpt::poses::CPose3D sensorPose;
    obs.getSensorPose(sensorPose);
    const ::mrpt::poses::CPose3D sensorInWorld = robotPose + sensorPose;
    return {sensorInWorld.x(), sensorInWorld.y(), sensorInWorld.z()};
}

/// Robot-frame point p (x, y, z of a 4-float point) into the world.
void pushWorld(const ::mrpt::poses::CPose3D& pose, const float* p, std::vector<float>& out) {
    double gx = 0, gy = 0, gz = 0;
    pose.composePoint(p[0], p[1], p[2], gx, gy, gz);
    out.push_back(float(gx)), out.push_back(float(gy)), out.push_back(float(gz));
}

}  // namespace

ScanPart scanPartOf(const ::mrpt::obs::CObservation& obs) {
    if (endsWith(obs.sensorLabel, "_ground")) return ScanPart::Ground;
    if (endsWith(obs.sensorLabel, "_obstacles")) return ScanPart::Obstacles;
    return ScanPart::Raw;
}

WorldScan segmentToWorld(const ::mrpt::obs::CObservation& obs, const ::mrpt::poses::CPose3D& robotPose,
                         GroundSegmenter& segmenter, bool autoHeight, WorldScanTimes* times) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<float> levelled = gseg::mrpt::levelledPoints(obs);
    if (levelled.empty()) throw std::invalid_argument("observation '" + obs.sensorLabel + "' has no points");
    const PointCloudView cloud(levelled.data(), levelled.size() / 4, 4 * sizeof(float));
    if (autoHeight) {
        const auto h = estimateSensorHeight(cloud);
        if (!h.valid) throw std::invalid_argument("'" + obs.sensorLabel + "': distToGround: auto found no ground level");
        Params p = segmenter.params();
        p.distToGround = h.height;
        segmenter = GroundSegmenter(p);
    }
    const Result r = segmenter.segment(cloud, false);
    const auto t1 = std::chrono::steady_clock::now();

    // Levelled frame = sensor position with the robot's axes: world = robot pose + sensor offset.
    ::mrpt::poses::CPose3D sensorPose;
    obs.getSensorPose(sensorPose);
    const ::mrpt::poses::CPose3D levelledToWorld =
        robotPose + ::mrpt::poses::CPose3D(sensorPose.x(), sensorPose.y(), sensorPose.z(), 0, 0, 0);
    WorldScan out;
    out.ground.reserve(3 * r.numGround);
    out.obstacles.reserve(3 * r.numNonGround);
    for (std::size_t i = 0; i < r.labels.size(); ++i)
        pushWorld(levelledToWorld, &levelled[4 * i], r.labels[i] ? out.ground : out.obstacles);
    out.sensorOrigin = originOf(obs, robotPose);
    if (times) {
        times->segmentation += std::chrono::duration<double>(t1 - t0).count();
        times->transform += std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    }
    return out;
}

Eigen::Vector3d appendWorldPoints(const ::mrpt::obs::CObservation& obs, const ::mrpt::poses::CPose3D& robotPose,
                                  std::vector<float>& out) {
    const std::vector<float> pts = gseg::mrpt::sensorFramePoints(obs);
    ::mrpt::poses::CPose3D sensorPose;
    obs.getSensorPose(sensorPose);
    const ::mrpt::poses::CPose3D sensorToWorld = robotPose + sensorPose;
    out.reserve(out.size() + 3 * (pts.size() / 4));
    for (std::size_t i = 0; i + 3 < pts.size(); i += 4) pushWorld(sensorToWorld, &pts[i], out);
    return originOf(obs, robotPose);
}

}  // namespace gseg::map
