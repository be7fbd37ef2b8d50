#include <gseg/mrpt/observation_points.hpp>

#include <mrpt/maps/CPointsMapXYZI.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/poses/CPose3D.h>

#include <stdexcept>

namespace gseg::mrpt {
namespace {

std::vector<float> fromVelodyne(const ::mrpt::obs::CObservationVelodyneScan& scan) {
    const ::mrpt::obs::CObservationVelodyneScan* src = &scan;
    ::mrpt::obs::CObservationVelodyneScan generated;
    if (scan.point_cloud.x.empty()) {
        if (scan.scan_packets.empty())
            throw std::invalid_argument("CObservationVelodyneScan '" + scan.sensorLabel +
                                        "' has neither points nor packets");
        generated = scan;  // generatePointCloud() is not const; leave the caller's scan untouched
        generated.generatePointCloud();
        src = &generated;
    }
    const auto& pc = src->point_cloud;
    std::vector<float> out(4 * pc.x.size());
    for (std::size_t i = 0; i < pc.x.size(); ++i) {
        out[4 * i] = pc.x[i], out[4 * i + 1] = pc.y[i], out[4 * i + 2] = pc.z[i];
        out[4 * i + 3] = i < pc.intensity.size() ? float(pc.intensity[i]) : 0.f;
    }
    return out;
}

std::vector<float> fromPointsMap(const ::mrpt::maps::CPointsMap& map) {
    const auto& xs = map.getPointsBufferRef_x();
    const auto& ys = map.getPointsBufferRef_y();
    const auto& zs = map.getPointsBufferRef_z();
    const auto* xyzi = dynamic_cast<const ::mrpt::maps::CPointsMapXYZI*>(&map);
    std::vector<float> out(4 * xs.size());
    for (std::size_t i = 0; i < xs.size(); ++i) {
        out[4 * i] = xs[i], out[4 * i + 1] = ys[i], out[4 * i + 2] = zs[i];
        out[4 * i + 3] = xyzi ? xyzi->getPointIntensity_fast(i) : 0.f;
    }
    return out;
}

}  // namespace

bool isLidarObservation(const ::mrpt::obs::CObservation& obs) {
    return dynamic_cast<const ::mrpt::obs::CObservationVelodyneScan*>(&obs) ||
           dynamic_cast<const ::mrpt::obs::CObservationPointCloud*>(&obs) ||
           dynamic_cast<const ::mrpt::obs::CObservation3DRangeScan*>(&obs);
}

std::vector<float> sensorFramePoints(const ::mrpt::obs::CObservation& obs) {
    if (const auto* v = dynamic_cast<const ::mrpt::obs::CObservationVelodyneScan*>(&obs)) return fromVelodyne(*v);
    if (const auto* pc = dynamic_cast<const ::mrpt::obs::CObservationPointCloud*>(&obs)) {
        if (!pc->pointcloud) throw std::invalid_argument("CObservationPointCloud '" + obs.sensorLabel + "' has no cloud");
        return fromPointsMap(*pc->pointcloud);
    }
    if (const auto* r = dynamic_cast<const ::mrpt::obs::CObservation3DRangeScan*>(&obs)) {
        if (!r->hasRangeImage && !r->hasPoints3D)
            throw std::invalid_argument("CObservation3DRangeScan '" + obs.sensorLabel + "' has no range image");
        if (r->hasPoints3D) {
            std::vector<float> out(4 * r->points3D_x.size(), 0.f);
            for (std::size_t i = 0; i < r->points3D_x.size(); ++i)
                out[4 * i] = r->points3D_x[i], out[4 * i + 1] = r->points3D_y[i], out[4 * i + 2] = r->points3D_z[i];
            return out;
        }
        ::mrpt::obs::CObservation3DRangeScan copy = *r;  // unprojectInto() is not const
        ::mrpt::maps::CSimplePointsMap pts;
        ::mrpt::obs::T3DPointsProjectionParams pp;
        pp.takeIntoAccountSensorPoseOnRobot = false;
        copy.unprojectInto(pts, pp);
        return fromPointsMap(pts);
    }
    throw std::invalid_argument(std::string(obs.GetRuntimeClass()->className) + " '" + obs.sensorLabel +
                                "' is not a 3D LiDAR observation (gseg needs a 3D point cloud)");
}

void levelPoints(std::vector<float>& xyzi, const ::mrpt::poses::CPose3D& sensorPose) {
    const auto R = sensorPose.getRotationMatrix();
    for (std::size_t i = 0; i + 3 < xyzi.size(); i += 4) {
        const double x = xyzi[i], y = xyzi[i + 1], z = xyzi[i + 2];
        xyzi[i] = float(R(0, 0) * x + R(0, 1) * y + R(0, 2) * z);
        xyzi[i + 1] = float(R(1, 0) * x + R(1, 1) * y + R(1, 2) * z);
        xyzi[i + 2] = float(R(2, 0) * x + R(2, 1) * y + R(2, 2) * z);
    }
}

std::vector<float> levelledPoints(const ::mrpt::obs::CObservation& obs) {
    std::vector<float> pts = sensorFramePoints(obs);
    ::mrpt::poses::CPose3D sensorPose;
    obs.getSensorPose(sensorPose);
    levelPoints(pts, sensorPose);
    return pts;
}

}  // namespace gseg::mrpt
