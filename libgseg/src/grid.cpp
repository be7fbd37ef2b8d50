#include <gseg/grid.hpp>

#include "cpu_features.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

namespace gseg {
namespace detail {

// cellCoord of n values into out: a loop that vectorises (two quotients at a time on x86-64's
// baseline); on x86-64 CPUs with AVX2 (checked once) four at a time, with AVX's floor
// instruction: the same values (no fused multiply-add). There the quotient is first taken as a
// product with the reciprocal of the size (q'), which differs from the division's quotient q by at
// most 3 units of 2^-53 |q'|: where q' lies farther than 2^-40 (1 + |q'|) from every integer and
// |q'| < 2^29 (no clamp), floor(q) = floor(q'); the few other values take the division.
#if defined(__GNUC__) && defined(__x86_64__)
namespace {
__attribute__((target("avx2"))) void cellCoordsAvx2(const float* v, std::size_t n, double size, double origin,
                                                    std::int32_t* out) {
    constexpr double lim = 1073741824.0;  // as cellCoord
    const auto divided = [&](std::size_t k) {
        double q = (static_cast<double>(v[k]) - origin) / size;
        q = q > -lim ? q : -lim;
        q = q < lim ? q : lim;
        out[k] = static_cast<std::int32_t>(std::floor(q));
    };
    const __m256d inv = _mm256_set1_pd(1.0 / size), org = _mm256_set1_pd(origin);
    const __m256d one = _mm256_set1_pd(1.0), tol = _mm256_set1_pd(0x1p-40), safe = _mm256_set1_pd(0x1p29);
    const __m256d absMask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL));
    std::size_t k = 0;
    for (; k + 4 <= n; k += 4) {
        const __m256d q = _mm256_mul_pd(_mm256_sub_pd(_mm256_cvtps_pd(_mm_loadu_ps(v + k)), org), inv);
        const __m256d f = _mm256_floor_pd(q);
        const __m256d a = _mm256_and_pd(q, absMask);
        const __m256d margin = _mm256_mul_pd(tol, _mm256_add_pd(one, a));
        const __m256d frac = _mm256_sub_pd(q, f);  // exact, in [0, 1)
        const __m256d ok = _mm256_and_pd(_mm256_and_pd(_mm256_cmp_pd(frac, margin, _CMP_GT_OQ),
                                                       _mm256_cmp_pd(_mm256_sub_pd(one, frac), margin, _CMP_GT_OQ)),
                                         _mm256_cmp_pd(a, safe, _CMP_LT_OQ));  // false for NaN
        if (_mm256_movemask_pd(ok) == 0xf)
            _mm_storeu_si128(reinterpret_cast<__m128i*>(out + k), _mm256_cvttpd_epi32(f));
        else
            for (std::size_t j = k; j < k + 4; ++j) divided(j);
    }
    for (; k < n; ++k) divided(k);
}
}  // namespace
#endif

// lo = min(lo, v[k]) and hi = max(hi, v[k]) over k < n, in a loop that vectorises (inlined into
// both forms of valueRange).
__attribute__((always_inline)) inline void rangeLoop(const std::int32_t* v, std::size_t n, std::int32_t& lo,
                                                     std::int32_t& hi) {
    std::int32_t l = lo, h = hi;
    for (std::size_t k = 0; k < n; ++k) l = std::min(l, v[k]), h = std::max(h, v[k]);
    lo = l, hi = h;
}
#if defined(__GNUC__) && defined(__x86_64__)
namespace {
__attribute__((target("avx2"))) void rangeAvx2(const std::int32_t* v, std::size_t n, std::int32_t& lo, std::int32_t& hi) {
    rangeLoop(v, n, lo, hi);  // eight lanes, one instruction each for min and max (SSE2 has neither)
}
}  // namespace
#endif

void valueRange(const std::int32_t* v, std::size_t n, std::int32_t& lo, std::int32_t& hi) {
#if defined(__GNUC__) && defined(__x86_64__)
    if (cpuHasAvx2()) return rangeAvx2(v, n, lo, hi);
#endif
    rangeLoop(v, n, lo, hi);
}

