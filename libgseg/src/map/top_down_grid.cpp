// The top-down grid: sparse tiles of 64 x 64 cells.
#include <gseg/map/top_down_grid.hpp>

#include "voxel_keys.hpp"

#include <algorithm>

namespace gseg::map {
namespace {

std::int64_t floorDiv(std::int64_t a, std::int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

}  // namespace

std::uint64_t TopDownGrid::tileKey(std::int64_t tx, std::int64_t ty) { return detail::pairKey(tx, ty); }
std::int64_t TopDownGrid::tileX(std::uint64_t key) { return detail::splitPairKey(key).first; }
std::int64_t TopDownGrid::tileY(std::uint64_t key) { return detail::splitPairKey(key).second; }

ColumnClass TopDownGrid::atCell(std::int64_t ix, std::int64_t iy) const {
    const auto it = tiles_.find(tileKey(floorDiv(ix, kTile), floorDiv(iy, kTile)));
    if (it == tiles_.end()) return ColumnClass::Unknown;
    const std::int64_t i = ix - floorDiv(ix, kTile) * kTile, j = iy - floorDiv(iy, kTile) * kTile;
    return it->second[std::size_t(j * kTile + i)];
}

void TopDownGrid::set(std::int64_t ix, std::int64_t iy, ColumnClass c) {
    const std::int64_t tx = floorDiv(ix, kTile), ty = floorDiv(iy, kTile);
    auto& tile = tiles_[tileKey(tx, ty)];
    if (tile.empty()) tile.assign(std::size_t(kTile * kTile), ColumnClass::Unknown);
    ColumnClass& cell = tile[std::size_t((iy - ty * kTile) * kTile + (ix - tx * kTile))];
    if (cell != ColumnClass::Unknown) --counts_[std::size_t(cell)];
    if (c != ColumnClass::Unknown) ++counts_[std::size_t(c)];
    cell = c;
    if (c == ColumnClass::Unknown) return;
    lo_[0] = any_ ? std::min(lo_[0], ix) : ix, hi_[0] = any_ ? std::max(hi_[0], ix) : ix;
    lo_[1] = any_ ? std::min(lo_[1], iy) : iy, hi_[1] = any_ ? std::max(hi_[1], iy) : iy;
    any_ = true;
}

std::size_t TopDownGrid::count(ColumnClass c) const { return counts_[std::size_t(c)]; }

}  // namespace gseg::map
