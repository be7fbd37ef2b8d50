#include <gseg/cell_classifier.hpp>

#include "cpu_features.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define GSEG_AVX2_FORMS 1
#endif

namespace gseg {

#if defined(GSEG_AVX2_FORMS)
namespace {
// pointSum and scatterMatrix on CPUs with AVX2: a point's x, y, z in the lanes 0-2 of one register
// of four doubles, each lane adding (and multiplying) what the SSE2 form's lane or scalar does, in
// the points' order: the same values. (Lane 3 holds whatever follows a point and is never read.)
// Point p as (x, y, z, *) in doubles: one 16-byte load where a point follows it (its x is the
// fourth float), two loads for the last point (nothing may be read past it).
__attribute__((target("avx2"))) inline __m256d loadFollowed(const float* p) { return _mm256_cvtps_pd(_mm_loadu_ps(p)); }
__attribute__((target("avx2"))) inline __m256d loadLast(const float* p) {
    const __m128 xy = _mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)));
    return _mm256_cvtps_pd(_mm_movelh_ps(xy, _mm_load_ss(p + 2)));
}

template <bool kMasked>
__attribute__((target("avx2"))) Eigen::Vector3d pointSumAvx2(const Eigen::Vector3f* pts, std::size_t n,
                                                               const std::uint8_t* mask, std::size_t& count) {
    __m256d sum = _mm256_setzero_pd();
    if (n == 0) return Eigen::Vector3d::Zero();
    std::size_t m = 0;  // (a local: the caller's count would be stored per point)
    for (std::size_t i = 0; i + 1 < n; ++i) {
        if (kMasked && !mask[i]) continue;
        sum = _mm256_add_pd(sum, loadFollowed(pts[i].data()));
        ++m;
    }
    if (!kMasked || mask[n - 1]) sum = _mm256_add_pd(sum, loadLast(pts[n - 1].data())), ++m;
    count = m;
    alignas(32) double a[4];
    _mm256_store_pd(a, sum);
    return Eigen::Vector3d(a[0], a[1], a[2]);
}

template <bool kMasked>
__attribute__((target("avx2"))) Eigen::Matrix3d scatterMatrixAvx2(const Eigen::Vector3f* pts, std::size_t n,
                                                                    const Eigen::Vector3d& mean, const std::uint8_t* mask) {
    const __m256d m = _mm256_set_pd(0.0, mean.z(), mean.y(), mean.x());
    __m256d lower = _mm256_setzero_pd(), rest = _mm256_setzero_pd();  // (xx, yx, zx, *) and (yy, zy, zz, *)
    // (dx dx, dy dx, dz dx, *) and (dy dy, dz dy, dz dz, *): d times lane 0, lanes (1, 2, 2) times lanes (1, 1, 2).
    const auto add = [&](__m256d p) __attribute__((target("avx2"))) {
        const __m256d d = _mm256_sub_pd(p, m);  // (dx, dy, dz, *)
        lower = _mm256_add_pd(lower, _mm256_mul_pd(d, _mm256_permute4x64_pd(d, 0x00)));
        rest = _mm256_add_pd(rest, _mm256_mul_pd(_mm256_permute4x64_pd(d, 0xE9), _mm256_permute4x64_pd(d, 0xE5)));
    };
    if (n == 0) return Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i + 1 < n; ++i)
        if (!kMasked || mask[i]) add(loadFollowed(pts[i].data()));
    if (!kMasked || mask[n - 1]) add(loadLast(pts[n - 1].data()));
    alignas(32) double a[4], b[4];
    _mm256_store_pd(a, lower), _mm256_store_pd(b, rest);
    Eigen::Matrix3d out;
    out << a[0], a[1], a[2], a[1], b[0], b[1], a[2], b[1], b[2];
    return out;
}
}  // namespace
#endif

Eigen::Vector3d detail::pointSum(const Eigen::Vector3f* pts, std::size_t n, const std::uint8_t* mask, std::size_t* count) {
    std::size_t m = 0;
#if defined(GSEG_AVX2_FORMS)
    if (cpuHasAvx2()) {
        const Eigen::Vector3d sum = mask ? pointSumAvx2<true>(pts, n, mask, m) : pointSumAvx2<false>(pts, n, mask, m);
        if (count) *count = m;
        return sum;
    }
#endif
#if defined(__SSE2__)
    __m128d xy = _mm_setzero_pd();
    double z = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (mask && !mask[i]) continue;
        const float* p = pts[i].data();
        xy = _mm_add_pd(xy, _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)))));
        z += double(p[2]);
        ++m;
    }
    double a[2];
    _mm_storeu_pd(a, xy);
    const Eigen::Vector3d sum(a[0], a[1], z);
#else
    double x = 0, y = 0, z = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (mask && !mask[i]) continue;
        x += double(pts[i].x()), y += double(pts[i].y()), z += double(pts[i].z());
        ++m;
    }
    const Eigen::Vector3d sum(x, y, z);
#endif
    if (count) *count = m;
    return sum;
}

