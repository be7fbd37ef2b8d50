#pragma once
/// \file grid.hpp
/// Binning of points into axis-aligned cells, indexed with floor (never truncation).

#include <gseg/point_cloud.hpp>

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

namespace gseg {

/// Integer index of a cell along one axis: floor((v - origin) / size), clamped to +-2^30 so that absurdly
/// far points land in a far cell of their own instead of overflowing (NaN: -2^30).
/// (Branch-free, so that loops over many points vectorise, as grid.cpp's do (compiled with
/// -fno-trapping-math, which changes no value): the quotient is clamped first, then truncated
/// towards zero and corrected down where that rounded up, all in double; x86-64 does this without
/// a call to floor(); the same value for every input.)
inline std::int32_t cellCoord(float v, double size, double origin = 0.0) {
    double q = (static_cast<double>(v) - origin) / size;
    constexpr double lim = 1073741824.0;  // 2^30
    q = q > -lim ? q : -lim;              // floor(q) <= -2^30, and NaN
    q = q < lim ? q : lim;                // floor(q) >= 2^30
    const double t = static_cast<double>(static_cast<std::int32_t>(q));  // towards zero; |q| <= 2^30 fits
    return static_cast<std::int32_t>(t > q ? t - 1.0 : t);
}

namespace detail {
/// out[k] = cellCoord(v[k], size, origin) for k < n, in loops that vectorise (AVX2 where the CPU
/// has it, checked once): the same values.
void cellCoords(const float* v, std::size_t n, double size, double origin, std::int32_t* out);
/// lo = min(lo, v[k]), hi = max(hi, v[k]) for k < n (AVX2 where the CPU has it).
void valueRange(const std::int32_t* v, std::size_t n, std::int32_t& lo, std::int32_t& hi);
}  // namespace detail

/// One occupied cell: its index and the range [begin, end) of its points in Grid::order().
struct GridCell {
    std::int32_t ix = 0, iy = 0, iz = 0;
    std::uint32_t begin = 0, end = 0;
    std::uint32_t size() const { return end - begin; }
};

/// The columns (ix, iy) of cells sx * sy of a scan's points, numbered once per scan so that both
/// phases of the segmenter bin into them without recomputing a column per point. Column ids
/// follow (ix, iy) order. Where the points' columns fit a box of a few times their number (every
/// real scan), the ids are the box's dense index (empty columns have ids too); otherwise (points
/// spread absurdly far) they are the ranks of the occupied columns. Reuses its memory.
class ColumnIndex {
public:
    /// Numbers the columns of the points `indices` of `cloud`; `columnOf[k]` receives the column
    /// id of point indices[k] (resized to indices.size()).
    void build(const PointCloudView& cloud, const std::vector<std::uint32_t>& indices, double sx, double sy,
               std::vector<std::uint32_t>& columnOf);

    /// Number of column ids (ids are 0 .. size() - 1).
    std::uint32_t size() const { return size_; }
    /// Id of column (ix, iy), or -1 where it holds no point (dense ids: outside the box).
    /// (Dense ids inline: the recovery asks for nine columns per cell.)
    std::int64_t find(std::int32_t ix, std::int32_t iy) const {
        if (!dense_) return findSparse(ix, iy);
        const std::int64_t x = std::int64_t(ix) - lo_[0], y = std::int64_t(iy) - lo_[1];
        if (x < 0 || y < 0 || y >= extY_ || x * extY_ + y >= std::int64_t(size_)) return -1;
        return x * extY_ + y;
    }
    /// Column index along x and y of the column `id`.
    std::int32_t ix(std::uint32_t id) const;
    std::int32_t iy(std::uint32_t id) const;
    /// Whether the ids are the dense index of a box: id = (ix - loX()) * extentY() + (iy - loY()).
    bool denseIds() const { return dense_; }
    std::int64_t loX() const { return lo_[0]; }
    std::int64_t loY() const { return lo_[1]; }
    std::int64_t extentY() const { return extY_; }
    /// [m] The z of each point of the last build()'s `indices`, in their order (gathered with
    /// their x and y: Phase I's grid takes them from here instead of the cloud).
    const std::vector<float>& z() const { return z_; }

private:
    std::int64_t findSparse(std::int32_t ix, std::int32_t iy) const;

