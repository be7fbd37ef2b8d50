#include <gseg/mrpt/observation_points.hpp>

#include <mrpt/maps/CPointsMapXYZI.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/obs/VelodyneCalibration.h>
#include <mrpt/poses/CPose3D.h>

#include <gseg/io/float_cast.hpp>

#include <cctype>
#include <cmath>
#include <stdexcept>

namespace gseg::mrpt {
namespace {

std::string describe(const ::mrpt::obs::CObservation& obs) {
    std::string cls = obs.GetRuntimeClass()->className;
    if (cls.rfind("mrpt::obs::", 0) == 0) cls = cls.substr(11);
    return cls + " '" + obs.sensorLabel + "'";
}

// Vectors that must hold one value per point (an empty optional one is allowed).
void checkSameLength(const ::mrpt::obs::CObservation& obs, const char* what,
                     std::initializer_list<std::pair<const char*, std::size_t>> sizes, bool lastOptional) {
    const std::size_t n = sizes.begin()->second;
    std::size_t k = 0;
    bool ok = true;
    for (const auto& s : sizes) {
        const bool optional = lastOptional && ++k == sizes.size();
        ok = ok && (s.second == n || (optional && s.second == 0));
    }
    if (ok) return;
    std::string list;
    for (const auto& s : sizes) list += std::string(list.empty() ? "" : ", ") + s.first + " " + std::to_string(s.second);
    throw std::invalid_argument(describe(obs) + ": " + what + " vectors differ in length (" + list + ")");
}

std::vector<float> fromVelodyne(const ::mrpt::obs::CObservationVelodyneScan& scan) {
    const ::mrpt::obs::CObservationVelodyneScan* src = &scan;
    ::mrpt::obs::CObservationVelodyneScan generated;
    const auto& given = scan.point_cloud;
    if (given.x.empty() && given.y.empty() && given.z.empty()) {
        if (scan.scan_packets.empty())
            throw std::invalid_argument("CObservationVelodyneScan '" + scan.sensorLabel +
                                        "' has neither points nor packets");
        generated = scan;  // generatePointCloud() is not const; leave the caller's scan untouched
        generated.generatePointCloud();
        src = &generated;
    }
    const auto& pc = src->point_cloud;
    checkSameLength(scan, "point_cloud",
                    {{"x", pc.x.size()}, {"y", pc.y.size()}, {"z", pc.z.size()}, {"intensity", pc.intensity.size()}}, true);
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

// Vertical angle [rad] of each row of a rotating scan, from the default calibration of its model.
std::vector<double> rowElevations(const ::mrpt::obs::CObservationRotatingScan& scan) {
    std::string model;
    for (char c : scan.lidarModel)
        if (std::isalnum(static_cast<unsigned char>(c))) model += char(std::toupper(static_cast<unsigned char>(c)));
    const char* known = nullptr;
    for (const char* m : {"VLP16", "HDL32", "HDL64"})
        if (model.rfind(m, 0) == 0) known = m;
    if (!known)
        throw std::invalid_argument(describe(scan) + ": no beam angles known for lidarModel '" + scan.lidarModel +
                                    "' (gseg knows VLP-16, HDL-32 and HDL-64)");
    const auto& calib = ::mrpt::obs::VelodyneCalibration::LoadDefaultCalibration(known).laser_corrections;
    if (calib.size() != std::size_t(scan.rangeImage.rows()))
        throw std::invalid_argument(describe(scan) + ": " + std::to_string(scan.rangeImage.rows()) +
                                    " range image rows, but a " + scan.lidarModel + " has " +
                                    std::to_string(calib.size()) + " beams");
    std::vector<double> out;
    for (const auto& l : calib) out.push_back(l.verticalCorrection * M_PI / 180.0);
    return out;
}

// The columns that carry the sweep. MRPT 2.5.8's CObservationRotatingScan::fromVelodyne sizes the
// range image (2 x) rowCount times too wide and fills only the first columns (one per firing, the
// columns of the mrpt-common sample: 1800 of 28800): when every return lies in the first
// columns / rows (or columns / (2 rows), dual return) columns, the sweep spans those.
std::size_t sweepColumns(const ::mrpt::math::CMatrix_u16& range) {
    const std::size_t rows = std::size_t(range.rows()), cols = std::size_t(range.cols());
    std::size_t last = 0;
    for (std::size_t c = 0; c < cols; ++c)
        for (std::size_t r = 0; r < rows; ++r)
            if (range(long(r), long(c))) last = c;
    for (std::size_t d : {2 * rows, rows})
        if (rows > 1 && cols % d == 0 && last < cols / d) return cols / d;
    return cols;
}

// Points of a rotating scan's range image: row r is beam r (vertical angle from the model's
// calibration), column c fires at startAzimuth + azimuthSpan * c / columns; zero range = no return.
// Axes as MRPT's Velodyne point clouds: x forward, y left, z up.
std::vector<float> fromRotatingScan(const ::mrpt::obs::CObservationRotatingScan& scan) {
    const auto& range = scan.rangeImage;
    const std::size_t rows = std::size_t(range.rows()), cols = std::size_t(range.cols());
    if (rows == 0 || cols == 0) throw std::invalid_argument(describe(scan) + ": empty range image");
    if (rows != scan.rowCount || cols != scan.columnCount)
        throw std::invalid_argument(describe(scan) + ": range image " + std::to_string(rows) + " x " +
                                    std::to_string(cols) + " but rowCount x columnCount " +
                                    std::to_string(scan.rowCount) + " x " + std::to_string(scan.columnCount));
    if (rows == 1)
        throw std::invalid_argument(describe(scan) + " is a 2D scan (one row): gseg needs a 3D point cloud");
    const auto& intensity = scan.intensityImage;
    const bool withIntensity = intensity.rows() > 0 || intensity.cols() > 0;
    if (withIntensity && (std::size_t(intensity.rows()) != rows || std::size_t(intensity.cols()) != cols))
        throw std::invalid_argument(describe(scan) + ": intensity image size differs from the range image's");
    if (!std::isfinite(scan.rangeResolution) || scan.rangeResolution <= 0 || !std::isfinite(scan.startAzimuth) ||
        !std::isfinite(scan.azimuthSpan) || std::abs(scan.azimuthSpan) > 4 * M_PI)
        throw std::invalid_argument(describe(scan) + ": invalid rangeResolution, startAzimuth or azimuthSpan");
    const std::vector<double> elevation = rowElevations(scan);
    const std::size_t sweep = sweepColumns(range);
    std::vector<float> out;
    for (std::size_t c = 0; c < cols; ++c) {
        const double az = scan.startAzimuth + scan.azimuthSpan * double(c) / double(sweep);
        for (std::size_t r = 0; r < rows; ++r) {
            const std::uint16_t raw = range(long(r), long(c));
            if (!raw) continue;
            const double d = raw * scan.rangeResolution, horizontal = d * std::cos(elevation[r]);
            out.insert(out.end(), {gseg::io::toFloat(horizontal * std::cos(az)), gseg::io::toFloat(-horizontal * std::sin(az)),
                                   gseg::io::toFloat(d * std::sin(elevation[r])),
                                   withIntensity ? float(intensity(long(r), long(c))) : 0.f});
        }
    }
    return out;
}

}  // namespace

bool isLidarObservation(const ::mrpt::obs::CObservation& obs) {
    return dynamic_cast<const ::mrpt::obs::CObservationVelodyneScan*>(&obs) ||
           dynamic_cast<const ::mrpt::obs::CObservationPointCloud*>(&obs) ||
           dynamic_cast<const ::mrpt::obs::CObservation3DRangeScan*>(&obs) ||
           dynamic_cast<const ::mrpt::obs::CObservationRotatingScan*>(&obs);
}

std::vector<float> sensorFramePoints(const ::mrpt::obs::CObservation& obs) {
    if (const auto* v = dynamic_cast<const ::mrpt::obs::CObservationVelodyneScan*>(&obs)) return fromVelodyne(*v);
    if (const auto* pc = dynamic_cast<const ::mrpt::obs::CObservationPointCloud*>(&obs)) {
        if (!pc->pointcloud) throw std::invalid_argument("CObservationPointCloud '" + obs.sensorLabel + "' has no cloud");
        return fromPointsMap(*pc->pointcloud);
    }
    if (const auto* rot = dynamic_cast<const ::mrpt::obs::CObservationRotatingScan*>(&obs)) return fromRotatingScan(*rot);
    if (const auto* r = dynamic_cast<const ::mrpt::obs::CObservation3DRangeScan*>(&obs)) {
        if (!r->hasRangeImage && !r->hasPoints3D)
            throw std::invalid_argument("CObservation3DRangeScan '" + obs.sensorLabel + "' has no range image");
        if (r->hasPoints3D) {
            checkSameLength(obs, "points3D",
                            {{"x", r->points3D_x.size()}, {"y", r->points3D_y.size()}, {"z", r->points3D_z.size()}},
                            false);
            std::vector<float> out(4 * r->points3D_x.size(), 0.f);
            for (std::size_t i = 0; i < r->points3D_x.size(); ++i)
                out[4 * i] = r->points3D_x[i], out[4 * i + 1] = r->points3D_y[i], out[4 * i + 2] = r->points3D_z[i];
            return out;
        }
        // MRPT "autofixes" a camera whose resolution differs from the image (a warning on stderr, then
        // the intrinsics of one size applied to the other): refuse instead.
        const auto& cam = r->cameraParams;
        if (r->rangeImage.rows() == 0 || r->rangeImage.cols() == 0 || cam.ncols != std::uint32_t(r->rangeImage.cols()) ||
            cam.nrows != std::uint32_t(r->rangeImage.rows()))
            throw std::invalid_argument(describe(obs) + ": range image " + std::to_string(r->rangeImage.cols()) + " x " +
                                        std::to_string(r->rangeImage.rows()) + " but camera " + std::to_string(cam.ncols) +
                                        " x " + std::to_string(cam.nrows));
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
        xyzi[i] = gseg::io::toFloat(R(0, 0) * x + R(0, 1) * y + R(0, 2) * z);
        xyzi[i + 1] = gseg::io::toFloat(R(1, 0) * x + R(1, 1) * y + R(1, 2) * z);
        xyzi[i + 2] = gseg::io::toFloat(R(2, 0) * x + R(2, 1) * y + R(2, 2) * z);
    }
}

std::vector<float> transformedPoints(const gseg::PointCloudView& points, const ::mrpt::poses::CPose3D& pose) {
    std::vector<float> out(3 * points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        double x = 0, y = 0, z = 0;
        pose.composePoint(points.x(i), points.y(i), points.z(i), x, y, z);
        out[3 * i] = float(x), out[3 * i + 1] = float(y), out[3 * i + 2] = float(z);
    }
    return out;
}

std::vector<float> levelledPoints(const ::mrpt::obs::CObservation& obs) {
    std::vector<float> pts = sensorFramePoints(obs);
    ::mrpt::poses::CPose3D sensorPose;
    obs.getSensorPose(sensorPose);
    levelPoints(pts, sensorPose);
    return pts;
}

std::shared_ptr<::mrpt::obs::CObservationPointCloud> pointCloudObservation(const float* xyzi, std::size_t points,
                                                                          const ::mrpt::poses::CPose3D& sensorPose,
                                                                          const std::string& label, ::mrpt::Clock::time_point t) {
    auto pc = ::mrpt::maps::CPointsMapXYZI::Create();
    pc->reserve(points);
    for (std::size_t i = 0; i < points; ++i) {
        pc->insertPointFast(xyzi[4 * i], xyzi[4 * i + 1], xyzi[4 * i + 2]);
        pc->setPointIntensity(i, xyzi[4 * i + 3]);
    }
    auto obs = ::mrpt::obs::CObservationPointCloud::Create();
    obs->pointcloud = pc;
    obs->sensorLabel = label;
    obs->timestamp = t;
    obs->sensorPose = sensorPose;
    return obs;
}

}  // namespace gseg::mrpt