Eigen::Matrix3d detail::scatterMatrix(const Eigen::Vector3f* pts, std::size_t n, const Eigen::Vector3d& mean,
                                      const std::uint8_t* mask) {
    // Element (r, c) sums d_r d_c in the points' order, as Eigen's outer product does; (c, r) is
    // the same product (multiplication commutes exactly), so only the lower triangle is summed.
#if defined(GSEG_AVX2_FORMS)
    if (cpuHasAvx2()) return mask ? scatterMatrixAvx2<true>(pts, n, mean, mask) : scatterMatrixAvx2<false>(pts, n, mean, mask);
#endif
#if defined(__SSE2__)
    const __m128d mxy = _mm_set_pd(mean.y(), mean.x());  // lanes (x, y)
    const __m128d mz = _mm_set_sd(mean.z());
    __m128d xxyx = _mm_setzero_pd(), yyzy = _mm_setzero_pd(), xzzz = _mm_setzero_pd();
    for (std::size_t i = 0; i < n; ++i) {
        if (mask && !mask[i]) continue;
        const float* p = pts[i].data();
        const __m128d dxy = _mm_sub_pd(_mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)))), mxy);
        const __m128d dz = _mm_sub_sd(_mm_cvtss_sd(_mm_setzero_pd(), _mm_load_ss(p + 2)), mz);
        xxyx = _mm_add_pd(xxyx, _mm_mul_pd(dxy, _mm_unpacklo_pd(dxy, dxy)));                 // (dx dx, dy dx)
        yyzy = _mm_add_pd(yyzy, _mm_mul_pd(_mm_shuffle_pd(dxy, dz, 1), _mm_unpackhi_pd(dxy, dxy)));  // (dy dy, dz dy)
        xzzz = _mm_add_pd(xzzz, _mm_mul_pd(_mm_unpacklo_pd(dxy, dz), _mm_unpacklo_pd(dz, dz)));   // (dx dz, dz dz)
    }
    double a[2], b[2], c[2];
    _mm_storeu_pd(a, xxyx), _mm_storeu_pd(b, yyzy), _mm_storeu_pd(c, xzzz);
    const double xx = a[0], yx = a[1], yy = b[0], zy = b[1], zx = c[0], zz = c[1];
#else
    double xx = 0, yx = 0, zx = 0, yy = 0, zy = 0, zz = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (mask && !mask[i]) continue;
        const Eigen::Vector3d d = pts[i].cast<double>() - mean;
        xx += d.x() * d.x(), yx += d.y() * d.x(), zx += d.z() * d.x();
        yy += d.y() * d.y(), zy += d.z() * d.y(), zz += d.z() * d.z();
    }
#endif
    Eigen::Matrix3d m;
    m << xx, yx, zx, yx, yy, zy, zx, zy, zz;
    return m;
}

SlopeLimit::SlopeLimit(const Params& params)
    : sin(std::sin(params.slopeThresholdDegrees * M_PI / 180.0)), cos(std::cos(params.slopeThresholdDegrees * M_PI / 180.0)) {}

CellClassification classifyCell(const Eigen::Vector3f* pts, std::size_t n, const Params& params) {
    return classifyCell(pts, n, params, SlopeLimit(params));
}

CellClassification classifyCell(const Eigen::Vector3f* pts, std::size_t n, const Params& params, const SlopeLimit& slope,
                                PointMoments* moments) {
    CellClassification out;
    if (moments) moments->count = 0;
    if (n == 0) return out;
    Eigen::Vector3d mean = detail::pointSum(pts, n);
    mean /= double(n);
    out.mean = mean.cast<float>();
    if (n < std::size_t(params.minPointsPerCell)) return out;  // TooFewPoints

    Eigen::Matrix3d cov = detail::scatterMatrix(pts, n, mean);
    if (moments) moments->count = n, moments->mean = mean, moments->scatter = cov;
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

    const double sinSlope = slope.sin;
    const double cosSlope = slope.cos;
    if (ratio > params.lineRatioThreshold) {
        out.cellClass = CellClass::Line;
        const double verticalComponent = std::abs(eig.eigenvectors().col(2).z());  // sin(line elevation)
        // A "line" with a clear second extent is a strip; if that strip stands upright (its normal
        // steeper than the limit) it is the foot of a wall or a fence seen by a few rings.
        const bool strip = l(1) >= params.stripMinSpread * params.stripMinSpread;
        const bool uprightStrip = params.checkPlaneNormal && strip && std::abs(eig.eigenvectors().col(0).z()) < cosSlope;
        out.groundCandidate = verticalComponent <= sinSlope && !uprightStrip;
        out.rejection = out.groundCandidate ? CellOutcome::Ground : CellOutcome::Steep;
        const Eigen::Vector3d axis = eig.eigenvectors().col(2);
        const Eigen::Vector3d across = Eigen::Vector3d::UnitZ().cross(axis);
        if (across.squaredNorm() > 1e-12) {
            Eigen::Vector3d n = axis.cross(across).normalized();
            out.normal = (n.z() < 0 ? -n : n).cast<float>();
        }
    } else if (ratio > params.planeRatioThreshold) {
        out.cellClass = CellClass::Plane;
        // A normal steeper than the limit is a wall, a car side or a hedge face; in a 0.2 m slab the
        // plane fit could not tell (a horizontal plane through the slab holds every point of it).
        const bool steep = std::abs(eig.eigenvectors().col(0).z()) < cosSlope;
        out.steepNormal = params.checkPlaneNormal && steep;
        out.groundCandidate = true;
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
