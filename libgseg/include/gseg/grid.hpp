#pragma once
/// \file grid.hpp
/// Binning of points into axis-aligned cells, indexed with floor (never truncation).

#include <gseg/point_cloud.hpp>

#include <cmath>
#include <cstdint>
#include <vector>

namespace gseg {

/// Integer index of a cell along one axis: floor((v - origin) / size), clamped to +-2^30 so that absurdly
/// far points land in a far cell of their own instead of overflowing.
inline std::int32_t cellCoord(float v, double size, double origin = 0.0) {
    const double c = std::floor((static_cast<double>(v) - origin) / size);
    constexpr double lim = 1073741824.0;  // 2^30
    return static_cast<std::int32_t>(c < -lim ? -lim : (c > lim ? lim : c));
}

/// One occupied cell: its index and the range [begin, end) of its points in Grid::order().
struct GridCell {
    std::int32_t ix = 0, iy = 0, iz = 0;
    std::uint32_t begin = 0, end = 0;
    std::uint32_t size() const { return end - begin; }
};

/// A 3-D grid of occupied cells, rebuilt per scan. Cells come sorted by (ix, iy, iz), so the cells
/// of one vertical column are adjacent and ordered bottom to top. Reuses its memory across builds.
class Grid {
public:
    /// Bins the points `indices` of `cloud` into cells of size sx * sy * sz metres; the vertical
    /// grid starts at `originZ` (cell iz spans [originZ + iz sz, originZ + (iz + 1) sz)).
    void build(const PointCloudView& cloud, const std::vector<std::uint32_t>& indices, double sx,
               double sy, double sz, double originZ = 0.0);

    const std::vector<GridCell>& cells() const { return cells_; }
    /// Point indices (into the cloud) grouped by cell: cell c owns order()[c.begin .. c.end).
    const std::vector<std::uint32_t>& order() const { return order_; }

private:
    std::vector<GridCell> cells_;
    std::vector<std::uint32_t> order_;
    std::vector<std::int32_t> coords_;  // ix, iy, iz per input index
    std::vector<std::uint32_t> keys_, counts_;
    std::vector<std::uint64_t> sortKeys_;
};

}  // namespace gseg
