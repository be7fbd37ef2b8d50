#pragma once
/// \file cell_types.hpp
/// What the segmenter made of one grid cell: its eigen class and its outcome. Shared by the cell
/// classifier (cell_classifier.hpp) and the segmenter's diagnostics (ground_segmenter.hpp).

#include <cstdint>

namespace gseg {

/// What the local eigen classification made of a cell.
enum class CellClass : std::uint8_t {
    TooFewPoints,  ///< fewer than minPointsPerCell points: not classified
    Small,         ///< minPointsPerCell..minPointsForPca-1 points: variance rule instead of PCA
    Line,          ///< l1 dominant
    Plane,         ///< l1 ~ l2 >> l3
    NonPlanar      ///< l1 ~ l2 ~ l3 (clutter)
};

/// Why a cell ended up as it did. Points of every cell that is not Ground are non-ground,
/// except the plane outliers of a Ground cell, which are non-ground too.
enum class CellOutcome : std::uint8_t {
    Ground,             ///< reached by the expansion and accepted: plane inliers are ground
    TooFewPoints,       ///< not classified (fewer than minPointsPerCell points)
    Steep,              ///< line or plane steeper than slopeThresholdDegrees, or small cell taller than wide
    NonPlanar,          ///< non-planar (clutter)
    NotReached,         ///< ground candidate that the region expansion never reached
    RejectedAmbiguous,  ///< inliers and outliers equally sparse, and no neighbour or too high above the lowest one
    RejectedFloating    ///< an occupied non-ground cell lies directly below
};

/// Name of a CellClass / CellOutcome, for reports.
const char* toString(CellClass c);
const char* toString(CellOutcome o);

}  // namespace gseg
