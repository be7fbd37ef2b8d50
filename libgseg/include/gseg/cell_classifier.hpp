#pragma once
/// \file cell_classifier.hpp
/// Local eigen classification of one cell (paper step 2) and the sparsity buckets of Algorithm 1.

#include <gseg/cell_types.hpp>
#include <gseg/params.hpp>

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>

namespace gseg {

/// Outcome of classifying one cell from its points.
struct CellClassification {
    CellClass cellClass = CellClass::TooFewPoints;
    bool groundCandidate = false;  ///< tentative ground (Line/Small), or Plane to be confirmed by the plane fit
    CellOutcome rejection = CellOutcome::TooFewPoints;  ///< reason when not a candidate
    Eigen::Vector3f mean = Eigen::Vector3f::Zero();      ///< centroid of the points
    bool steepNormal = false;  ///< Plane: its PCA normal is steeper than the slope limit (checkPlaneNormal)
    Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();   ///< ground-plane normal (z >= 0) of a Line cell: the least tilted plane containing its axis; UnitZ otherwise
};

/// Classifies a cell from its points `pts[0..n)` given relative to any origin (the mean is
/// computed here). Planar cells come back as candidates: the plane fit decides their slope.
CellClassification classifyCell(const Eigen::Vector3f* pts, std::size_t n, const Params& params);

/// sin and cos of Params::slopeThresholdDegrees (computed once, not per cell).
struct SlopeLimit {
    double sin = 0, cos = 1;
    SlopeLimit() = default;
    explicit SlopeLimit(const Params& params);
};

/// The mean and the scatter matrix of a cell's points, as the classification computes them (the
/// plane fit's least-squares pass takes them where its inliers are all the cell's points: the same
/// sums in the same order, so it need not sum them again).
struct PointMoments {
    std::size_t count = 0;                                  ///< [points] how many points they cover (0: none computed)
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();         ///< [m] detail::pointSum of the points / count
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();      ///< [m^2] detail::scatterMatrix about `mean` (not divided by count)
};

/// The same with the slope limit's sine and cosine given (the segmenter computes them once per
/// scan); `moments` (optional) receives the points' mean and scatter matrix where they were
/// computed (at least Params::minPointsPerCell points; otherwise its count is 0).
CellClassification classifyCell(const Eigen::Vector3f* pts, std::size_t n, const Params& params, const SlopeLimit& slope,
                                PointMoments* moments = nullptr);

namespace detail {
/// The sum of the points `pts[0..n)` whose `mask` is non-zero (mask null: every point), in double,
/// in the points' order (bit for bit Eigen's `sum += p.cast<double>()`, kept in registers);
/// `count` (optional) receives how many were summed.
Eigen::Vector3d pointSum(const Eigen::Vector3f* pts, std::size_t n, const std::uint8_t* mask = nullptr,
                         std::size_t* count = nullptr);
/// The scatter matrix sum over the points i of (p_i - mean)(p_i - mean)^T [m^2], the differences
/// and sums in double, of the points `pts[0..n)` whose `mask` is non-zero (mask null: every
/// point): the same value, bit for bit, as Eigen's `cov.noalias() += d * d.transpose()` summed in
/// the points' order (each symmetric pair computed once; SSE2 where there is).
Eigen::Matrix3d scatterMatrix(const Eigen::Vector3f* pts, std::size_t n, const Eigen::Vector3d& mean,
                              const std::uint8_t* mask = nullptr);
}  // namespace detail

/// Bounding-box sparsity of Algorithm 1: box volume / point count, in m^3 per point.
enum class Sparsity : std::uint8_t { Low, Medium, High };

/// Bucket of `volumePerPoint` [m^3/point] against Params::sparsityLow / sparsityMedium.
Sparsity sparsityBucket(double volumePerPoint, const Params& params);

}  // namespace gseg
