#include <gseg/cell_classifier.hpp>
#include <gseg/plane_fit.hpp>

#include "cpu_features.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace gseg {
namespace {

// The points within `thr` of the plane n . p + d = 0 among x, y, z[0..n) (n . p as Eigen's dot:
// n0 p0 + (n1 p1 + n2 p2), so that the same points count as with Eigen::Vector3f); with kMask,
// writes 1/0 per point into `mask`. (Inlined into both forms below; the loop vectorises, each lane
// the scalar operations.)
template <bool kMask>
__attribute__((always_inline)) inline std::size_t inliersOver(const float* x, const float* y, const float* z, std::size_t n,
                                                              float nx, float ny, float nz, float d, float thr,
                                                              std::uint8_t* mask) {
    std::uint32_t count = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const bool in = std::abs(nx * x[i] + (ny * y[i] + nz * z[i]) + d) <= thr;
        if (kMask) mask[i] = in;
        count += in ? 1u : 0u;
    }
    return count;
}

#if defined(__GNUC__) && defined(__x86_64__)
// The same loop on CPUs with AVX2: eight points per operation instead of four (no fused
// multiply-add: the same values).
template <bool kMask>
__attribute__((target("avx2"))) std::size_t inliersOverAvx2(const float* x, const float* y, const float* z, std::size_t n,
                                                            float nx, float ny, float nz, float d, float thr,
                                                            std::uint8_t* mask) {
    return inliersOver<kMask>(x, y, z, n, nx, ny, nz, d, thr, mask);
}
#endif

// The points of the scratch's x, y, z[0..n) within `thr` of the plane n . p + d = 0; writes 1/0
// per point into `mask` if given.
std::size_t markInliers(const PlaneFitScratch& s, std::size_t n, const Eigen::Vector3f& normal, float d, float thr,
                        std::uint8_t* mask) {
    const float nx = normal.x(), ny = normal.y(), nz = normal.z();
    const float* x = s.x.data();
    const float* y = s.y.data();
    const float* z = s.z.data();
#if defined(__GNUC__) && defined(__x86_64__)
    if (detail::cpuHasAvx2())
        return mask ? inliersOverAvx2<true>(x, y, z, n, nx, ny, nz, d, thr, mask)
                    : inliersOverAvx2<false>(x, y, z, n, nx, ny, nz, d, thr, mask);
#endif
    return mask ? inliersOver<true>(x, y, z, n, nx, ny, nz, d, thr, mask)
                : inliersOver<false>(x, y, z, n, nx, ny, nz, d, thr, mask);
}

// Least-squares plane through the masked points: normal = smallest principal axis. `all`
// (optional): the moments of all n points, given where the mask holds every point (the masked
// sums would add the same values in the same order).
bool leastSquaresPlane(const Eigen::Vector3f* pts, std::size_t n, const std::vector<std::uint8_t>& mask,
                       float thr, const PointMoments* all, Eigen::Vector3f& normal, float& d) {
    std::size_t m = n;
    Eigen::Vector3d mean;
    Eigen::Matrix3d cov;
    if (all) {
        mean = all->mean, cov = all->scatter;
    } else {
        mean = detail::pointSum(pts, n, mask.data(), &m);
        if (m < 3) return false;
        mean /= double(m);
        cov = detail::scatterMatrix(pts, n, mean, mask.data());
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(cov);
    // Inliers spread less than the inlier distance across their main axis: a line, no plane.
    if (eig.eigenvalues()(1) / double(m) < double(thr) * double(thr)) return false;
    normal = eig.eigenvectors().col(0).normalized().cast<float>();
    if (normal.z() < 0) normal = -normal;
    d = float(-normal.cast<double>().dot(mean));
    return true;
}

// Plane hypothesis from three points. A triangle thinner than `thr` (its third point within the
// inlier distance of the line through the other two) does not fix the tilt of a plane around that
// line: such a sample stands for the line itself, and the hypothesis is the least tilted plane
// containing it (a scan ring across a ground cell is a line, not a wall).
bool hypothesis(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& c, float thr,
                Eigen::Vector3f& normal, float& d) {
    const Eigen::Vector3f e[3] = {b - a, c - b, a - c};
    const float len2[3] = {e[0].squaredNorm(), e[1].squaredNorm(), e[2].squaredNorm()};
    const int longest = len2[0] >= len2[1] ? (len2[0] >= len2[2] ? 0 : 2) : (len2[1] >= len2[2] ? 1 : 2);
    if (!(len2[longest] > 1e-12f)) return false;
    const Eigen::Vector3f cross = e[0].cross(-e[2]);  // (b - a) x (c - a)
    const float height = cross.norm() / std::sqrt(len2[longest]);  // smallest height of the triangle
    const Eigen::Vector3f& origin = longest == 0 ? a : (longest == 1 ? b : c);
    if (height >= thr) {
        normal = cross.normalized();
    } else {
        const Eigen::Vector3f dir = e[longest] / std::sqrt(len2[longest]);
        const Eigen::Vector3f side = Eigen::Vector3f::UnitZ().cross(dir);  // horizontal, across the line
        if (!(side.squaredNorm() > 1e-12f)) return false;                 // vertical line: no ground plane
        normal = dir.cross(side).normalized();
    }
    if (normal.z() < 0) normal = -normal;
    d = -normal.dot(origin);
    return true;
}

}  // namespace

