#pragma once
/// \file sensor_height.hpp
/// `distToGround: auto`: the ground plane under the sensor estimated from the scan itself (height
/// and tilt), and a segmenter that uses it per scan and never refuses one.

#include <gseg/ground_segmenter.hpp>
#include <gseg/point_cloud.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

namespace gseg {

/// Options of estimateSensorHeight().
struct SensorHeightOptions {
    double minRange = 1.5;       ///< [m] ignore points closer than this horizontally (the vehicle itself)
    double maxRange = 30.0;      ///< [m] and farther than this
    double columnSize = 2.0;     ///< [m] side of the square columns
    int minColumnPoints = 5;     ///< [points] a column's floor is the lowest run of this many points within floorThickness
    double floorThickness = 0.25;  ///< [m] (sparse points below a dense floor, such as reflections, are skipped)
    int minColumns = 8;          ///< [columns] fewer columns with a floor: no estimate
    double maxTiltDegrees = 15;  ///< [deg] steepest ground plane (sensor tilt plus terrain slope) considered
    double planeTolerance = 0.2; ///< [m] a column floor within this of the plane supports it
    double minLevelTiltDegrees = 3;   ///< [deg] AutoHeightSegmenter levels out tilts from this (a mounting tilt) ...
    double maxLevelTiltDegrees = 10;  ///< [deg] ... up to this; otherwise it keeps the frame and only uses the ground's height under the sensor

    /// Throws std::invalid_argument naming the first invalid field.
    void validate() const;
    /// The keys (the field names, in declaration order), as in YAML `sensorHeight:` and the INI
    /// `[sensorHeight]` section (the plugin's `<prefix>_sensorHeight`).
    static const std::vector<std::string>& keys();
    /// Sets a field from text; throws std::invalid_argument on an unknown key or an unreadable value.
    void set(const std::string& key, const std::string& value);
    std::string get(const std::string& key) const;  ///< the field as text (set() reads it back)
    /// {unit, meaning} of a key.
    static std::pair<std::string, std::string> describe(const std::string& key);
};

/// Result of estimateSensorHeight().
struct SensorHeightEstimate {
    bool valid = false;
    double height = 0;      ///< [m] distance of the sensor above the ground plane (> 0: ground below)
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< ground-plane normal in the cloud's frame (z > 0)
    double tiltDegrees = 0; ///< [deg] angle between that normal and the cloud's z axis
    int columns = 0;        ///< columns with a floor (votes)
    int inliers = 0;        ///< votes within planeTolerance of the plane
    double spread = 0;      ///< [m] median absolute distance of the supporting votes from the plane
    std::string reason;     ///< why there is no estimate (empty when valid)
    /// [m] height of the plane straight under the sensor (along the cloud's z axis)
    double heightUnderSensor() const { return height / std::max(0.1, normal.z()); }
};

/// The ground plane around the sensor: in each column (the sensor at the origin) the lowest dense
/// layer of points votes for the ground level there, and a plane through the votes (robust fit,
/// nearer columns weigh more, at most maxTiltDegrees) gives the sensor's height and tilt. Columns
/// holding only a wall or a car roof, and stray points below the ground, do not move it.
SensorHeightEstimate estimateSensorHeight(const PointCloudView& cloud,
                                          const SensorHeightOptions& options = SensorHeightOptions());

/// A fixed distToGround checked against the scan: "" when the scan's own estimate of the height
/// of the ground under the sensor agrees with `distToGround` within `tolerance` (the seed's height
/// tolerance: beyond it the expansion may not start from the true ground; on real scans most
/// ground is then missed), or when the scan gives no estimate; otherwise one line saying both heights and what to
/// do. Costs about one segmentation (10 ms on an HDL-64 scan): the tools check the first scan.
std::string checkDistToGround(const PointCloudView& cloud, double distToGround, double tolerance,
                              const SensorHeightOptions& options = SensorHeightOptions());

/// What AutoHeightSegmenter used for one scan.
struct HeightDecision {
    enum class Source { Estimated, PreviousScan, Fallback };
    Source source = Source::Fallback;
    double height = 0;          ///< [m] the distToGround used
    double tiltDegrees = 0;     ///< [deg] tilt taken out before segmenting (0: none)
    SensorHeightEstimate estimate;  ///< what the estimator said about this scan
    std::string describe() const;   ///< one line for reports, e.g. "1.78 m (estimated, tilt 4.9 deg)"
};

/// One scan segmented by AutoHeightSegmenter: the labels and the height that made them.
struct AutoHeightResult {
    Result result;            ///< as from GroundSegmenter (labels in input order)
    HeightDecision decision;  ///< the height used and why
};

/// Segments scans with `distToGround: auto`: the height (and a mounting tilt between
/// minLevelTiltDegrees and maxLevelTiltDegrees, which is levelled out) is estimated per scan; where
/// a scan gives no estimate, the caller's `previous` estimate (an earlier scan's) is used, and
/// without one the fallback height (Params::distToGround). Never refuses a scan. Keeps no state
/// between scans but scratch memory: the decision comes back with the labels. One object per thread.
class AutoHeightSegmenter {
public:
    explicit AutoHeightSegmenter(const Params& params, const SensorHeightOptions& options = SensorHeightOptions());

    /// `previous`: a valid estimate of an earlier scan (its decision.estimate), used if this scan
    /// gives none (Source::PreviousScan); nullptr: the fallback height then (Source::Fallback).
    AutoHeightResult segment(const PointCloudView& cloud, bool keepCellDiagnostics = true,
                             const SensorHeightEstimate* previous = nullptr);

private:
    GroundSegmenter segmenter_;
    SensorHeightOptions options_;
    double fallback_;
    std::vector<float> levelled_;
};

}  // namespace gseg