void cellCoords(const float* v, std::size_t n, double size, double origin, std::int32_t* out) {
#if defined(__GNUC__) && defined(__x86_64__)
    if (cpuHasAvx2()) return cellCoordsAvx2(v, n, size, origin, out);
#endif
    for (std::size_t k = 0; k < n; ++k) out[k] = cellCoord(v[k], size, origin);
}

}  // namespace detail

void Grid::build(const PointCloudView& cloud, const std::vector<std::uint32_t>& indices, double sx,
                 double sy, double sz, double originZ) {
    const std::size_t n = indices.size();
    cells_.clear();
    order_.resize(n);
    if (n == 0) return;

    coords_.resize(3 * n);
    std::int32_t lo[3] = {std::numeric_limits<std::int32_t>::max(), std::numeric_limits<std::int32_t>::max(),
                          std::numeric_limits<std::int32_t>::max()};
    std::int32_t hi[3] = {std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::min(),
                          std::numeric_limits<std::int32_t>::min()};
    for (std::size_t k = 0; k < n; ++k) {
        const float* p = cloud.point(indices[k]);
        const std::int32_t c[3] = {cellCoord(p[0], sx), cellCoord(p[1], sy), cellCoord(p[2], sz, originZ)};
        for (int a = 0; a < 3; ++a) {
            coords_[3 * k + a] = c[a];
            lo[a] = std::min(lo[a], c[a]);
            hi[a] = std::max(hi[a], c[a]);
        }
    }
    const std::uint64_t ext[3] = {std::uint64_t(std::int64_t(hi[0]) - lo[0] + 1),
                                  std::uint64_t(std::int64_t(hi[1]) - lo[1] + 1),
                                  std::uint64_t(std::int64_t(hi[2]) - lo[2] + 1)};
    const double volume = double(ext[0]) * double(ext[1]) * double(ext[2]);
    const double denseLimit = std::max<double>(8.0 * double(n), 1 << 20);

    auto emitCells = [&](auto keyAt) {
        // order_ holds positions k (into indices) sorted by key; turn them into cells.
        for (std::size_t s = 0; s < n;) {
            const auto key = keyAt(order_[s]);
            std::size_t e = s + 1;
            while (e < n && keyAt(order_[e]) == key) ++e;
            const std::uint32_t k = order_[s];
            cells_.push_back({coords_[3 * k], coords_[3 * k + 1], coords_[3 * k + 2], std::uint32_t(s),
                              std::uint32_t(e)});
            s = e;
        }
        for (std::size_t s = 0; s < n; ++s) order_[s] = indices[order_[s]];
    };

    if (volume <= denseLimit) {
        // Counting sort on the dense linear index of the occupied bounding box: O(n + volume).
        keys_.resize(n);
        counts_.assign(std::size_t(volume) + 1, 0);
        for (std::size_t k = 0; k < n; ++k) {
            const std::uint64_t key = (std::uint64_t(coords_[3 * k] - lo[0]) * ext[1] +
                                       std::uint64_t(coords_[3 * k + 1] - lo[1])) * ext[2] +
                                      std::uint64_t(coords_[3 * k + 2] - lo[2]);
            keys_[k] = std::uint32_t(key);
            ++counts_[key + 1];
        }
        for (std::size_t b = 1; b < counts_.size(); ++b) counts_[b] += counts_[b - 1];
        for (std::size_t k = 0; k < n; ++k) order_[counts_[keys_[k]]++] = std::uint32_t(k);
        emitCells([&](std::uint32_t k) { return keys_[k]; });
    } else {
        // Sparse fallback (points spread over a huge box): sort 64-bit keys. Each coordinate
        // offset fits in 21 bits only if the box is small, so compare the coordinate triples.
        sortKeys_.resize(n);
        for (std::size_t k = 0; k < n; ++k) sortKeys_[k] = k;
        auto less = [&](std::uint64_t a, std::uint64_t b) {
            const std::int32_t* ca = &coords_[3 * a];
            const std::int32_t* cb = &coords_[3 * b];
            if (ca[0] != cb[0]) return ca[0] < cb[0];
            if (ca[1] != cb[1]) return ca[1] < cb[1];
            if (ca[2] != cb[2]) return ca[2] < cb[2];
            return a < b;
        };
        std::sort(sortKeys_.begin(), sortKeys_.end(), less);
        for (std::size_t s = 0; s < n; ++s) order_[s] = std::uint32_t(sortKeys_[s]);
        struct Triple {
            std::int32_t a, b, c;
            bool operator==(const Triple& o) const { return a == o.a && b == o.b && c == o.c; }
        };
        emitCells([&](std::uint32_t k) { return Triple{coords_[3 * k], coords_[3 * k + 1], coords_[3 * k + 2]}; });
    }
}

