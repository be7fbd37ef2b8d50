#include <gseg/grid.hpp>

#include <algorithm>
#include <limits>

namespace gseg {

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

}  // namespace gseg
