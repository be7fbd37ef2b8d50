#pragma once
/// \file segment_scan.hpp
/// Segmenting real scans: points with NaN or infinite coordinates (a driver's "no return", the
/// holes of an organised cloud) are labelled non-ground and counted instead of failing the scan,
/// and `distToGround: auto` is resolved per scan. Used by the tools and gseg::GroundFilter.

#include <gseg/ground_segmenter.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/point_cloud.hpp>
#include <gseg/sensor_height.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace gseg::mrpt {

/// A scan's finite points, the non-finite ones set aside (no copy when every point is finite).
class FinitePoints {
public:
    explicit FinitePoints(const PointCloudView& cloud);

    /// The finite points, in input order (x, y, z with a 12-byte stride, or the input's own view).
    const PointCloudView& view() const { return view_; }
    std::size_t inputSize() const { return inputSize_; }
    std::size_t nonFinite() const { return inputSize_ - view_.size(); }

    /// Labels of the finite points, in input order, with 0 (non-ground) for the non-finite ones.
    std::vector<std::uint8_t> toInputOrder(const std::vector<std::uint8_t>& finiteLabels) const;

private:
    std::size_t inputSize_ = 0;
    std::vector<float> xyz_;             // copies of the finite points, if some were not
    std::vector<std::uint32_t> source_;  // input index of each copied point
    PointCloudView view_;
};

/// One segmented scan.
struct ScanSegmentation {
    /// labels: one per input point (non-finite points 0); numGround / numNonGround count every
    /// input point; phase1 / phase2 report the segmentation of the finite points.
    gseg::Result result;
    std::size_t nonFinitePoints = 0;     ///< input points with a NaN or infinite coordinate
    double distToGround = 0;             ///< [m] the sensor height used
    bool distToGroundEstimated = false;  ///< from `distToGround: auto`
    SensorHeightEstimate heightEstimate; ///< the estimate, when distToGroundEstimated
};

/// Segments scans with one configuration, reusing its GroundSegmenter while the sensor height
/// stays the same. One object per thread.
class ScanSegmenter {
public:
    explicit ScanSegmenter(const LoadedConfig& config);

    /// The parameters for a scan's finite points: `distToGround: auto` estimated from them (the
    /// estimate in `*estimate` if given). Throws std::runtime_error if no ground level is found
    /// around the sensor.
    Params paramsFor(const PointCloudView& finitePoints, SensorHeightEstimate* estimate = nullptr) const;

    /// Labels every point of `cloud` (levelled frame, sensor at the origin). A scan without finite
    /// points gets all labels 0 without being segmented. Throws std::runtime_error (auto height
    /// not found) or what GroundSegmenter throws.
    ScanSegmentation segment(const PointCloudView& cloud, bool keepCellDiagnostics = false);

    const LoadedConfig& config() const { return config_; }

private:
    LoadedConfig config_;
    std::unique_ptr<GroundSegmenter> segmenter_;
};

}  // namespace gseg::mrpt