double planeSlopeDegrees(const Eigen::Vector3f& normal) {
    const double c = std::min(1.0, std::abs(double(normal.z())) / std::max(1e-12, double(normal.norm())));
    return std::acos(c) * 180.0 / M_PI;
}

PlaneFitResult fitPlane(const Eigen::Vector3f* pts, std::size_t n, const Params& params, std::uint64_t seed,
                        std::vector<std::uint8_t>& inlier, double maxSlopeDegrees, double minInlierRatio) {
    PlaneFitScratch scratch;
    return fitPlane(pts, n, params, seed, inlier, scratch, maxSlopeDegrees, minInlierRatio);
}

PlaneFitResult fitPlane(const Eigen::Vector3f* pts, std::size_t n, const Params& params, std::uint64_t seed,
                        std::vector<std::uint8_t>& inlier, PlaneFitScratch& scratch, double maxSlopeDegrees,
                        double minInlierRatio, const PointMoments* moments) {
    PlaneFitResult res;
    inlier.assign(n, 0);
    if (n < 3) return res;
    // Grown, never shrunk (a vector grown again fills its new part): the first n are this cell's.
    if (scratch.x.size() < n) scratch.x.resize(n), scratch.y.resize(n), scratch.z.resize(n);
    for (std::size_t i = 0; i < n; ++i) scratch.x[i] = pts[i].x(), scratch.y[i] = pts[i].y(), scratch.z[i] = pts[i].z();
    const float thr = float(params.groundInlierThreshold);
    const double logFail = std::log(1.0 - params.ransacConfidence);
    const float minNz = float(std::cos(std::min(90.0, maxSlopeDegrees) * M_PI / 180.0)) - 1e-6f;

    std::uint64_t state = seed;
    std::size_t best = 0;
    Eigen::Vector3f bestN = Eigen::Vector3f::UnitZ();
    float bestD = 0.f;
    // Iterations needed to draw one all-inlier sample with probability ransacConfidence when a
    // share w of the points are inliers; a plane holding less than minInlierRatio is of no use, so
    // w never counts as lower than that.
    const auto iterationsFor = [&](double w) {
        const double w3 = std::pow(std::max(w, minInlierRatio), 3.0);
        if (w3 >= 1.0) return 1;
        if (w3 <= 0.0) return params.ransacMaxIterations;
        return int(std::min<double>(params.ransacMaxIterations, std::max(1.0, std::ceil(logFail / std::log(1.0 - w3)))));
    };
    int needed = iterationsFor(0.0);
    int it = 0;
    while (it < needed) {
        ++it;
        const std::size_t i = splitmix64(state) % n;
        std::size_t j = splitmix64(state) % (n - 1);
        std::size_t k = splitmix64(state) % (n - 2);
        // Three distinct indices without rejection loops.
        if (j >= i) ++j;
        const std::size_t a = std::min(i, j), b = std::max(i, j);
        if (k >= a) ++k;
        if (k >= b) ++k;
        Eigen::Vector3f nrm;
        float d;
        if (!hypothesis(pts[i], pts[j], pts[k], thr, nrm, d) || nrm.z() < minNz) continue;
        const std::size_t count = markInliers(scratch, n, nrm, d, thr, nullptr);
        if (count > best) {
            best = count;
            bestN = nrm;
            bestD = d;
            if (best == n) break;
            needed = iterationsFor(double(best) / double(n));
        }
    }
    res.iterations = it;
    if (best < 3) return res;  // no acceptable plane

    // Least-squares refinement on the inliers; kept only if it is well defined (inliers not
    // collinear at the noise scale), within the slope limit, and does not lose inliers.
    if (best == n)
        std::fill(inlier.begin(), inlier.end(), 1);  // the count over the same plane found every point in
    else
        markInliers(scratch, n, bestN, bestD, thr, inlier.data());
    Eigen::Vector3f refN;
    float refD;
    const PointMoments* all = moments && moments->count == n && best == n ? moments : nullptr;
    if (leastSquaresPlane(pts, n, inlier, thr, all, refN, refD) && refN.z() >= minNz) {
        std::vector<std::uint8_t>& refMask = scratch.mask;
        refMask.resize(n);
        const std::size_t refCount = markInliers(scratch, n, refN, refD, thr, refMask.data());
        if (refCount >= best) {
            bestN = refN, bestD = refD, best = refCount;
            inlier.swap(refMask);
        }
    }
    res.valid = true;
    res.normal = bestN;
    res.d = bestD;
    res.numInliers = best;
    return res;
}

}  // namespace gseg
