#include <gseg/io/float_cast.hpp>
#include <gseg/mrpt/ground_filter.hpp>
#include <gseg/mrpt/observation_points.hpp>
#include <gseg/mrpt/scan_parts.hpp>

#include <mrpt/maps/CPointsMapXYZI.h>
#include <mrpt/poses/CPose3D.h>

#include <cmath>
#include <stdexcept>

INTERNAL_IMPLEMENTS_MRPT_OBJECT(GroundFilter, mrpt::rtti::CObject, gseg_filters, "gseg::GroundFilter")

// Registered by an ordinary static object defined after the class id above, so the id is set
// when this runs (MRPT_INITIALIZER's constructor function ran before it in clang's sanitizer
// builds: "registerClass invoked with a nullptr classname").
namespace {
struct RegisterGroundFilter {
    RegisterGroundFilter() { mrpt::rtti::registerClass(CLASS_ID_NAMESPACE(GroundFilter, gseg_filters)); }
} registerGroundFilter;
}  // namespace

namespace gseg_filters {

using gseg::PointCloudView;
namespace gm = gseg::mrpt;

GroundFilter::GroundFilter() : GroundFilter(gm::defaultConfig()) {}  // the one default: distToGround auto

GroundFilter::GroundFilter(const gm::LoadedConfig& config, OutputFrame frame)
    : outputFrame(frame), segmenter_(config) {}

void GroundFilter::loadConfig(const std::string& path) { segmenter_ = gm::ScanSegmenter(gm::loadConfig(path)); }

GroundFilter::Output GroundFilter::filter(const ::mrpt::obs::CObservation& obs) {
    ::mrpt::poses::CPose3D sensorPose;
    obs.getSensorPose(sensorPose);
    return split(gm::sensorFramePoints(obs), sensorPose, &obs, obs.sensorLabel);
}

GroundFilter::Output GroundFilter::filter(const ::mrpt::obs::CObservation& obs, const ::mrpt::poses::CPose3D& robotPose) {
    ::mrpt::poses::CPose3D sensorPose;
    obs.getSensorPose(sensorPose);
    return split(gm::sensorFramePoints(obs), sensorPose, &obs, obs.sensorLabel, &robotPose);
}

void GroundFilter::useDriveModel(std::shared_ptr<const gseg::TerrainModel> model) {
    driveModel_ = std::move(model);
    causal_.reset();
}

void GroundFilter::collectDriveEvidence(bool on) { collect_ = on; }

void GroundFilter::relabelWithDrive(const std::vector<float>& sensorXyzi, const ::mrpt::poses::CPose3D& worldSensorPose,
                                    Output& out) {
    const gseg::map::TraversabilityOptions& t = config().traversability;
    if (!t.driveTerrain) return;
    const std::vector<float> world = gm::transformedPoints(PointCloudView(sensorXyzi.data(), sensorXyzi.size() / 4, 16), worldSensorPose);
    const PointCloudView cloud(world.data(), world.size() / 3);
    const Eigen::Vector3d sensor(worldSensorPose.x(), worldSensorPose.y(), worldSensorPose.z());
    if (collect_) {
        out.driveEvidence = gseg::terrainSamples(cloud, out.result, t.terrainOptions().cellSize, t.maxRange, sensor);
    } else if (driveModel_) {
        const std::size_t changed = gseg::relabelWithModel(*driveModel_, cloud, out.result, &out.driveRelabelled);
        out.driveDropped = changed - out.driveRelabelled;  // after the call: the operands of '-' are unsequenced
    } else {
        if (!causal_) causal_ = std::make_unique<gseg::DriveTerrain>(t.terrainOptions(), t.maxRange);
        const std::size_t changed = causal_->label(cloud, out.result, sensor, &out.driveRelabelled);
        out.driveDropped = changed - out.driveRelabelled;
    }
}

GroundFilter::Output GroundFilter::filter(const ::mrpt::maps::CPointsMap& map, const std::string& label) {
    std::vector<float> xyzi(4 * map.size(), 0.f);
    const auto* withI = dynamic_cast<const ::mrpt::maps::CPointsMapXYZI*>(&map);
    for (std::size_t i = 0; i < map.size(); ++i) {
        map.getPointFast(i, xyzi[4 * i], xyzi[4 * i + 1], xyzi[4 * i + 2]);
        if (withI) xyzi[4 * i + 3] = withI->getPointIntensity_fast(i);
    }
    return split(xyzi, ::mrpt::poses::CPose3D(), nullptr, label);
}

GroundFilter::Output GroundFilter::split(const std::vector<float>& sensorXyzi, const ::mrpt::poses::CPose3D& sensorPose,
                                         const ::mrpt::obs::CObservation* source, const std::string& label,
                                         const ::mrpt::poses::CPose3D* robotPose) {
    std::vector<float> levelled = sensorXyzi;
    gm::levelPoints(levelled, sensorPose);
    const PointCloudView cloud(levelled.data(), levelled.size() / 4, 16);

    const gm::ScanSegmentation seg = segmenter_.segment(cloud, false);
    Output out;
    out.result = seg.result;
    out.distToGround = seg.distToGround;
    out.distToGroundEstimated = seg.distToGroundEstimated;
    out.heightWarning = seg.heightWarning;
    if (robotPose) relabelWithDrive(sensorXyzi, *robotPose + sensorPose, out);

    // The two halves, in the frame asked for.
    const bool vehicle = outputFrame == OutputFrame::Vehicle;
    auto ground = ::mrpt::maps::CPointsMapXYZI::Create(), obstacles = ::mrpt::maps::CPointsMapXYZI::Create();
    ground->reserve(out.result.numGround);
    out.reflections = out.result.belowGround.size();
    obstacles->reserve(out.result.numNonGround - out.result.numNonFinite - out.reflections);
    gm::forEachSplitPoint(cloud, out.result, [&](std::size_t i, bool isGround) {  // reflections and NaN points: neither
        const float* p = &sensorXyzi[4 * i];
        double x = p[0], y = p[1], z = p[2];
        if (vehicle) sensorPose.composePoint(p[0], p[1], p[2], x, y, z);
        auto& dst = isGround ? *ground : *obstacles;
        dst.insertPointFast(gseg::io::toFloat(x), gseg::io::toFloat(y), gseg::io::toFloat(z));
        dst.setPointIntensity(dst.size() - 1, p[3]);
    });
    auto make = [&](const ::mrpt::maps::CPointsMapXYZI::Ptr& pts, gm::ScanPart part) {
        auto obs = ::mrpt::obs::CObservationPointCloud::Create();
        obs->pointcloud = pts;
        obs->sensorLabel = gm::partLabel(label, part);
        obs->sensorPose = vehicle ? ::mrpt::poses::CPose3D() : sensorPose;
        if (source) obs->timestamp = source->timestamp;
        return obs;
    };
    out.ground = make(ground, gm::ScanPart::Ground);
    out.obstacles = make(obstacles, gm::ScanPart::Obstacles);
    return out;
}

}  // namespace gseg_filters
