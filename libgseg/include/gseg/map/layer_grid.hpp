#pragma once
/// \file layer_grid.hpp
/// A 2D grid of named float layers over the map frame (grid_map's model: `elevation`, `slope`,
/// ... per cell, NaN where unknown): the 2.5D layers of a traversability map, as computed by the
/// map layer and written by its encoders (GeoTIFF, pictures, the costmap).
///
/// Frame: cell (cx, cy) covers map-frame x in [originX + cx * resolution, originX + (cx + 1) *
/// resolution) and y likewise; cy = 0 is the row of smallest y (a north-up image flips it).

#include <cmath>
#include <cstddef>
#include <deque>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace gseg::map {

class LayerGrid {
public:
    /// One named layer: width * height values, index(cx, cy); NaN = unknown.
    struct Layer {
        std::string name;     ///< e.g. "elevation" (a GeoTIFF band's description)
        std::string unit;     ///< e.g. "m", "deg", "-"
        std::string meaning;  ///< one line, for legends and metadata
        std::vector<float> values;
    };

    LayerGrid() = default;
    /// An empty grid of width x height cells (no layers). Throws std::invalid_argument on a
    /// non-positive size or resolution, or a non-finite origin.
    LayerGrid(int width, int height, double resolution, double originX, double originY)
        : resolution_(resolution), originX_(originX), originY_(originY), width_(width), height_(height) {
        if (width <= 0 || height <= 0) throw std::invalid_argument("layer grid: no cells");
        if (!(std::isfinite(resolution) && resolution > 0)) throw std::invalid_argument("layer grid: resolution must be positive");
        if (!std::isfinite(originX) || !std::isfinite(originY)) throw std::invalid_argument("layer grid: origin must be finite");
    }

    double resolution() const { return resolution_; }  ///< [m] cell edge
    double originX() const { return originX_; }        ///< [m] x of the left edge of column 0
    double originY() const { return originY_; }        ///< [m] y of the bottom edge of row 0
    int width() const { return width_; }               ///< [cells] along x
    int height() const { return height_; }             ///< [cells] along y
    std::size_t cells() const { return std::size_t(width_) * std::size_t(height_); }
    bool inside(long long cx, long long cy) const { return cx >= 0 && cy >= 0 && cx < width_ && cy < height_; }
    std::size_t index(int cx, int cy) const { return std::size_t(cy) * std::size_t(width_) + std::size_t(cx); }
    /// The cell holding map-frame x (floor; may be outside the grid).
    long long cellX(double x) const { return (long long)std::floor((x - originX_) / resolution_); }
    long long cellY(double y) const { return (long long)std::floor((y - originY_) / resolution_); }
    double centreX(int cx) const { return originX_ + (cx + 0.5) * resolution_; }  ///< [m]
    double centreY(int cy) const { return originY_ + (cy + 0.5) * resolution_; }  ///< [m]

    /// Adds a layer filled with NaN (or returns the existing one of that name, unchanged). The
    /// reference (and those to the other layers) stays valid while more layers are added.
    Layer& add(const std::string& name, const std::string& unit, const std::string& meaning) {
        if (Layer* l = find(name)) return *l;
        layers_.push_back({name, unit, meaning, std::vector<float>(cells(), std::numeric_limits<float>::quiet_NaN())});
        return layers_.back();
    }
    /// The layer of that name, or nullptr.
    Layer* find(const std::string& name) {
        for (auto& l : layers_)
            if (l.name == name) return &l;
        return nullptr;
    }
    const Layer* find(const std::string& name) const { return const_cast<LayerGrid*>(this)->find(name); }
    /// The layer of that name; throws std::out_of_range naming it if absent.
    const Layer& layer(const std::string& name) const {
        if (const Layer* l = find(name)) return *l;
        throw std::out_of_range("layer grid: no layer '" + name + "'");
    }
    const std::deque<Layer>& layers() const { return layers_; }

private:
    double resolution_ = 0.2;
    double originX_ = 0, originY_ = 0;
    int width_ = 0, height_ = 0;
    std::deque<Layer> layers_;  ///< a deque: adding a layer moves none (references stay valid)
};

}  // namespace gseg::map
