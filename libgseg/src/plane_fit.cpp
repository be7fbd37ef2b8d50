#include <gseg/plane_fit.hpp>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace gseg {
namespace {

std::size_t markInliers(const Eigen::Vector3f* pts, std::size_t n, const Eigen::Vector3f& normal, float d,
                        float thr, std::vector<std::uint8_t>* mask) {
    std::size_t count = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const bool in = std::abs(normal.dot(pts[i]) + d) <= thr;
        count += in;
        if (mask) (*mask)[i] = in;
    }
    return count;
}

// Least-squares plane through the masked points: normal = smallest principal axis.
bool leastSquaresPlane(const Eigen::Vector3f* pts, std::size_t n, const std::vector<std::uint8_t>& mask,
                       Eigen::Vector3f& normal, float& d) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    std::size_t m = 0;
    for (std::size_t i = 0; i < n; ++i)
        if (mask[i]) mean += pts[i].cast<double>(), ++m;
    if (m < 3) return false;
    mean /= double(m);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < n; ++i)
        if (mask[i]) {
            const Eigen::Vector3d q = pts[i].cast<double>() - mean;
            cov.noalias() += q * q.transpose();
        }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(cov);
    if (eig.eigenvalues()(1) <= 1e-12) return false;  // collinear inliers: no plane
    normal = eig.eigenvectors().col(0).normalized().cast<float>();
    d = float(-normal.cast<double>().dot(mean));
    return true;
}

}  // namespace

double planeSlopeDegrees(const Eigen::Vector3f& normal) {
    const double c = std::min(1.0, std::abs(double(normal.z())) / std::max(1e-12, double(normal.norm())));
    return std::acos(c) * 180.0 / M_PI;
}

PlaneFitResult fitPlane(const Eigen::Vector3f* pts, std::size_t n, const Params& params, std::uint64_t seed,
                        std::vector<std::uint8_t>& inlier) {
    PlaneFitResult res;
    inlier.assign(n, 0);
    if (n < 3) return res;
    const float thr = float(params.groundInlierThreshold);
    const double logFail = std::log(1.0 - params.ransacConfidence);

    std::uint64_t state = seed;
    std::size_t best = 0;
    Eigen::Vector3f bestN = Eigen::Vector3f::UnitZ();
    float bestD = 0.f;
    int needed = params.ransacMaxIterations;
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
        Eigen::Vector3f nrm = (pts[j] - pts[i]).cross(pts[k] - pts[i]);
        const float len = nrm.norm();
        if (!(len > 1e-9f)) continue;
        nrm /= len;
        const float d = -nrm.dot(pts[i]);
        const std::size_t count = markInliers(pts, n, nrm, d, thr, nullptr);
        if (count > best) {
            best = count;
            bestN = nrm;
            bestD = d;
            if (best == n) break;
            const double w3 = std::pow(double(best) / double(n), 3.0);
            const double adaptive = std::ceil(logFail / std::log(1.0 - w3));
            needed = int(std::min<double>(params.ransacMaxIterations, std::max(1.0, adaptive)));
        }
    }
    res.iterations = it;
    if (best < 3) return res;  // every sample collinear

    // Least-squares refinement on the inliers; kept only if it does not lose inliers.
    markInliers(pts, n, bestN, bestD, thr, &inlier);
    Eigen::Vector3f refN;
    float refD;
    if (leastSquaresPlane(pts, n, inlier, refN, refD)) {
        std::vector<std::uint8_t> refMask(n);
        const std::size_t refCount = markInliers(pts, n, refN, refD, thr, &refMask);
        if (refCount >= best) {
            bestN = refN, bestD = refD, best = refCount;
            inlier.swap(refMask);
        }
    }
    if (bestN.z() < 0) bestN = -bestN, bestD = -bestD;
    res.valid = true;
    res.normal = bestN;
    res.d = bestD;
    res.numInliers = best;
    return res;
}

}  // namespace gseg