    bool dense_ = true;
    std::int32_t lo_[2] = {0, 0};
    std::int64_t extY_ = 1;
    std::uint32_t size_ = 0;
    std::vector<std::uint64_t> keys_;    // sparse ids: sorted keys of the occupied columns
    std::vector<std::int32_t> coords_;   // ix of every input position, then iy of every one (scratch)
    std::vector<float> xy_;              // [m] x of every input position, then y of every one (scratch)
    std::vector<float> z_;               // [m] z of every input position (z())
};

/// A 3-D grid of occupied cells, rebuilt per scan. Cells come sorted by (ix, iy, iz), so the cells
/// of one vertical column are adjacent and ordered bottom to top. Reuses its memory across builds.
class Grid {
public:
    /// Bins the points `indices` of `cloud` into cells of size sx * sy * sz metres; the vertical
    /// grid starts at `originZ` (cell iz spans [originZ + iz sz, originZ + (iz + 1) sz)).
    void build(const PointCloudView& cloud, const std::vector<std::uint32_t>& indices, double sx,
               double sy, double sz, double originZ = 0.0);

    /// The same cells as build() (same order, same order() within each cell), from the points'
    /// columns numbered by `columns` (`columnOf[k]`: the column id of indices[k]) and sx, sy the
    /// columns' sizes: points are binned per column and only their z cell is computed here. Also
    /// fills points(), columnCells() and cellColumns().
    /// `pointsOfIndices`, if given, holds the points of `indices` in their order (a copy the caller
    /// has at hand, read sequentially instead of the cloud); `zOfIndices`, if given, their z
    /// coordinates [m] in their order (as ColumnIndex::z() keeps them).
    void build(const PointCloudView& cloud, const std::vector<std::uint32_t>& indices, const ColumnIndex& columns,
               const std::uint32_t* columnOf, double sz, double originZ = 0.0,
               const Eigen::Vector3f* pointsOfIndices = nullptr, const float* zOfIndices = nullptr);

    const std::vector<GridCell>& cells() const { return cells_; }
    /// [m] The points (x, y, z) aligned with order() (filled by the ColumnIndex form of build()).
    const std::vector<Eigen::Vector3f>& points() const { return points_; }
    /// The cells of column id c are cells()[columnCells()[c] .. columnCells()[c + 1]) (filled by
    /// the ColumnIndex form of build(); size ColumnIndex::size() + 1).
    const std::vector<std::uint32_t>& columnCells() const { return columnCells_; }
    /// The column id of each cell (filled by the ColumnIndex form of build()).
    const std::vector<std::uint32_t>& cellColumns() const { return cellColumns_; }
    /// Point indices (into the cloud) grouped by cell: cell c owns order()[c.begin .. c.end).
    const std::vector<std::uint32_t>& order() const { return order_; }

private:
    // The ColumnIndex form's single counting sort by (column, z cell) where the keys are few;
    // false: not done.
    void zCells(const PointCloudView& cloud, const std::vector<std::uint32_t>& indices,
                const Eigen::Vector3f* pointsOfIndices, const float* zOfIndices, double sz, double originZ,
                std::vector<std::int32_t>& out);
    bool buildByColumnAndZ(const PointCloudView& cloud, const std::vector<std::uint32_t>& indices,
                           const ColumnIndex& columns, const std::uint32_t* columnOf, double sz, double originZ,
                           const Eigen::Vector3f* pointsOfIndices, const float* zOfIndices);

    std::vector<GridCell> cells_;
    std::vector<std::uint32_t> order_;
    std::vector<std::int32_t> coords_;  // ix, iy, iz per input index
    std::vector<std::uint32_t> keys_, counts_;
    std::vector<std::uint32_t> zCounts_;  // one column's counting sort by z cell (small: keys_ keeps its size)
    std::vector<std::uint64_t> sortKeys_;
    std::vector<Eigen::Vector3f> points_, byColumnPoints_;
    std::vector<std::uint32_t> columnCells_, cellColumns_, byColumn_;
    std::vector<std::int32_t> iz_, sortedIz_, izIn_;
    std::vector<float> zs_;
};

}  // namespace gseg
