#include <gseg/map/world_scan.hpp>

#include <gseg/mrpt/observation_points.hpp>
#include <gseg/text.hpp>

#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <chrono>
#include <cmath>
#include <stdexcept>

namespace gseg::map {
namespace {

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
    return gseg::mrpt::scanPartOfLabel(obs.sensorLabel);
}

WorldScan segmentToWorld(const ::mrpt::obs::CObservation& obs, const ::mrpt::poses::CPose3D& robotPose,
                         gseg::mrpt::ScanSegmenter& segmenter, ScanTimes* times, gseg::mrpt::HeightCheck check) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<float> levelled = gseg::mrpt::levelledPoints(obs);
    if (levelled.empty()) throw std::invalid_argument("observation '" + obs.sensorLabel + "' has no points");
    const PointCloudView cloud(levelled.data(), levelled.size() / 4, 4 * sizeof(float));
    WorldScan out;
    gseg::mrpt::ScanSegmentation seg = segmenter.segment(cloud, false, check);
    if (seg.heightFallback()) out.notes.heightNote = seg.height.describe();
    out.notes.heightWarning = std::move(seg.heightWarning);
    const Result& r = seg.result;
    const auto t1 = std::chrono::steady_clock::now();

    // Levelled frame = sensor position with the robot's axes: world = robot pose + sensor offset.
    ::mrpt::poses::CPose3D sensorPose;
    obs.getSensorPose(sensorPose);
    const ::mrpt::poses::CPose3D levelledToWorld =
        robotPose + ::mrpt::poses::CPose3D(sensorPose.x(), sensorPose.y(), sensorPose.z(), 0, 0, 0);
    out.ground.reserve(3 * r.numGround);
    out.obstacles.reserve(3 * r.numNonGround);
    // Points without a return, and reflections below the ground, are neither ground nor obstacles.
    out.notes.reflections = r.belowGround.size();
    gseg::mrpt::forEachSplitPoint(cloud, r, [&](std::size_t i, bool ground) {
        pushWorld(levelledToWorld, &levelled[4 * i], ground ? out.ground : out.obstacles);
    });
    out.sensorOrigin = originOf(obs, robotPose);
    if (times) {
        times->segmentation += std::chrono::duration<double>(t1 - t0).count();
        times->transform += secondsSince(t1);
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
