#pragma once
/// \file top_down_grid.hpp
/// The top-down grid of a traversability map: one class (traversable / obstacle / unknown) per
/// voxel column, in the map's world frame (metres, z up; cells index world x and y).

#include <gseg/map/column_class.hpp>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace gseg::map {

/// Top-down grid: one cell per voxel column, cell (ix, iy) covering world x in
/// [ix * cell, (ix + 1) * cell) and y likewise. Sparse: only cells with data are stored, in tiles
/// of 64 x 64 cells, so memory follows the mapped area, not the extent of the path.
class TopDownGrid {
public:
    explicit TopDownGrid(double cell = 0.2) : cell_(cell) {}
    double cell() const { return cell_; }  ///< [m] cell edge

    std::int64_t cellIndex(double v) const { return std::int64_t(std::floor(v / cell_)); }
    /// Class at world (x, y); Unknown where nothing was seen.
    ColumnClass at(double x, double y) const { return atCell(cellIndex(x), cellIndex(y)); }
    ColumnClass atCell(std::int64_t ix, std::int64_t iy) const;
    void set(std::int64_t ix, std::int64_t iy, ColumnClass c);

    bool empty() const { return !any_; }  ///< no cell was ever set to a known class
    std::size_t count(ColumnClass c) const;  ///< cells of class c (Traversable or Obstacle)
    /// Cell index ranges of every cell ever set to a known class, inclusive (meaningless when empty()).
    std::int64_t minX() const { return lo_[0]; }
    std::int64_t maxX() const { return hi_[0]; }
    std::int64_t minY() const { return lo_[1]; }
    std::int64_t maxY() const { return hi_[1]; }

    /// Calls f(ix, iy, class) for every cell with data (tile by tile).
    template <class F>
    void forEachCell(F&& f) const {
        for (const auto& [key, tile] : tiles_)
            for (int j = 0; j < kTile; ++j)
                for (int i = 0; i < kTile; ++i) {
                    const ColumnClass c = tile[std::size_t(j * kTile + i)];
                    if (c != ColumnClass::Unknown) f(tileX(key) * kTile + i, tileY(key) * kTile + j, c);
                }
    }

    static constexpr int kTile = 64;  ///< [cells] tile edge

private:
    double cell_;
    std::unordered_map<std::uint64_t, std::vector<ColumnClass>> tiles_;
    std::int64_t lo_[2] = {0, 0}, hi_[2] = {0, 0};
    bool any_ = false;
    std::size_t counts_[3] = {0, 0, 0};  ///< per class; [Unknown] unused
    static std::uint64_t tileKey(std::int64_t tx, std::int64_t ty);
    static std::int64_t tileX(std::uint64_t key);
    static std::int64_t tileY(std::uint64_t key);
};

}  // namespace gseg::map
