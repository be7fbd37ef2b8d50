#pragma once
/// \file layer_tiles.hpp
/// The 2.5D layers of a map held sparse (#35): named float layers over the map frame in tiles of
/// kTile x kTile cells, a tile allocated only where a cell of it was written. Memory follows the
/// ground seen, not the box around it: two scans kilometres apart cost two patches of tiles.
///
/// Frame: cell (ix, iy) covers map-frame x in [ix * resolution, (ix + 1) * resolution) and y
/// likewise (the cell index of x is floor(x / resolution), negative left of the origin); tile
/// (tx, ty) holds the cells tx * kTile <= ix < (tx + 1) * kTile and likewise in y. A cell of no
/// tile reads NaN (unknown). window() and dense() give a LayerGrid (gseg/map/layer_grid.hpp) of a
/// bounded box for the encoders; overview() a coarser LayerTiles for pictures and GeoTIFF overviews.

#include <gseg/map/layer_grid.hpp>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

namespace gseg::map {

class LayerTiles {
public:
    static constexpr int kTile = 64;  ///< [cells] tile edge
    static constexpr int kTileShift = 6;  ///< kTile = 1 << kTileShift (floorDiv by a shift, two's complement)
    static constexpr std::int64_t kTileMask = kTile - 1;
    /// [bytes] one tile of one layer
    static constexpr std::size_t kTileBytes = std::size_t(kTile) * kTile * sizeof(float);

    /// A layer's name, unit and one-line meaning (as LayerGrid::Layer, without values).
    struct Info {
        std::string name, unit, meaning;
    };

    LayerTiles() = default;
    /// Empty tiles at cells of edge `resolution` [m] with these layers. Throws
    /// std::invalid_argument on a non-positive or non-finite resolution.
    LayerTiles(double resolution, std::vector<Info> layers);

    double resolution() const { return resolution_; }
    const std::vector<Info>& layers() const { return layers_; }
    /// The index of the layer of that name; throws std::out_of_range naming it if absent.
    std::size_t layerIndex(const std::string& name) const;

    /// The value of cell (ix, iy) of layer `layer`; NaN where no tile holds it.
    float get(std::size_t layer, std::int64_t ix, std::int64_t iy) const;
    /// The value of cell (ix, iy) of layer `layer`, its tile allocated (every layer NaN) if needed.
    float& at(std::size_t layer, std::int64_t ix, std::int64_t iy);
    /// Allocates the tile of cell (ix, iy) (every layer NaN) if it has none.
    void touch(std::int64_t ix, std::int64_t iy);
    bool hasTile(std::int64_t tx, std::int64_t ty) const { return tiles_.count(key(tx, ty)) > 0; }

    /// Fast access to one layer: remembers the last tile it used (single thread).
    class Cursor {
    public:
        Cursor(LayerTiles& t, std::size_t layer) : t_(&t), layer_(layer) {}
        /// The cell's value, NaN where its tile is not allocated. Inline: the layers' 3 x 3 and disc
        /// loops read a neighbour's value this way, mostly within the tile read last.
        float get(std::int64_t ix, std::int64_t iy) {
            const std::int64_t tx = ix >> kTileShift, ty = iy >> kTileShift;
            const float* v = tx == tx_ && ty == ty_ ? values_ : tile(tx, ty, false);
            return v ? v[std::size_t(((iy & kTileMask) << kTileShift) | (ix & kTileMask))] : std::numeric_limits<float>::quiet_NaN();
        }
        float& at(std::int64_t ix, std::int64_t iy);

    private:
        float* tile(std::int64_t tx, std::int64_t ty, bool allocate);
        LayerTiles* t_;
        std::size_t layer_;
        std::int64_t tx_ = std::numeric_limits<std::int64_t>::min(), ty_ = 0;
        float* values_ = nullptr;  ///< the layer's values of tile (tx_, ty_), nullptr: none
    };

    /// The allocated tiles (tx, ty), sorted by ty then tx (the same order for the same map).
    std::vector<std::pair<std::int64_t, std::int64_t>> tileList() const;
    std::size_t tiles() const { return tiles_.size(); }
    /// [bytes] the tiles' values
    double bytes() const { return double(tiles_.size()) * double(layers_.size()) * double(kTileBytes); }
    /// Keeps the first `n` layers, dropping the rest (scratch layers of a computation) and their memory.
    void keepLayers(std::size_t n);

    /// The box of cells the map covers (inclusive cell indices), as set by setBox(); a map of no
    /// cell has lo > hi.
    void setBox(std::int64_t loX, std::int64_t loY, std::int64_t hiX, std::int64_t hiY) { lo_[0] = loX, lo_[1] = loY, hi_[0] = hiX, hi_[1] = hiY; }
    std::int64_t minX() const { return lo_[0]; }
    std::int64_t minY() const { return lo_[1]; }
    std::int64_t maxX() const { return hi_[0]; }
    std::int64_t maxY() const { return hi_[1]; }
    std::int64_t boxWidth() const { return hi_[0] < lo_[0] ? 0 : hi_[0] - lo_[0] + 1; }   ///< [cells]
    std::int64_t boxHeight() const { return hi_[1] < lo_[1] ? 0 : hi_[1] - lo_[1] + 1; }  ///< [cells]

    /// A dense LayerGrid of `width` x `height` cells from cell (x0, y0): every layer, NaN where no
    /// tile is. Throws std::invalid_argument on a non-positive size.
    LayerGrid window(std::int64_t x0, std::int64_t y0, int width, int height) const;
    /// window() over the box. Throws std::length_error if the box is wider or higher than
    /// `maxSide` cells (a dense grid of it would not fit: use tiles, window() or overview()).
    LayerGrid dense(std::int64_t maxSide = 16384) const;

    /// The layers at cells of `factor` x `factor` cells (factor >= 1): cell (ox, oy) of the
    /// overview holds cells ox * factor .. ox * factor + factor - 1 (and likewise in y). A layer
    /// named `class` or `cost` takes the largest value of its cells (the most blocking), every
    /// other the mean of its finite values (+inf or -inf where all of them are infinite alike; NaN
    /// where none is known). The box is scaled likewise (floor division). Throws
    /// std::invalid_argument on factor < 1.
    LayerTiles overview(int factor) const;

    /// floor(a / b) for b > 0 (a negative a rounds down).
    static std::int64_t floorDiv(std::int64_t a, std::int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

private:
    static std::uint64_t key(std::int64_t tx, std::int64_t ty);
    static std::int64_t keyX(std::uint64_t k);
    static std::int64_t keyY(std::uint64_t k);
    std::vector<float>& tileOf(std::int64_t tx, std::int64_t ty);

    double resolution_ = 0.2;
    std::vector<Info> layers_;
    std::unordered_map<std::uint64_t, std::vector<float>> tiles_;  ///< per tile: every layer's kTile * kTile values, layer after layer
    std::int64_t lo_[2] = {0, 0}, hi_[2] = {-1, -1};
};

}  // namespace gseg::map
