#include <gseg/cell_classifier.hpp>

#include <Eigen/Eigenvalues>
#include <cmath>

namespace gseg {

CellClassification classifyCell(const Eigen::Vector3f* pts, std::size_t n, const Params& params) {
    CellClassification out;
    if (n == 0) return out;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < n; ++i) mean += pts[i].cast<double>();
    mean /= double(n);
    out.mean = mean.cast<float>();
    if (n < std::size_t(params.minPointsPerCell)) return out;  // TooFewPoints

    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3d d = pts[i].cast<double>() - mean;
        cov.noalias() += d * d.transpose();
    }
    cov /= double(n);

    if (n < std::size_t(params.minPointsForPca)) {
        // Too few points for a stable PCA: a cell taller than it is wide stands up.
        out.cellClass = CellClass::Small;
        const bool upright = cov(2, 2) > cov(0, 0) && cov(2, 2) > cov(1, 1);
        out.groundCandidate = !upright;
        out.rejection = upright ? CellOutcome::Steep : CellOutcome::Ground;
        return out;
    }

    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(cov);
    const Eigen::Vector3d l = eig.eigenvalues();  // ascending: l3, l2, l1
    const double sum = l.sum();
    const double ratio = sum > 1e-12 ? l(2) / sum : 0.0;  // identical points: treated as clutter

    const double sinSlope = std::sin(params.slopeThresholdDegrees * M_PI / 180.0);
    if (ratio > params.lineRatioThreshold) {
        out.cellClass = CellClass::Line;
        const double verticalComponent = std::abs(eig.eigenvectors().col(2).z());  // sin(line elevation)
        out.groundCandidate = verticalComponent <= sinSlope;
        out.rejection = out.groundCandidate ? CellOutcome::Ground : CellOutcome::Steep;
    } else if (ratio > params.planeRatioThreshold) {
        out.cellClass = CellClass::Plane;
        out.groundCandidate = true;  // the plane fit decides the slope
        out.rejection = CellOutcome::Ground;
    } else {
        out.cellClass = CellClass::NonPlanar;
        out.rejection = CellOutcome::NonPlanar;
    }
    return out;
}

Sparsity sparsityBucket(double volumePerPoint, const Params& params) {
    if (volumePerPoint < params.sparsityLow) return Sparsity::Low;
    if (volumePerPoint < params.sparsityMedium) return Sparsity::Medium;
    return Sparsity::High;
}

}  // namespace gseg
