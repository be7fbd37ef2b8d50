#pragma once
/// \file ground_filter.hpp
/// GSeg3D as an MRPT observation filter: a LiDAR observation in, a ground and an obstacle point
/// cloud observation out. Registered with MRPT's RTTI as "gseg::GroundFilter", so
/// `mrpt::rtti::classFactory("gseg::GroundFilter")` creates one (also from the plugin library).

#include <gseg/drive_terrain.hpp>
#include <gseg/ground_segmenter.hpp>
#include <gseg/sensor_height.hpp>
#include <gseg/terrain_model.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/segment_scan.hpp>

#include <mrpt/maps/CPointsMap.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/rtti/CObject.h>

#include <memory>
#include <string>

// MRPT's RTTI macros name `mrpt::...` unqualified, which inside namespace gseg would find
// gseg::mrpt: the class lives in gseg_filters, is registered as "gseg::GroundFilter", and is
// aliased as gseg::GroundFilter below.
namespace gseg_filters {

/// Splits LiDAR observations (CObservationVelodyneScan, CObservationPointCloud,
/// CObservation3DRangeScan, CObservationRotatingScan) and point maps into ground and obstacles.
///
/// Frames: segmentation runs in the levelled sensor frame (the rotation of `sensorPose` applied:
/// pitch and roll of the mounting are undone, so z is up; origin at the sensor, so distToGround is
/// the sensor's own height). The outputs keep the input's points in the frame chosen by
/// `outputFrame`: `Sensor` (default) keeps the input's coordinates and its sensorPose; `Vehicle`
/// transforms the points by the full sensorPose and sets the output's sensorPose to identity.
class GroundFilter : public ::mrpt::rtti::CObject {
    DEFINE_MRPT_OBJECT(GroundFilter, gseg_filters)

public:
    enum class OutputFrame { Sensor, Vehicle };

    /// The two halves of one scan. ground->pointcloud->size() + obstacles->...size() +
    /// result.numNonFinite + reflections equals the input's point count; both keep the input's
    /// timestamp, sensorPose (in Sensor frame) and intensity, and are labelled
    /// "<sensorLabel>_ground" / "<sensorLabel>_obstacles". Points with a NaN or infinite coordinate
    /// (no return) and reflections far below the ground (result.belowGround) are labelled
    /// non-ground in `result.labels` but kept out of both clouds (no map wants them).
    struct Output {
        ::mrpt::obs::CObservationPointCloud::Ptr ground, obstacles;
        double distToGround = 0;  ///< [m] the sensor height used (estimated if `auto`)
        bool distToGroundEstimated = false;
        /// A fixed distToGround that the filter's first scan contradicts (see
        /// gseg::checkDistToGround()): "" otherwise, and on every later scan.
        std::string heightWarning;
        std::size_t reflections = 0;      ///< points more than belowGroundMargin below the ground (result.belowGround)
        std::size_t driveRelabelled = 0;  ///< points the drive's terrain model turned ground (filter() with a pose)
        std::size_t driveDropped = 0;     ///< ground points it turned non-ground (the feet of what stands)
        /// collectDriveEvidence(true): the scan's evidence for the drive's model (its single-scan
        /// labels by cell of the configuration's terrain model, for TerrainModel::add() in scan order)
        std::vector<gseg::TerrainSample> driveEvidence;
        gseg::Result result;      ///< labels (one per input point), counters and timing of the segmentation
    };

    /// With gseg::mrpt::defaultConfig(), the one default of every route (`distToGround: auto`).
    GroundFilter();
    explicit GroundFilter(const gseg::mrpt::LoadedConfig& config, OutputFrame frame = OutputFrame::Sensor);

    /// Configuration from a YAML or INI file (see gseg/mrpt/config.hpp); throws on bad keys. A
    /// retired key (e.g. `threads`) loads, its warning in config().warnings for the caller to show.
    void loadConfig(const std::string& path);
    const gseg::mrpt::LoadedConfig& config() const { return segmenter_.config(); }
    OutputFrame outputFrame = OutputFrame::Sensor;

    /// Segments one observation. Throws std::invalid_argument for unsupported kinds (a 2D laser
    /// scan has no ground to find) and malformed observations (e.g. point vectors of different
    /// lengths), std::runtime_error if `distToGround: auto` finds no ground.
    Output filter(const ::mrpt::obs::CObservation& obs);

    /// Segments a point map given in a levelled frame with the sensor at the origin.
    Output filter(const ::mrpt::maps::CPointsMap& map, const std::string& label = "points");

    /// With the drive's context (#31): segments `obs` as filter(obs) does, then labels ground the
    /// non-ground points lying on the terrain the drive's model holds, and non-ground the feet of
    /// what stands on it (TerrainModel::relabel(); `result.labels`, the halves and
    /// `driveRelabelled` say so). `robotPose`: the vehicle's pose
    /// in the world frame (the observation's sensorPose is on the vehicle). The model is, by
    /// default, the causal one of the scans given to this call before (a stream: call it in the
    /// drive's order; gseg::DriveTerrain keeps the area around the sensor), or the one
    /// useDriveModel() gave (offline: the whole drive's, not changed by this call). With
    /// `traversability.driveTerrain: false` in the configuration it is filter(obs).
    Output filter(const ::mrpt::obs::CObservation& obs, const ::mrpt::poses::CPose3D& robotPose);

    /// Relabels with `model` (built, e.g. from a whole drive) in filter(obs, pose) instead of the
    /// causal model; nullptr goes back to the causal one (started afresh).
    void useDriveModel(std::shared_ptr<const gseg::TerrainModel> model);
    /// The first pass of the offline form: filter(obs, pose) gives each scan's evidence (its
    /// single-scan labels) in Output::driveEvidence and relabels nothing; false ends it. The caller
    /// adds the scans' evidence in scan order to a TerrainModel (config().traversability
    /// .terrainOptions()), builds it and gives it to useDriveModel() for the second pass; scans
    /// may be segmented by several filters at once (gseg::map::driveModelOf()).
    void collectDriveEvidence(bool on);

private:
    Output split(const std::vector<float>& sensorXyzi, const ::mrpt::poses::CPose3D& sensorPose,
                 const ::mrpt::obs::CObservation* source, const std::string& label,
                 const ::mrpt::poses::CPose3D* robotPose = nullptr);
    /// The drive's context on `out.result` (see filter(obs, robotPose)).
    void relabelWithDrive(const std::vector<float>& sensorXyzi, const ::mrpt::poses::CPose3D& worldSensorPose, Output& out);

    gseg::mrpt::ScanSegmenter segmenter_;
    std::shared_ptr<const gseg::TerrainModel> driveModel_;  ///< offline: the whole drive's
    std::unique_ptr<gseg::DriveTerrain> causal_;            ///< a stream's, made at its first scan
    bool collect_ = false;                                  ///< the offline first pass
};

/// Name under which MRPT's class factory knows GroundFilter.
constexpr const char* kGroundFilterClassName = "gseg::GroundFilter";

}  // namespace gseg_filters

namespace gseg {
using GroundFilter = gseg_filters::GroundFilter;
}  // namespace gseg