namespace {
constexpr std::int64_t kColumnBias = std::int64_t(1) << 31;
std::uint64_t columnKey(std::int32_t ix, std::int32_t iy) {
    return (std::uint64_t(std::int64_t(ix) + kColumnBias) << 32) | std::uint64_t(std::int64_t(iy) + kColumnBias);
}

// Point k of `indices`: from pointsOfIndices where the caller has them at hand, else the cloud.
Eigen::Vector3f pointOf(const PointCloudView& cloud, const std::vector<std::uint32_t>& indices,
                        const Eigen::Vector3f* pointsOfIndices, std::size_t k) {
    if (pointsOfIndices) return pointsOfIndices[k];
    const float* p = cloud.point(indices[k]);
    return Eigen::Vector3f(p[0], p[1], p[2]);
}

// (ix, iy) of the column ids 0, 1, 2, ... visited in turn: dense ids are stepped along
// (c / extY, c % extY without a division per column), sparse ids looked up.
class ColumnWalk {
public:
    explicit ColumnWalk(const ColumnIndex& columns)
        : columns_(columns), dense_(columns.denseIds()), extY_(dense_ ? columns.extentY() : 1) {}
    /// Moves to column c (called for c = 0, 1, 2, ... in order).
    void step(std::uint32_t c) {
        if (c > 0 && ++y_ == extY_) y_ = 0, ++x_;
    }
    std::int32_t ix(std::uint32_t c) const { return dense_ ? std::int32_t(columns_.loX() + x_) : columns_.ix(c); }
    std::int32_t iy(std::uint32_t c) const { return dense_ ? std::int32_t(columns_.loY() + y_) : columns_.iy(c); }

private:
    const ColumnIndex& columns_;
    bool dense_;
    std::int64_t extY_;
    std::int64_t x_ = 0, y_ = 0;
};
}  // namespace

// The z cells of the points `indices` in their order, computed in loops that vectorise (from
// zOfIndices where the caller has their z at hand).
void Grid::zCells(const PointCloudView& cloud, const std::vector<std::uint32_t>& indices,
                  const Eigen::Vector3f* pointsOfIndices, const float* zOfIndices, double sz, double originZ,
                  std::vector<std::int32_t>& out) {
    const std::size_t n = indices.size();
    out.resize(n);
    if (!zOfIndices) {
        zs_.resize(n);
        for (std::size_t k = 0; k < n; ++k) zs_[k] = pointsOfIndices ? pointsOfIndices[k].z() : cloud.z(indices[k]);
        zOfIndices = zs_.data();
    }
    detail::cellCoords(zOfIndices, n, sz, originZ, out.data());
}

