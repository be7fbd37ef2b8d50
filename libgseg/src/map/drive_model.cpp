#include <gseg/map/drive_model.hpp>
#include <gseg/map/scan_stream.hpp>
#include <gseg/mrpt/ground_filter.hpp>

#include <algorithm>

namespace gseg::map {

std::optional<::mrpt::poses::CPose3D> DriveModel::poseOf(std::size_t entry, const std::string& label) const {
    const auto it = poses.find({entry, label});
    if (it == poses.end()) return std::nullopt;
    return it->second;
}

DriveModel driveModelOf(const std::string& rawlog, const gseg::mrpt::LoadedConfig& config, const std::vector<std::string>& sensors,
                        const std::function<void(std::size_t, double)>& progress) {
    DriveModel out;
    if (!config.traversability.driveTerrain) {
        return out;  // turned off: nothing to say
    }
    PoseConfig poseConfig;
    poseConfig.input = rawlog;
    ScanStream stream(poseConfig);
    out.poseSource = stream.poseSource();
    auto model = std::make_shared<gseg::TerrainModel>(config.traversability.terrainOptions());
    gseg::GroundFilter filter(config);
    filter.collectDriveModel(model.get());
    ScanJob job;
    for (;;) {
        try {
            if (!stream.next(job)) break;
        } catch (const std::exception& e) {
            const std::string what = e.what();
            if (what.find("pose") == std::string::npos) throw;  // a corrupt rawlog: not a matter of poses
            // A rawlog without any pose holds single scans, not a drive: nothing to say. A drive
            // with a scan missing its pose is named (rawlog-gseg reads the rawlog's own poses).
            if (!out.poses.empty()) out.why = what.substr(0, what.find(": give --poses"));
            out.poses.clear();
            return out;
        }
        if (!job.raw || job.presegmented()) continue;  // rawlog-gseg passes a segmented scan through
        if (!sensors.empty() && std::find(sensors.begin(), sensors.end(), job.raw->sensorLabel) == sensors.end()) continue;
        out.poses[{job.entry, job.raw->sensorLabel}] = job.robotPose;
        try {
            filter.filter(*job.raw, job.robotPose);
            ++out.scans;
        } catch (const std::exception&) {  // the second pass names it and passes it through
        }
        if (progress) progress(out.scans, job.fraction);
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
