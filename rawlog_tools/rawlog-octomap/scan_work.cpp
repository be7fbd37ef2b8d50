#include "scan_work.hpp"

#include <gseg/map/world_scan.hpp>

#include <chrono>
#include <stdexcept>

namespace rawlog_octomap {

PhaseTimes& PhaseTimes::operator+=(const PhaseTimes& o) {
    read += o.read, segmentation += o.segmentation, transform += o.transform;
    rayCasting += o.rayCasting, mapUpdate += o.mapUpdate, writing += o.writing;
    return *this;
}

ScanWorker::ScanWorker(const gseg::mrpt::LoadedConfig& config, const gseg::map::TraversabilityOptions& options)
    : segmenter_(config.params),
      autoHeight_(config.distToGroundAuto ? std::make_unique<gseg::AutoHeightSegmenter>(config.params) : nullptr),
      options_(options) {}

ScanResult ScanWorker::operator()(const ScanJob& job) {
    ScanResult r;
    r.describe = job.describe();
    r.presegmented = job.presegmented();
    r.fraction = job.fraction;
    gseg::map::WorldScan world;
    if (job.raw) {
        gseg::map::WorldScanTimes t;
        try {
            if (autoHeight_) autoHeight_->reset();  // any thread count gives the same maps
            world = gseg::map::segmentToWorld(*job.raw, job.robotPose, segmenter_, autoHeight_.get(), &t, job.index == 0);
            r.reflections = world.reflections;
            r.heightNote = world.heightNote;
            r.heightWarning = world.heightWarning;
        } catch (const std::invalid_argument& e) {
            r.skipped = e.what();
            return r;
        }
        r.times.segmentation = t.segmentation, r.times.transform = t.transform;
    } else {
        const auto t0 = std::chrono::steady_clock::now();
        if (job.ground) world.sensorOrigin = gseg::map::appendWorldPoints(*job.ground, job.robotPose, world.ground);
        if (job.obstacles) world.sensorOrigin = gseg::map::appendWorldPoints(*job.obstacles, job.robotPose, world.obstacles);
        r.times.transform = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    const auto t0 = std::chrono::steady_clock::now();
    try {
        r.update = gseg::map::castScan(world.groundView(), world.obstaclesView(), world.sensorOrigin, options_);
    } catch (const std::out_of_range& e) {
        throw std::runtime_error(r.describe + ": " + e.what() + "; for poses in UTM or other large coordinates use --origin first");
    } catch (const std::bad_alloc&) {
        throw;  // the tool says what it was doing, with the options memory follows
    } catch (const std::exception& e) {
        throw std::runtime_error(r.describe + ": " + e.what());
    }
    r.times.rayCasting = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

}  // namespace rawlog_octomap
