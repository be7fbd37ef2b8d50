#pragma once
/// \file below_ground.hpp
/// Reflections below the ground (not a step of the GSeg3D paper; this project's addition): non-ground
/// points lying well below the ground the segmenter found around them, such as mirror reflections
/// and multipath returns. They are neither ground nor obstacles, and map building leaves them out.

#include <gseg/params.hpp>
#include <gseg/point_cloud.hpp>

#include <cstdint>
#include <vector>

namespace gseg {

/// Scratch memory of flagBelowGround(), reused between scans (one per thread).
struct BelowGroundScratch {
    std::vector<float> ground, next;  ///< [m] lowest ground z per column (dense), and its next ring
};

/// The non-ground points (labels[i] == 0) of `cloud` lying more than Params::belowGroundMargin
/// below the lowest ground point (labels[i] != 0) of their column of Params::cellSizeX x cellSizeY
/// (in the cloud's frame, columns indexed like the segmenter's grid), or, in a column without
/// ground, of the columns around it up to two away (for columns at most one beyond the bounding
/// box of the ground's columns; those farther out have no reference). Columns with no ground that
/// close flag nothing; nor does a margin of 0, a cloud without ground, or ground spread over more
/// than 2^24 columns (with the border). Points with a NaN or infinite coordinate are never flagged. `labels` holds one byte per
/// point of `cloud`. Returns ascending point indices.
std::vector<std::uint32_t> flagBelowGround(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                                           const Params& params, BelowGroundScratch& scratch);

}  // namespace gseg
