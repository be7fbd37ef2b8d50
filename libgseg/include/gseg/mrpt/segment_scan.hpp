#pragma once
/// \file segment_scan.hpp
/// Segmenting real scans with a loaded configuration: `distToGround: auto` resolved per scan
/// (gseg::AutoHeightSegmenter: never refuses a scan, keeps the previous scan's height as fallback)
/// and points with NaN or infinite coordinates (a driver's "no return", the holes of an organised
/// cloud) labelled non-ground and counted by the core. Used by the tools and gseg::GroundFilter.

#include <gseg/ground_segmenter.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/point_cloud.hpp>
#include <gseg/sensor_height.hpp>

#include <cstddef>

namespace gseg::mrpt {

/// One segmented scan.
struct ScanSegmentation {
    /// One label per input point (non-finite points 0, counted in result.numNonFinite).
    gseg::Result result;
    std::size_t nonFinitePoints = 0;     ///< input points with a NaN or infinite coordinate
    double distToGround = 0;             ///< [m] the sensor height used
    bool distToGroundEstimated = false;  ///< `distToGround: auto` and this scan gave an estimate
    HeightDecision height;               ///< with `distToGround: auto`: what was used and why
    /// With a fixed distToGround, on the first scan with points only: the scan's own estimate
    /// contradicts it (gseg::checkDistToGround()); "" otherwise.
    std::string heightWarning;
};

/// Segments scans with one configuration. One object per stream and thread.
class ScanSegmenter {
public:
    explicit ScanSegmenter(const LoadedConfig& config);

    /// Labels every point of `cloud` (levelled frame, sensor at the origin). A scan without finite
    /// points gets all labels 0, an empty one no labels. Never refuses a scan for its height; with
    /// a fixed distToGround the first scan with points is checked against it (heightWarning).
    ScanSegmentation segment(const PointCloudView& cloud, bool keepCellDiagnostics = false);

    const LoadedConfig& config() const { return config_; }

private:
    LoadedConfig config_;
    GroundSegmenter fixed_;
    AutoHeightSegmenter auto_;
    bool heightChecked_ = false;
};

}  // namespace gseg::mrpt
