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

/// The lowest ground point of one column of Params::cellSizeX x cellSizeY (indexed like the
/// segmenter's grid: cellCoord()).
struct GroundColumn {
    std::int32_t ix = 0, iy = 0;  ///< column index
    float lowest = 0;             ///< [m] z of its lowest ground point
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

/// The same with the ground already gathered per column (as the segmenter has it from its grid; in
/// any order, a column may come several times) and `finitePoints`, the ascending indices of the
/// points of `cloud` with finite coordinates: no pass over the whole cloud but the last.
std::vector<std::uint32_t> flagBelowGround(const PointCloudView& cloud, const std::vector<std::uint32_t>& finitePoints,
                                           const std::vector<std::uint8_t>& labels, const std::vector<GroundColumn>& groundColumns,
                                           const Params& params, BelowGroundScratch& scratch);

}  // namespace gseg