void ColumnIndex::build(const PointCloudView& cloud, const std::vector<std::uint32_t>& indices, double sx, double sy,
                        std::vector<std::uint32_t>& columnOf) {
    const std::size_t n = indices.size();
    columnOf.resize(n);
    coords_.resize(2 * n);
    xy_.resize(2 * n);
    z_.resize(n);
    // The coordinates gathered first, then the cells and the box in loops that vectorise.
    float* const xs = xy_.data();
    float* const ys = xy_.data() + n;
    float* const zs = z_.data();
    for (std::size_t k = 0; k < n; ++k) {
        const float* p = cloud.point(indices[k]);
        xs[k] = p[0], ys[k] = p[1], zs[k] = p[2];
    }
    std::int32_t* const cxs = coords_.data();
    std::int32_t* const cys = coords_.data() + n;
    detail::cellCoords(xs, n, sx, 0.0, cxs);
    detail::cellCoords(ys, n, sy, 0.0, cys);
    std::int32_t lo[2] = {std::numeric_limits<std::int32_t>::max(), std::numeric_limits<std::int32_t>::max()};
    std::int32_t hi[2] = {std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::min()};
    detail::valueRange(cxs, n, lo[0], hi[0]);
    detail::valueRange(cys, n, lo[1], hi[1]);
    keys_.clear();
    if (n == 0) {
        dense_ = true, lo_[0] = lo_[1] = 0, extY_ = 1, size_ = 0;
        return;
    }
    const double area = (double(hi[0]) - lo[0] + 1) * (double(hi[1]) - lo[1] + 1);
    dense_ = area <= 4.0 * double(n) + 65536.0;
    if (dense_) {
        lo_[0] = lo[0], lo_[1] = lo[1];
        extY_ = std::int64_t(hi[1]) - lo[1] + 1;
        size_ = std::uint32_t(area);
        // Dense ids fit 32 bits (the box holds at most 4 n + 65536 columns).
        const std::uint32_t ey = std::uint32_t(extY_), lx = std::uint32_t(lo[0]), ly = std::uint32_t(lo[1]);
        for (std::size_t k = 0; k < n; ++k) columnOf[k] = (std::uint32_t(cxs[k]) - lx) * ey + (std::uint32_t(cys[k]) - ly);
        return;
    }
    keys_.resize(n);
    for (std::size_t k = 0; k < n; ++k) keys_[k] = columnKey(coords_[k], coords_[n + k]);
    std::sort(keys_.begin(), keys_.end());
    keys_.erase(std::unique(keys_.begin(), keys_.end()), keys_.end());
    size_ = std::uint32_t(keys_.size());
    for (std::size_t k = 0; k < n; ++k)
        columnOf[k] = std::uint32_t(
            std::lower_bound(keys_.begin(), keys_.end(), columnKey(coords_[k], coords_[n + k])) - keys_.begin());
}

std::int64_t ColumnIndex::findSparse(std::int32_t ix, std::int32_t iy) const {
    const std::uint64_t key = columnKey(ix, iy);
    const auto it = std::lower_bound(keys_.begin(), keys_.end(), key);
    return it != keys_.end() && *it == key ? std::int64_t(it - keys_.begin()) : -1;
}

std::int32_t ColumnIndex::ix(std::uint32_t id) const {
    return dense_ ? std::int32_t(lo_[0] + std::int64_t(id) / extY_) : std::int32_t(std::int64_t(keys_[id] >> 32) - kColumnBias);
}

std::int32_t ColumnIndex::iy(std::uint32_t id) const {
    return dense_ ? std::int32_t(lo_[1] + std::int64_t(id) % extY_)
                  : std::int32_t(std::int64_t(keys_[id] & 0xffffffffull) - kColumnBias);
}

