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

/// A pose as CPose3D::composePoint() applies it (MRPT 2.5: g = R l + t, each row's products and
/// sums in that order, in double), without a call per point: the same floats out.
class WorldTransform {
public:
    explicit WorldTransform(const ::mrpt::poses::CPose3D& pose) {
        const auto& rot = pose.getRotationMatrix();
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r_[3 * i + j] = rot(i, j);
        t_[0] = pose.x(), t_[1] = pose.y(), t_[2] = pose.z();
    }
    /// Point p (x, y, z of a 4-float point) into the world, appended to `out`.
    void push(const float* p, std::vector<float>& out) const {
        const double lx = p[0], ly = p[1], lz = p[2];
        out.push_back(float(r_[0] * lx + r_[1] * ly + r_[2] * lz + t_[0]));
        out.push_back(float(r_[3] * lx + r_[4] * ly + r_[5] * lz + t_[1]));
        out.push_back(float(r_[6] * lx + r_[7] * ly + r_[8] * lz + t_[2]));
    }

private:
    double r_[9], t_[3];
};

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
    const WorldTransform levelledToWorld(robotPose + ::mrpt::poses::CPose3D(sensorPose.x(), sensorPose.y(), sensorPose.z(), 0, 0, 0));
    out.ground.reserve(3 * r.numGround);
    out.obstacles.reserve(3 * r.numNonGround);
    // Points without a return, and reflections below the ground, are neither ground nor obstacles.
    out.notes.reflections = r.belowGround.size();
    gseg::mrpt::forEachSplitPoint(cloud, r, [&](std::size_t i, bool ground) {
        levelledToWorld.push(&levelled[4 * i], ground ? out.ground : out.obstacles);
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
    const WorldTransform sensorToWorld(robotPose + sensorPose);
    out.reserve(out.size() + 3 * (pts.size() / 4));
    for (std::size_t i = 0; i + 3 < pts.size(); i += 4) sensorToWorld.push(&pts[i], out);
    return originOf(obs, robotPose);
}

}  // namespace gseg::map
