#pragma once
/// \file breakdown.hpp
/// Failure analysis of one labelled scan: where false ground and missed ground come from, by
/// SemanticKITTI class, by height above the local (labelled) ground and by range. The point
/// categories follow the scoring protocol of metrics.hpp (with vegetation).

#include <gseg/eval/metrics.hpp>
#include <gseg/point_cloud.hpp>

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace gseg {

/// What one point is under the protocol (with vegetation).
enum class PointOutcome : std::uint8_t {
    TrueNonGround = 0,  ///< not ground, predicted non-ground (also unlabelled/outlier predicted non-ground)
    TrueGround = 1,     ///< ground (or unlabelled/outlier) predicted ground
    FalseGround = 2,    ///< labelled non-ground, predicted ground
    MissedGround = 3    ///< labelled ground, predicted non-ground
};

/// Height bins of false ground: height above the local labelled ground [m].
struct HeightBins {
    static constexpr int kCount = 7;  ///< below, near, low, 0.5-1, 1-2, above 2, unknown
    /// Lower edges of bins 1..5 [m]; bin 0 is below edges[0]; bin 6: no labelled ground near the point.
    static constexpr std::array<double, 5> kEdges = {-0.3, 0.25, 0.5, 1.0, 2.0};
    static const char* name(int bin);  ///< e.g. "0.5..1 m"
};

/// Range bins of false and missed ground: horizontal distance from the sensor [m].
struct RangeBins {
    static constexpr int kCount = 5;
    static constexpr std::array<double, 4> kEdges = {10, 20, 30, 50};  ///< upper edges of bins 0..3
    static const char* name(int bin);  ///< e.g. "10..20 m"
};

/// Counts of one frame, or summed over frames.
struct Breakdown {
    std::map<std::uint32_t, std::uint64_t> falseByClass;   ///< semantic class -> false-ground points
    std::map<std::uint32_t, std::uint64_t> missedByClass;  ///< semantic class -> missed ground points
    std::array<std::uint64_t, HeightBins::kCount> falseByHeight{};
    std::array<std::uint64_t, RangeBins::kCount> falseByRange{};
    std::array<std::uint64_t, RangeBins::kCount> missedByRange{};
    std::uint64_t falseGround = 0, missedGround = 0, trueGround = 0;
    Breakdown& operator+=(const Breakdown& o);
};

/// How the local ground under a point is found.
struct BreakdownOptions {
    ProtocolOptions protocol;   ///< which points are ground (vegetation height)
    double groundCell = 1.0;    ///< [m] cell of the local-ground grid (mean z of labelled ground per cell)
    int groundSearchCells = 3;  ///< [cells] the nearest ring of cells (up to this far) holding labelled ground is used
};

/// Classifies every point and counts where the errors are. `outcomes`, if given, receives one
/// PointOutcome per point. Throws std::invalid_argument on size mismatches or a prediction not 0/1.
Breakdown breakdownFrame(const PointCloudView& cloud, const std::vector<std::uint32_t>& labels,
                         const std::vector<std::uint8_t>& pred, const BreakdownOptions& options = BreakdownOptions(),
                         std::vector<PointOutcome>* outcomes = nullptr);

/// SemanticKITTI's name of a semantic class (e.g. 10 "car"), or "class N".
std::string semanticClassName(std::uint32_t semanticId);

}  // namespace gseg
