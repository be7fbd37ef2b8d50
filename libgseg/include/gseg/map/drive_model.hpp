#pragma once
/// \file drive_model.hpp
/// The whole drive's terrain model of a rawlog (#31), for labelling its scans with the drive's
/// context offline (rawlog-gseg): the first of two passes. Every LiDAR scan that has a pose (the
/// poses ScanStream finds: the rawlog's own CObservationRobotPose, odometry or actions) is
/// segmented alone and its evidence added to a gseg::TerrainModel in scan order; the model is then
/// built. The second pass (gseg::mrpt::RawlogSegmenter with `poseOf` and `driveModel`) segments
/// each scan again and relabels it with the model. Memory: the model's sparse tiles (the area the
/// drive saw) and one pose per scan.

#include <gseg/mrpt/config.hpp>
#include <gseg/terrain_model.hpp>

#include <mrpt/poses/CPose3D.h>

#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace gseg::map {

struct DriveModel {
    std::shared_ptr<gseg::TerrainModel> model;  ///< built; null where the drive gets no context (see `why`)
    std::map<std::pair<std::size_t, std::string>, ::mrpt::poses::CPose3D> poses;  ///< vehicle pose by (rawlog entry, sensorLabel)
    std::size_t scans = 0;   ///< scans whose evidence was added
    std::string poseSource;  ///< where the poses came from (ScanStream::poseSource())
    /// Why a drive gets no model (a scan without a pose after scans with one); "" where there is a
    /// model or nothing to say (driveTerrain false, a rawlog without any pose: single scans).
    std::string why;

    /// The pose of the scan with `label` at rawlog `entry`, where the first pass saw it.
    std::optional<::mrpt::poses::CPose3D> poseOf(std::size_t entry, const std::string& label) const;
};

/// Pass 1 over `rawlog` (see the file comment): the scans with these sensorLabels (empty: every
/// LiDAR scan), labelled as GroundFilter labels them with `config`. A rawlog without a pose for
/// every scan gives no model, `why` saying which scan had none; a scan that cannot be segmented
/// adds nothing (the second pass names it). `progress(scans, fraction of the rawlog read)` after
/// each scan. `workers`: scans segmented at once (the rawlog is read in order and the evidence
/// added in scan order: the same model for any number). Throws std::runtime_error on an
/// unreadable rawlog.
DriveModel driveModelOf(const std::string& rawlog, const gseg::mrpt::LoadedConfig& config, const std::vector<std::string>& sensors,
                        const std::function<void(std::size_t scans, double fraction)>& progress = {}, unsigned workers = 1);

}  // namespace gseg::map