// One stable counting sort by the key (column, z cell) where the columns times the z cells of the
// points are few (Phase I's tall cells over a scan: about 10^5 keys): each point is moved once,
// straight to its place, and the cells are read off the keys in order. Returns false (nothing
// done) where there would be too many keys.
bool Grid::buildByColumnAndZ(const PointCloudView& cloud, const std::vector<std::uint32_t>& indices,
                             const ColumnIndex& columns, const std::uint32_t* columnOf, double sz, double originZ,
                             const Eigen::Vector3f* pointsOfIndices, const float* zOfIndices) {
    const std::size_t n = indices.size();
    const std::uint32_t numColumns = columns.size();
    zCells(cloud, indices, pointsOfIndices, zOfIndices, sz, originZ, izIn_);
    std::int32_t lo = izIn_[0], hi = izIn_[0];
    detail::valueRange(izIn_.data() + 1, n - 1, lo, hi);
    const std::uint64_t range = std::uint64_t(std::int64_t(hi) - lo) + 1;
    const std::uint64_t numKeys = range * numColumns;
    if (numKeys > 4 * std::uint64_t(n) + 65536 || numKeys >= (std::uint64_t(1) << 32)) return false;
    const std::uint32_t r = std::uint32_t(range);
    keys_.resize(n);
    counts_.assign(std::size_t(numKeys) + 1, 0);
    // The keys first (a loop that vectorises), then their counts.
    std::uint32_t* const keys = keys_.data();
    std::uint32_t* const counts = counts_.data();
    const std::int32_t* const iz = izIn_.data();
    for (std::size_t k = 0; k < n; ++k) keys[k] = columnOf[k] * r + std::uint32_t(iz[k] - lo);
    for (std::size_t k = 0; k < n; ++k) ++counts[keys[k] + 1];
    std::uint32_t sum = 0;  // the running sum in a register
    for (std::size_t b = 1; b <= numKeys; ++b) sum += counts[b], counts[b] = sum;
    for (std::size_t k = 0; k < n; ++k) {
        const std::uint32_t at = counts_[keys_[k]]++;
        order_[at] = indices[k];
        points_[at] = pointOf(cloud, indices, pointsOfIndices, k);
    }
    // counts_[key] is now the end of the key's points (and the start of the next key's).
    ColumnWalk walk(columns);
    std::uint32_t start = 0;
    for (std::uint32_t c = 0; c < numColumns; ++c) {
        walk.step(c);
        columnCells_[c] = std::uint32_t(cells_.size());
        if (counts_[std::size_t(c) * r + r - 1] == start) continue;  // no point in the column
        const std::int32_t ix = walk.ix(c), iy = walk.iy(c);
        for (std::uint32_t z = 0; z < r; ++z) {
            const std::uint32_t end = counts_[std::size_t(c) * r + z];
            if (end == start) continue;
            cells_.push_back({ix, iy, std::int32_t(std::int64_t(lo) + z), start, end});
            cellColumns_.push_back(c);
            start = end;
        }
    }
    columnCells_[numColumns] = std::uint32_t(cells_.size());
    return true;
}

