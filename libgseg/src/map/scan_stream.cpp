#include <gseg/map/scan_stream.hpp>

#include <gseg/map/world_scan.hpp>
#include <gseg/mrpt/observation_points.hpp>
#include <gseg/text.hpp>

#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CActionRobotMovement3D.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationRobotPose.h>
#include <mrpt/obs/CSensoryFrame.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;
using ::mrpt::poses::CPose3D;

namespace gseg::map {
namespace {

CPose3D toPose(const Eigen::Isometry3d& p) {
    ::mrpt::math::CMatrixDouble44 m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = p.matrix()(r, c);
    return CPose3D(m);
}

/// "X,Y,Z" in metres.
Eigen::Vector3d parseOrigin(const std::string& text) {
    Eigen::Vector3d v;
    char tail = 0;
    if (std::sscanf(text.c_str(), "%lf,%lf,%lf%c", &v.x(), &v.y(), &v.z(), &tail) != 3 || !v.allFinite())
        throw std::invalid_argument("--origin needs 'first' or X,Y,Z in metres, got '" + text + "'");
    return v;
}

const ::mrpt::obs::CObservation& anyPart(const ScanJob& job) {
    return job.raw ? *job.raw : job.ground ? *job.ground : *job.obstacles;
}

}  // namespace

std::string ScanJob::describe() const {
    char buf[200];
    std::snprintf(buf, sizeof buf, "scan %zu ('%s' at rawlog entry %zu, t = %.6f s)", index, label.c_str(), entry, t);
    return buf;
}

ScanStream::ScanStream(const PoseConfig& config) : config_(config), reader_(config.input) {
    if (!config_.origin.empty() && config_.origin != "first") shift_ = parseOrigin(config_.origin);
    if (config_.poses.empty()) return;
    if (gseg::map::detectPoseFileFormat(config_.poses) == gseg::map::PoseFileFormat::Tum) {
        tum_ = gseg::map::readTumTrajectory(config_.poses);
        return;
    }
    const std::string calib =
        config_.calib.empty() ? (fs::path(config_.poses).parent_path() / "calib.txt").string() : config_.calib;
    kitti_ = gseg::map::kittiToVelodyneFrame(gseg::map::readKittiPoses(config_.poses), gseg::map::readKittiCalibTr(calib));
}

std::string ScanStream::poseSource() const { return config_.poses.empty() ? "the rawlog" : config_.poses; }

void ScanStream::fill(std::size_t n) {
    const auto t0 = std::chrono::steady_clock::now();
    while (ready_.size() < n && !eof_) {
        const auto obj = reader_.next();
        if (!obj) {
            eof_ = true;
            close();
            break;
        }
        visit(reader_.index(), obj);
    }
    readSeconds_ += secondsSince(t0);
}

const std::deque<ScanJob>& ScanStream::prefetch(std::size_t n) {
    fill(n);
    return ready_;
}

bool ScanStream::next(ScanJob& job) {
    fill(1);
    if (ready_.empty()) return false;
    job = std::move(ready_.front());
    ready_.pop_front();
    return true;
}

void ScanStream::visit(std::size_t entry, const std::shared_ptr<::mrpt::serialization::CSerializable>& obj) {
    if (auto sf = std::dynamic_pointer_cast<::mrpt::obs::CSensoryFrame>(obj)) {
        if (!rawlogPose_) rawlogPose_ = CPose3D();  // sensory-frame layout: odometry starts at the origin
        for (std::size_t i = 0; i < sf->size(); ++i) observation(entry, sf->getObservationByIndex(i));
    } else if (auto acts = std::dynamic_pointer_cast<::mrpt::obs::CActionCollection>(obj)) {
        if (!rawlogPose_) rawlogPose_ = CPose3D();
        const ::mrpt::obs::CActionCollection& actions = *acts;
        for (std::size_t i = 0; i < actions.size(); ++i) {
            const ::mrpt::obs::CAction* a = &actions.get(i);
            if (auto m3 = dynamic_cast<const ::mrpt::obs::CActionRobotMovement3D*>(a)) {
                rawlogPose_ = *rawlogPose_ + m3->poseChange.mean;
            } else if (auto m2 = dynamic_cast<const ::mrpt::obs::CActionRobotMovement2D*>(a)) {
                rawlogPose_ = *rawlogPose_ + CPose3D(m2->poseChange->getMeanVal());
            }
        }
    } else if (auto obs = std::dynamic_pointer_cast<::mrpt::obs::CObservation>(obj)) {
        observation(entry, obs);
    }
}

void ScanStream::observation(std::size_t entry, const ::mrpt::obs::CObservation::Ptr& obs) {
    if (auto rp = std::dynamic_pointer_cast<::mrpt::obs::CObservationRobotPose>(obs)) {
        rawlogPose_ = rp->pose.mean;
        return;
    }
    if (auto odo = std::dynamic_pointer_cast<::mrpt::obs::CObservationOdometry>(obs)) {
        rawlogPose_ = CPose3D(odo->odometry);
        return;
    }
    const ScanPart part = gseg::map::scanPartOf(*obs);
    if (part == ScanPart::Raw && !gseg::mrpt::isLidarObservation(*obs)) return;
    const double t = ::mrpt::Clock::toDouble(obs->timestamp);
    const std::string label = gseg::mrpt::baseLabelOf(obs->sensorLabel);
    auto slotOf = [part](ScanJob& j) -> ::mrpt::obs::CObservation::Ptr& {
        return part == ScanPart::Raw ? j.raw : part == ScanPart::Ground ? j.ground : j.obstacles;
    };
    if (open_ && open_->label == label && open_->t == t && !slotOf(*open_)) {  // same scan: raw form or other part
        slotOf(*open_) = obs;
        return;
    }
    close();  // a new scan begins
    open_ = ScanJob();
    open_->entry = entry, open_->label = label, open_->t = t;
    slotOf(*open_) = obs;
    openPose_ = rawlogPose_;
}

void ScanStream::close() {
    if (!open_) return;
    ScanJob job = std::move(*open_);
    open_.reset();
    if (job.raw && job.presegmented()) {  // rawlog-gseg output without --replace: use the pair
        ++rawWithPair_;
        job.raw.reset();
    }
    job.index = emitted_++;
    job.robotPose = poseOf(job, openPose_);
    job.fraction = reader_.fraction();
    ready_.push_back(std::move(job));
}

CPose3D ScanStream::poseOf(const ScanJob& job, const std::optional<CPose3D>& rawlogPose) {
    CPose3D pose;
    if (config_.poses.empty()) {
        if (!rawlogPose)
            throw std::runtime_error(config_.input + ": no poses in the rawlog before " + job.describe() +
                                     " (no CObservationRobotPose, CObservationOdometry or odometry action): give --poses "
                                     "with a TUM or KITTI file");
        pose = *rawlogPose;
    } else if (!tum_.empty()) {
        const auto i = gseg::map::nearestPose(tum_, job.t, config_.poseTolerance);
        if (!i)
            throw std::runtime_error(config_.poses + ": no pose within " + std::to_string(config_.poseTolerance) + " s of " +
                                     job.describe());
        pose = toPose(tum_[*i].pose);
    } else {
        if (job.index >= kitti_.size())
            throw std::runtime_error(config_.poses + ": " + std::to_string(kitti_.size()) + " poses, but " + job.describe() +
                                     " needs pose " + std::to_string(job.index + 1) + " (one KITTI pose per scan, in order)");
        CPose3D mountingInv;  // KITTI poses are the velodyne's: remove the mounting
        anyPart(job).getSensorPose(mountingInv);
        mountingInv.inverse();
        pose = toPose(kitti_[job.index]) + mountingInv;
    }
    if (config_.origin == "first" && !shift_) {  // whole metres: the voxel grid stays where it was
        CPose3D sensorPose;
        anyPart(job).getSensorPose(sensorPose);
        const CPose3D sensor = pose + sensorPose;
        shift_ = Eigen::Vector3d(std::round(sensor.x()), std::round(sensor.y()), std::round(sensor.z()));
    }
    if (shift_) pose = CPose3D(-shift_->x(), -shift_->y(), -shift_->z(), 0, 0, 0) + pose;
    return pose;
}

}  // namespace gseg::map
