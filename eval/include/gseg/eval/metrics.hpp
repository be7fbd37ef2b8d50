#pragma once
/// \file metrics.hpp
/// Scoring of one labelled scan under the Ground Segmentation Benchmark protocol
/// (url-kaist/Ground-Segmentation-Benchmark), as used by the GSeg3D paper.

#include <gseg/point_cloud.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace gseg {

/// Confusion counts of one frame (or a sum of frames).
struct Counts {
    std::uint64_t tp = 0, fp = 0, fn = 0, tn = 0;
    double precision() const;  ///< [%] 100 tp / (tp + fp); NaN when nothing was predicted ground
    double recall() const;     ///< [%] 100 tp / (tp + fn); NaN when there is no ground
    double f1() const;         ///< [%] harmonic mean of precision and recall; NaN if either is
    Counts& operator+=(const Counts& o);
};

/// The protocol's constants.
struct ProtocolOptions {
    double vegetationZ = -1.73 * 0.75;  ///< [m] vegetation (class 70) below this z is ground (GSB: -3/4 sensor height)
    std::array<double, 10> rangeLimits = {10, 20, 30, 40, 50, 60, 70, 80, 90, 100};  ///< [m] horizontal range limits
};

/// Scores of one frame.
struct FrameScore {
    std::size_t points = 0;
    Counts withVegetation;      ///< ground = road, parking, sidewalk, other-ground, lane-marking, terrain, low vegetation
    Counts withoutVegetation;   ///< ground = the six ground classes; vegetation is don't-care
    std::array<Counts, 10> byRange;  ///< withVegetation restricted to points with sqrt(x^2+y^2) < rangeLimits[k]
};

/// SemanticKITTI classes that count as ground (semantic id = raw label & 0xFFFF).
bool isGroundClass(std::uint32_t semanticId);

/// Ground under the protocol with vegetation: a ground class, or vegetation below vegetationZ.
bool isGroundTruth(std::uint32_t semanticId, float z, const ProtocolOptions& options);

/// Unlabelled (0) or outlier (1): predicted ground counts as true positive, never as false negative.
inline bool isOutlierClass(std::uint32_t semanticId) { return semanticId == 0 || semanticId == 1; }

/// Throws std::invalid_argument unless labels and predictions have `points` entries each and every
/// prediction is 0 or 1.
void checkScoringInputs(std::size_t points, const std::vector<std::uint32_t>& labels,
                        const std::vector<std::uint8_t>& pred);

/// Scores predictions `pred` (1 ground, 0 non-ground) against SemanticKITTI labels `labels`
/// (raw uint32, instance in the upper 16 bits) for the points of `cloud`. Unlabelled (0) and
/// outlier (1) points predicted ground count as true positives, never as false negatives.
/// Throws std::invalid_argument if the three sizes differ or a prediction is not 0/1.
FrameScore scoreFrame(const PointCloudView& cloud, const std::vector<std::uint32_t>& labels,
                      const std::vector<std::uint8_t>& pred, const ProtocolOptions& options = ProtocolOptions());

/// Mean and population standard deviation (as GSB's cal_stdev) of the defined (non-NaN) values.
struct MeanStd {
    double mean = 0, stddev = 0;
    std::size_t count = 0;
};
MeanStd meanStd(const std::vector<double>& values);

}  // namespace gseg
