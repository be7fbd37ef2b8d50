#pragma once
/// \file region_growing.hpp
/// Ground region expansion over tentative-ground cell centroids (paper step 4): the paper's KD-tree
/// radius search, done in columns of centroids (the same neighbours: the squared distance in float
/// below the squared radius, as nanoflann's L2 metric).


#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace gseg {

/// Settings of one expansion.
struct ExpansionSettings {
    Eigen::Vector3f seed = Eigen::Vector3f::Zero();  ///< [m] synthetic seed under the robot
    double seedRadius = 7.7;    ///< [m] candidates within this distance of the seed start the expansion
    double radius = 5.0;        ///< [m] neighbour search radius between centroids
    double heightGate = std::numeric_limits<double>::infinity();  ///< [m] max step to a neighbour (Phase II)
    double seedGate = std::numeric_limits<double>::infinity();    ///< [m] max |dz| of a starting candidate to the seed
    /// Optional ground-plane normal per centroid (unit, z > 0). When given, the step to a neighbour
    /// is measured along both cells' normals (the larger of the two), so ground that slopes stays
    /// connected and a step up onto another surface does not; otherwise it is |dz|.
    const std::vector<Eigen::Vector3f>* normals = nullptr;
    /// If fewer than this many candidates in the seed disc pass the seed gate, a second disc
    /// reaching seedRadius beyond the nearest candidate adds those of its candidates that pass (a
    /// sensor whose blind zone hides the ground near the robot); 0: the seed disc only.
    std::size_t fewSeeds = 0;
    double seedSlope = 0.0;  ///< [-] if no candidate passes the seed's gate, it widens by this much per metre of horizontal distance (the robot stands on a slope)
    /// Optional: whether `accept` looks at a candidate's neighbours (only those get a list). A candidate
    /// for which it returns false is decided with an empty list, and only if accepted are its
    /// neighbours searched, skipping those already reached: the same walk, with less searching.
    std::function<bool(std::uint32_t candidate)> needsNeighbours;
    /// Bridges (0: none): once the walk has stopped, a candidate it never reached whose nearest
    /// accepted candidate (horizontally, within bridgeRadius [m]) has it within bridgeGate [m] of
    /// that candidate's ground plane (along its normal, where given), at most bridgeGate above it
    /// and at most bridgeMaxDrop below it, and whose normal agrees with that candidate's (cosine at
    /// least bridgeMinNormalCos), is reached from it (beyond `radius`, bridgeGapGate is the gate if
    /// larger), and the walk goes
    /// on; repeated until no candidate is added. Ground beyond a gap (rings farther apart than
    /// `radius`) or a step of the ground larger than heightGate (a verge beside the road).
    double bridgeRadius = 0.0;
    double bridgeGate = 0.0;  ///< [m] see bridgeRadius
    double bridgeMaxDrop = 0.0;  ///< [m] see bridgeRadius (at least bridgeGate is allowed)
    double bridgeGapGate = 0.0;  ///< [m] see bridgeRadius (used where larger than bridgeGate)
    double bridgeMinNormalCos = 1.0;  ///< [-] see bridgeRadius (cosine of the largest angle between the normals)
};

/// Decides a reached candidate: given its index and its neighbours (candidate indices within
/// the radius and the gate, itself excluded), returns true to accept it and expand from it.
using AcceptFn = std::function<bool(std::uint32_t candidate, const std::vector<std::uint32_t>& neighbours)>;

/// Breadth-first expansion from the seed. Each candidate reached is passed to `accept` exactly
/// once, in a deterministic order; only accepted candidates propagate. Returns, per candidate,
/// 0 not reached, 1 reached and rejected, 2 accepted. `parents`, if given, receives per candidate
/// the accepted candidate it was first reached from (-1: from the seed, -2: never reached).
std::vector<std::uint8_t> expandRegion(const std::vector<Eigen::Vector3f>& centroids,
                                       const ExpansionSettings& settings, const AcceptFn& accept,
                                       std::vector<std::int32_t>* parents = nullptr);

}  // namespace gseg
