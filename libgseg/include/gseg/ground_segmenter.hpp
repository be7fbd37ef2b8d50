#pragma once
/// \file ground_segmenter.hpp
/// GSeg3D ground segmentation of one LiDAR scan (the library's entry point).

#include <gseg/cell_types.hpp>
#include <gseg/params.hpp>
#include <gseg/point_cloud.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace gseg {

namespace detail {
struct Workspace;  // scratch memory of GroundSegmenter (implementation detail)
}

/// Per-point label. Stored as one byte per point: 1 ground, 0 non-ground.
enum class Label : std::uint8_t { NonGround = 0, Ground = 1 };

/// Diagnostics of one occupied cell of one phase.
struct CellDiagnostics {
    std::int32_t ix = 0, iy = 0, iz = 0;  ///< cell index (floor(p / cellSize) per axis)
    std::uint32_t numPoints = 0;          ///< points in the cell
    std::uint32_t numInliers = 0;         ///< ground candidates (plane inliers) of the cell
    CellClass cellClass = CellClass::TooFewPoints;
    CellOutcome outcome = CellOutcome::TooFewPoints;
    float groundHeight = 0.f;  ///< [m] mean z of the ground candidates (valid where numInliers > 0)
    std::int32_t reachedFrom = -2;  ///< index (in this phase's cells) of the ground cell the expansion reached this one from; -1 the seed, -2 not reached
};

/// Wall-clock time of each step of one phase, in milliseconds.
struct StepTimes {
    double grid = 0;            ///< binning points into cells
    double classification = 0;  ///< covariance + eigen classification
    double planeFit = 0;        ///< RANSAC plane fit of planar cells
    double expansion = 0;       ///< neighbour search between candidate centroids + breadth-first region expansion with its checks
    double refinement = 0;      ///< sparsity buckets and final per-point labels
    double total() const { return grid + classification + planeFit + expansion + refinement; }
};

/// Counters and diagnostics of one phase.
struct PhaseReport {
    std::size_t inputPoints = 0;     ///< points the phase looked at
    std::size_t groundPoints = 0;    ///< points the phase called ground
    std::size_t occupiedCells = 0;   ///< cells with at least one point
    std::size_t candidateCells = 0;  ///< tentative ground cells (the expansion's centroids)
    std::size_t groundCells = 0;     ///< cells accepted as ground
    std::size_t unlabelledCellPoints = 0;  ///< points in cells with too few points (labelled non-ground)
    std::size_t unreachedCellPoints = 0;   ///< points in candidate cells the expansion never reached (non-ground)
    std::size_t recoveredPoints = 0;       ///< Phase I: points of non-ground cells on an adjacent ground cell's plane (passed to Phase II); Phase II: points of cells too small to classify on an adjacent ground cell's plane (ground)
    StepTimes ms;                          ///< time per step
    std::vector<CellDiagnostics> cells;    ///< one entry per occupied cell, sorted by (ix, iy, iz)
};

/// Result of segmenting one scan.
struct Result {
    /// One label per input point, in input order: 1 ground, 0 non-ground. Every point gets one:
    /// points in unclassified or unreached cells, and plane outliers, are non-ground.
    std::vector<std::uint8_t> labels;
    std::size_t numGround = 0;     ///< points labelled ground
    std::size_t numNonGround = 0;  ///< points labelled non-ground
    std::size_t numNonFinite = 0;  ///< points with a NaN or infinite coordinate (no return): non-ground, not segmented
    /// Non-ground points lying more than Params::belowGroundMargin below the local ground (mirror
    /// reflections, multipath), ascending indices. They are neither ground nor obstacles: map
    /// building should leave them out.
    std::vector<std::uint32_t> belowGround;
    PhaseReport phase1;            ///< Phase I (tall cells, whole cloud)
    PhaseReport phase2;            ///< Phase II (thin cells, Phase I ground only)
    double totalMs = 0;            ///< wall-clock time of segment()
};

/// Two-phase GSeg3D ground segmentation.
///
/// Deterministic: the same cloud and Params give the same labels on every call, in any order and
/// on any thread. One object holds scratch memory reused between calls, so one object must not be
/// used from two threads at once; use one segmenter per thread (they are cheap).
class GroundSegmenter {
public:
    /// Throws std::invalid_argument if the parameters are invalid (see Params::validate()).
    explicit GroundSegmenter(const Params& params = Params());
    ~GroundSegmenter();
    GroundSegmenter(GroundSegmenter&&) noexcept;
    GroundSegmenter& operator=(GroundSegmenter&&) noexcept;

    const Params& params() const { return params_; }

    /// Labels every point of `cloud`; points with a NaN or infinite coordinate are non-ground (and
    /// counted). Throws std::invalid_argument for an empty cloud or a stride below 12 bytes. With
    /// `keepCellDiagnostics` false, PhaseReport::cells stays empty (saves a little time).
    Result segment(const PointCloudView& cloud, bool keepCellDiagnostics = true);

    /// The same with another sensor height than Params::distToGround (e.g. estimated per scan).
    /// Throws std::invalid_argument if `distToGround` is not finite.
    Result segment(const PointCloudView& cloud, double distToGround, bool keepCellDiagnostics = true);

private:
    Result run(const PointCloudView& cloud, const Params& params, bool keepCellDiagnostics);

    Params params_;
    std::unique_ptr<detail::Workspace> ws_;
};

}  // namespace gseg
