#pragma once
/// \file plane_fit.hpp
/// Seeded, adaptive RANSAC plane fit with least-squares refinement (paper step 3).

#include <gseg/cell_classifier.hpp>
#include <gseg/params.hpp>

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace gseg {

/// A plane n . p + d = 0 with |n| = 1 and n_z >= 0.
struct PlaneFitResult {
    bool valid = false;          ///< false if no acceptable plane was found (too few points, vertical lines only, all too steep)
    Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();
    float d = 0.f;
    std::size_t numInliers = 0;  ///< points within Params::groundInlierThreshold of the plane
    int iterations = 0;          ///< RANSAC iterations run
};

/// Fits the plane with the most inliers to `pts[0..n)` by RANSAC (random generator seeded with
/// `seed`; the iteration count adapts to the inlier ratio found, up to
/// Params::ransacMaxIterations) followed by a least-squares refit on the inliers. Writes 1/0 per
/// point into `inlier` (resized to n).
///
/// Only planes at most `maxSlopeDegrees` from horizontal are hypotheses (90: any plane). A sample
/// whose three points lie within Params::groundInlierThreshold of one line (a single scan ring)
/// stands for that line: its hypothesis is the least tilted plane containing the line.
/// `minInlierRatio` (in [0, 1)): the caller has no use for a plane holding a smaller share of the
/// points, so the search stops once such a plane is unlikely to exist (adaptive RANSAC bound).
PlaneFitResult fitPlane(const Eigen::Vector3f* pts, std::size_t n, const Params& params,
                        std::uint64_t seed, std::vector<std::uint8_t>& inlier, double maxSlopeDegrees = 90.0,
                        double minInlierRatio = 0.0);

/// Scratch memory of fitPlane(), reused between calls (one per thread): the points as separate
/// x, y, z arrays (the inlier count over them vectorises) and a second inlier mask.
struct PlaneFitScratch {
    std::vector<float> x, y, z;
    std::vector<std::uint8_t> mask;
};

/// The same, allocating nothing once `scratch` (and `inlier`) have grown to the largest cell.
/// `moments` (optional): the mean and scatter matrix of all n points as classifyCell() computed
/// them (count n); where RANSAC's best plane holds every point, the least-squares refit takes them
/// instead of summing the same points again (the same values, bit for bit).
PlaneFitResult fitPlane(const Eigen::Vector3f* pts, std::size_t n, const Params& params, std::uint64_t seed,
                        std::vector<std::uint8_t>& inlier, PlaneFitScratch& scratch, double maxSlopeDegrees = 90.0,
                        double minInlierRatio = 0.0, const PointMoments* moments = nullptr);

/// Angle [deg] between a unit normal and the z axis (0 = horizontal plane).
double planeSlopeDegrees(const Eigen::Vector3f& normal);

/// SplitMix64: the small deterministic generator behind every random choice of the library.
inline std::uint64_t splitmix64(std::uint64_t& state) {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

}  // namespace gseg