// Stable counting sort by column, then within each column a stable sort by z cell: the order of
// build()'s stable sort by (ix, iy, iz).
void Grid::build(const PointCloudView& cloud, const std::vector<std::uint32_t>& indices, const ColumnIndex& columns,
                 const std::uint32_t* columnOf, double sz, double originZ,
                 const Eigen::Vector3f* pointsOfIndices, const float* zOfIndices) {
    const std::size_t n = indices.size();
    const std::uint32_t numColumns = columns.size();
    cells_.clear();
    cellColumns_.clear();
    order_.resize(n);
    points_.resize(n);
    columnCells_.assign(std::size_t(numColumns) + 1, 0);
    if (n == 0) return;
    // Input already grouped by column in ascending order (Phase II: Phase I hands its ground over
    // cell by cell)? Then the stable counting sort by column keeps it as it is.
    // (In blocks whose test vectorises, stopping after the first block out of order.)
    bool sorted = true;
    for (std::size_t b = 1; b < n && sorted; b += 1024) {
        const std::size_t e = std::min(n, b + 1024);
        unsigned down = 0;
        for (std::size_t k = b; k < e; ++k) down |= columnOf[k] < columnOf[k - 1] ? 1u : 0u;
        sorted = down == 0;
    }
    if (!sorted && buildByColumnAndZ(cloud, indices, columns, columnOf, sz, originZ, pointsOfIndices, zOfIndices)) return;
    counts_.assign(std::size_t(numColumns) + 1, 0);
    if (!sorted) {
        for (std::size_t k = 0; k < n; ++k) ++counts_[columnOf[k] + 1];
        for (std::size_t c = 1; c <= numColumns; ++c) counts_[c] += counts_[c - 1];
    }
    const std::uint32_t* byColumn = indices.data();  // the points' indices, grouped by column
    const Eigen::Vector3f* byColumnPoints = pointsOfIndices;  // and their coordinates
    iz_.resize(n);
    sortedIz_.resize(n);
    if (sorted) {
        // The end of each column: where the next column's points begin (no count per point).
        // (Only where the column changes, found by a test that vectorises.)
        std::uint32_t c = 0;
        for (std::uint32_t b = 0; b < std::uint32_t(n); b += 64) {
            const std::uint32_t e = std::min(std::uint32_t(n), b + 64);
            if (columnOf[e - 1] == c) continue;  // sorted: the whole block lies in column c
            for (std::uint32_t k = b; k < e; ++k)
                while (c < columnOf[k]) counts_[c++] = k;
        }
        while (c < numColumns) counts_[c++] = std::uint32_t(n);
        if (!byColumnPoints) {
            byColumnPoints_.resize(n);
            for (std::size_t k = 0; k < n; ++k) byColumnPoints_[k] = pointOf(cloud, indices, nullptr, k);
            byColumnPoints = byColumnPoints_.data();
        }
        zCells(cloud, indices, byColumnPoints, zOfIndices, sz, originZ, iz_);
    } else {
        byColumn_.resize(n);
        byColumnPoints_.resize(n);
        // The z cells in the input's order first (vectorised), then carried along.
        zCells(cloud, indices, pointsOfIndices, zOfIndices, sz, originZ, izIn_);
        for (std::size_t k = 0; k < n; ++k) {
            const std::uint32_t at = counts_[columnOf[k]]++;
            byColumn_[at] = indices[k];
            byColumnPoints_[at] = pointOf(cloud, indices, pointsOfIndices, k);
            iz_[at] = izIn_[k];
        }
        byColumn = byColumn_.data();
        byColumnPoints = byColumnPoints_.data();
    }
    // counts_[c] is now the end of column c (and the start of column c + 1).
    std::uint32_t start = 0;
    ColumnWalk walk(columns);
    for (std::uint32_t c = 0; c < numColumns; ++c) {
        walk.step(c);
        const std::uint32_t end = counts_[c];
        columnCells_[c] = std::uint32_t(cells_.size());
        if (start == end) continue;
        const std::int32_t ix = walk.ix(c), iy = walk.iy(c);
        std::int32_t lo = iz_[start], hi = iz_[start];
        for (std::uint32_t k = start + 1; k < end; ++k) lo = std::min(lo, iz_[k]), hi = std::max(hi, iz_[k]);
        if (lo == hi) {
            std::copy(byColumn + start, byColumn + end, order_.begin() + start);
            std::copy(byColumnPoints + start, byColumnPoints + end, points_.begin() + start);
            cells_.push_back({ix, iy, lo, start, end});
            cellColumns_.push_back(c);
            start = end;
            continue;
        }
        // Stable sort of the column's points by z cell: counting sort over a small range, else a
        // stable comparison sort of (iz, position) keys.
        const std::uint64_t range = std::uint64_t(std::int64_t(hi) - lo) + 1;
        if (range <= 4 * std::uint64_t(end - start) + 64) {
            zCounts_.assign(std::size_t(range) + 1, 0);
            for (std::uint32_t k = start; k < end; ++k) ++zCounts_[std::size_t(iz_[k] - lo) + 1];
            for (std::size_t b = 1; b <= range; ++b) zCounts_[b] += zCounts_[b - 1];
            for (std::uint32_t k = start; k < end; ++k) {
                const std::uint32_t at = start + zCounts_[std::size_t(iz_[k] - lo)]++;
                order_[at] = byColumn[k];
                points_[at] = byColumnPoints[k];
                sortedIz_[at] = iz_[k];
            }
        } else {
            sortKeys_.resize(end - start);
            for (std::uint32_t k = start; k < end; ++k)
                sortKeys_[k - start] = (std::uint64_t(std::int64_t(iz_[k]) + kColumnBias) << 32) | (k - start);
            std::sort(sortKeys_.begin(), sortKeys_.begin() + (end - start));
            for (std::uint32_t k = start; k < end; ++k) {
                const std::uint32_t from = start + std::uint32_t(sortKeys_[k - start] & 0xffffffffull);
                order_[k] = byColumn[from];
                points_[k] = byColumnPoints[from];
                sortedIz_[k] = iz_[from];
            }
        }
        for (std::uint32_t s = start; s < end;) {
            std::uint32_t e = s + 1;
            while (e < end && sortedIz_[e] == sortedIz_[s]) ++e;
            cells_.push_back({ix, iy, sortedIz_[s], s, e});
            cellColumns_.push_back(c);
            s = e;
        }
        start = end;
    }
    columnCells_[numColumns] = std::uint32_t(cells_.size());
}

}  // namespace gseg
