#pragma once
/// \file params.hpp
/// Every parameter of GSeg3D, with its default, unit and meaning. Frames: the cloud is given in
/// a gravity-aligned frame whose z axis points up and whose origin is the sensor (or a point
/// straight above the ground under the robot); the ground under the robot is at z = -distToGround.

#include <cstdint>
#include <string>
#include <vector>

namespace gseg {

/// Configuration of GroundSegmenter. Defaults: the authors' library defaults and the paper's
/// SemanticKITTI configuration (Lodhi and Hertzberg, ICRCV 2025). Field names are the YAML keys.
struct Params {
    // --- robot / sensor -------------------------------------------------------------------------
    double distToGround = 1.723;  ///< [m] height of the sensor above the ground under the robot (> 0: ground is below)
    double robotRadius = 2.7;     ///< [m] radius of the seed disc under the robot from which expansion starts

    // --- grid -------------------------------------------------------------------------------------
    double cellSizeX = 1.5;        ///< [m] cell size along x, both phases
    double cellSizeY = 1.0;        ///< [m] cell size along y, both phases
    double cellSizeZPhase1 = 1.5;  ///< [m] cell height in Phase I (tall cells: throw out tall structures)
    double cellSizeZPhase2 = 0.2;  ///< [m] cell height in Phase II (thin cells: separate ground from what stands on it)
    double gridGroundLevel = 0.8;  ///< [-] where the expected ground (z = -distToGround) lies inside its cell, as a fraction of the cell height from its bottom (both phases)

    // --- local eigen classification ---------------------------------------------------------------
    int minPointsPerCell = 3;            ///< [points] cells with fewer points are not classified (their points: non-ground)
    int minPointsForPca = 6;             ///< [points] cells with fewer points (but >= minPointsPerCell) use the variance rule instead of PCA
    double lineRatioThreshold = 0.95;    ///< [-] l1/(l1+l2+l3) above this: line cell
    double planeRatioThreshold = 0.4;    ///< [-] l1/(l1+l2+l3) above this (and not a line): planar cell; else non-planar
    double slopeThresholdDegrees = 30.0; ///< [deg] steepest line or plane still taken as ground
    bool checkPlaneNormal = true;        ///< a planar cell whose PCA normal is steeper than slopeThresholdDegrees is steep before any plane fit (the authors' rule; false: only the fit decides); so is a line cell that is an upright strip (see stripMinSpread)
    double stripMinSpread = 0.03;        ///< [m] a line cell whose points spread more than this (standard deviation) across its axis is a strip, whose PCA normal counts like a planar cell's

    // --- surface gradient analysis (RANSAC plane fit) ----------------------------------------------
    double groundInlierThreshold = 0.125;  ///< [m] point-to-plane distance of a plane inlier
    double minGroundInlierRatio = 0.5;     ///< [-] a planar cell is ground candidate only if its best plane within the slope limit holds more than this share of its points
    int ransacMaxIterations = 1000;        ///< [-] upper bound of RANSAC iterations per cell
    double ransacConfidence = 0.999;       ///< [-] stop once another sample would find a better plane with less than 1 - this probability
    std::uint64_t ransacSeed = 42;         ///< [-] seed of the per-cell random generators (mixed with the cell index: results never depend on call order)

    // --- ground region expansion ------------------------------------------------------------------
    double seedHeightTolerance = 0.3;   ///< [m] expansion starts from the candidates within robotRadius + centroidSearchRadius whose ground lies within this of -distToGround (both phases; if fewer than 4 do, also those within robotRadius + centroidSearchRadius beyond the nearest candidate: a sensor whose blind zone hides the ground near the robot; if none does, the tolerance widens at slopeThresholdDegrees with the distance: the robot stands on a slope)
    double centroidSearchRadius = 5.0;  ///< [m] radius of the neighbour search between ground-candidate centroids (the paper's KD-tree search)
    double heightGate = 0.1;            ///< [m] Phase II (tau): a neighbour is taken only if the step between the two ground centroids, measured along both cells' fitted ground planes (height for line and small cells), is at most this
    bool recoverNearGround = true;      ///< Phase I: points of non-ground cells that lie on the ground plane of a ground cell beside them (or one level below) go on to Phase II
    double recoveryThreshold = 0.1;     ///< [m] point-to-plane distance of such a recovered point
    double sparseRecoveryThreshold = 0.1;  ///< [m] Phase II: points of cells with fewer than minPointsPerCell points that lie within this of the ground plane of a ground cell beside them (or one level below) are ground (0: never)
    double bridgeRadius = 10.0;  ///< [m] Phase II: once the expansion stops, a candidate it never reached whose horizontally nearest ground cell within this radius has it within bridgeGate of its ground plane is reached from that cell, and the expansion goes on (repeated until none is added): ground beyond a gap between rings, beside a step larger than heightGate (0: never)
    double bridgeGate = 0.1;    ///< [m] ... the largest distance of such a candidate's ground centroid from that cell's ground plane (along its normal; line and small cells: vertical) and from its ground centroid's height
    double bridgeGapGate = 0.15;  ///< [m] ... bridgeGate instead, where that cell lies farther than centroidSearchRadius horizontally (rings farther apart than the search radius, which the expansion never compared; used only where larger than bridgeGate)
    double bridgeMaxDrop = 0.3;  ///< [m] ... such a candidate may lie up to this below that cell's ground centroid (up to bridgeGate above it; never less than bridgeGate): ground falling away from the road or downhill beyond a gap, where the cell's plane predicts it
    double bridgeMaxAngleDegrees = 10.0;  ///< [deg] ... and the largest angle between the two cells' ground-plane normals (line and small cells: vertical; a bush's top, a slab of a bonnet tilt away from the ground beside them)

    // --- per-cell refinement ----------------------------------------------------------------------
    double sparsityLow = 0.001;              ///< [m^3/point] bounding-box volume per point below this: Low sparsity
    double sparsityMedium = 0.01;            ///< [m^3/point] below this (and not Low): Medium; otherwise High
    double maxGroundHeightDeviation = 0.3;   ///< [m] ambiguous cell rejected if its ground is higher than this above the lowest neighbour (above a curb)
    double floatingMinHeight = 0.1;          ///< [m] Phase II: a cell is floating (not ground) if a point Phase I rejected lies more than this below its bottom in the same column (a car roof above the car's side); a point closer below is a step of the ground (the road under a sidewalk's edge)
    double floatingMaxDepth = 0.5;           ///< [m] ... and at most this below it; deeper points are reflections under the ground (a rejected cell recovered onto a neighbour's plane does not count its points more than this below that plane either)
    bool floatingIgnoresLowOutliers = true;  ///< ... not counting the outliers of a Phase I ground cell that lie below its plane (lower ground beside it); false: every outlier counts
    double belowGroundMargin = 0.5;          ///< [m] non-ground points this far below the local ground are flagged as reflections (Result::belowGround; 0: never)

    /// Throws std::invalid_argument naming the first invalid key and its value.
    void validate() const;

    /// Names of all keys, in declaration order (the YAML/INI keys).
    static const std::vector<std::string>& keys();

    /// Sets the field named `key` from its text form. Throws std::invalid_argument on an unknown
    /// key or a value that does not parse as the field's type (does not validate ranges).
    void set(const std::string& key, const std::string& value);

    /// The field named `key` as text (round-trips through set()). Throws on an unknown key.
    std::string get(const std::string& key) const;
};

}  // namespace gseg
