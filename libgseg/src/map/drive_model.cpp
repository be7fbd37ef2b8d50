#include <gseg/map/drive_model.hpp>
#include <gseg/map/scan_stream.hpp>
#include <gseg/mrpt/ground_filter.hpp>

#include <gseg/ordered_pipeline.hpp>

#include <algorithm>

namespace gseg::map {

std::optional<::mrpt::poses::CPose3D> DriveModel::poseOf(std::size_t entry, const std::string& label) const {
    const auto it = poses.find({entry, label});
    if (it == poses.end()) return std::nullopt;
    return it->second;
}

DriveModel driveModelOf(const std::string& rawlog, const gseg::mrpt::LoadedConfig& config, const std::vector<std::string>& sensors,
                        const std::function<void(std::size_t, double)>& progress, unsigned workers) {
    DriveModel out;
    if (!config.traversability.driveTerrain) {
        return out;  // turned off: nothing to say
    }
    PoseConfig poseConfig;
    poseConfig.input = rawlog;
    ScanStream stream(poseConfig);
    out.poseSource = stream.poseSource();
    auto model = std::make_shared<gseg::TerrainModel>(config.traversability.terrainOptions());
    // Read in order, segmented by `workers` filters at once, the evidence added in scan order: the
    // same model for any number of workers.
    std::vector<std::unique_ptr<gseg::GroundFilter>> filters(std::max(1u, workers));
    for (auto& f : filters) {
        f = std::make_unique<gseg::GroundFilter>(config);
        f->collectDriveEvidence(true);
    }
    struct Evidence {
        bool segmented = false;  ///< false: the scan cannot be segmented (the second pass names it)
        std::vector<gseg::TerrainSample> samples;
        double fraction = 0;     ///< of the rawlog read (progress)
    };
    const std::function<bool(ScanJob&)> produce = [&](ScanJob& job) {
        for (;;) {
            if (!stream.next(job)) return false;
            if (!job.raw || job.presegmented()) continue;  // rawlog-gseg passes a segmented scan through
            if (!sensors.empty() && std::find(sensors.begin(), sensors.end(), job.raw->sensorLabel) == sensors.end()) continue;
            out.poses[{job.entry, job.raw->sensorLabel}] = job.robotPose;
            return true;
        }
    };
    const std::function<Evidence(unsigned, ScanJob&)> work = [&](unsigned worker, ScanJob& job) {
        Evidence e;
        e.fraction = job.fraction;
        try {
            e.samples = filters[worker]->filter(*job.raw, job.robotPose).driveEvidence;
            e.segmented = true;
        } catch (const std::exception&) {
        }
        return e;
    };
    const std::function<void(std::size_t, Evidence&)> consume = [&](std::size_t, Evidence& e) {
        if (e.segmented) {
            model->add(e.samples);
            ++out.scans;
        }
        if (progress) progress(out.scans, e.fraction);
    };
    gseg::PipelineOptions pipeline;
    pipeline.workers = unsigned(filters.size());
    try {
        gseg::runOrdered<ScanJob, Evidence>(produce, work, consume, pipeline);
    } catch (const std::exception& e) {
        const std::string what = e.what();
        if (what.find("pose") == std::string::npos) throw;  // a corrupt rawlog: not a matter of poses
        // A rawlog without any pose holds single scans, not a drive: nothing to say. A drive
        // with a scan missing its pose is named (rawlog-gseg reads the rawlog's own poses).
        if (!out.poses.empty()) out.why = what.substr(0, what.find(": give --poses"));
        out.poses.clear();
        return out;
    }
    out.poseSource = stream.poseSource();
    if (out.scans == 0) {
        if (!out.poses.empty()) out.why = "no scan of the drive could be segmented";
        out.poses.clear();
        return out;
    }
    model->build();
    out.model = std::move(model);
    return out;
}

}  // namespace gseg::map
