// The 2.5D layers in sparse tiles of 64 x 64 cells (#35).
#include <gseg/map/layer_tiles.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace gseg::map {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr std::size_t kCells = std::size_t(LayerTiles::kTile) * LayerTiles::kTile;
static_assert(LayerTiles::kTile == 1 << LayerTiles::kTileShift, "Cursor::get() divides by a shift");
static_assert((-1 >> 1) == -1, "Cursor::get() needs an arithmetic right shift (floor division)");

/// The index of cell (ix, iy) within its tile.
std::size_t inTile(std::int64_t ix, std::int64_t iy) {
    const std::int64_t i = ix - LayerTiles::floorDiv(ix, LayerTiles::kTile) * LayerTiles::kTile;
    const std::int64_t j = iy - LayerTiles::floorDiv(iy, LayerTiles::kTile) * LayerTiles::kTile;
    return std::size_t(j * LayerTiles::kTile + i);
}

}  // namespace

LayerTiles::LayerTiles(double resolution, std::vector<Info> layers) : resolution_(resolution), layers_(std::move(layers)) {
    if (!(std::isfinite(resolution) && resolution > 0)) throw std::invalid_argument("layer tiles: resolution must be positive");
}

std::uint64_t LayerTiles::key(std::int64_t tx, std::int64_t ty) {
    return (std::uint64_t(std::uint32_t(std::int32_t(tx))) << 32) | std::uint64_t(std::uint32_t(std::int32_t(ty)));
}
std::int64_t LayerTiles::keyX(std::uint64_t k) { return std::int32_t(std::uint32_t(k >> 32)); }
std::int64_t LayerTiles::keyY(std::uint64_t k) { return std::int32_t(std::uint32_t(k)); }

std::size_t LayerTiles::layerIndex(const std::string& name) const {
    for (std::size_t i = 0; i < layers_.size(); ++i)
        if (layers_[i].name == name) return i;
    throw std::out_of_range("layer tiles: no layer '" + name + "'");
}

std::vector<float>& LayerTiles::tileOf(std::int64_t tx, std::int64_t ty) {
    std::vector<float>& t = tiles_[key(tx, ty)];
    if (t.empty()) t.assign(layers_.size() * kCells, kNaN);
    return t;
}

float LayerTiles::get(std::size_t layer, std::int64_t ix, std::int64_t iy) const {
    const auto it = tiles_.find(key(floorDiv(ix, kTile), floorDiv(iy, kTile)));
    return it == tiles_.end() ? kNaN : it->second[layer * kCells + inTile(ix, iy)];
}

float& LayerTiles::at(std::size_t layer, std::int64_t ix, std::int64_t iy) {
    return tileOf(floorDiv(ix, kTile), floorDiv(iy, kTile))[layer * kCells + inTile(ix, iy)];
}

void LayerTiles::touch(std::int64_t ix, std::int64_t iy) { tileOf(floorDiv(ix, kTile), floorDiv(iy, kTile)); }

float* LayerTiles::Cursor::tile(std::int64_t tx, std::int64_t ty, bool allocate) {
    if (tx != tx_ || ty != ty_ || (!values_ && allocate)) {
        tx_ = tx, ty_ = ty, values_ = nullptr;
        if (allocate) {
            values_ = t_->tileOf(tx, ty).data() + layer_ * kCells;
        } else if (const auto it = t_->tiles_.find(key(tx, ty)); it != t_->tiles_.end()) {
            values_ = it->second.data() + layer_ * kCells;
        }
    }
    return values_;
}

float& LayerTiles::Cursor::at(std::int64_t ix, std::int64_t iy) {
    return tile(floorDiv(ix, kTile), floorDiv(iy, kTile), true)[inTile(ix, iy)];
}

std::vector<std::pair<std::int64_t, std::int64_t>> LayerTiles::tileList() const {
    std::vector<std::pair<std::int64_t, std::int64_t>> list;
    list.reserve(tiles_.size());
    for (const auto& kv : tiles_) list.emplace_back(keyY(kv.first), keyX(kv.first));
    std::sort(list.begin(), list.end());
    for (auto& p : list) std::swap(p.first, p.second);
    return list;
}

void LayerTiles::keepLayers(std::size_t n) {
    if (n >= layers_.size()) return;
    layers_.resize(n);
    for (auto& kv : tiles_) {
        kv.second.resize(n * kCells);
        kv.second.shrink_to_fit();
    }
}

LayerGrid LayerTiles::window(std::int64_t x0, std::int64_t y0, int width, int height) const {
    LayerGrid g(width, height, resolution_, double(x0) * resolution_, double(y0) * resolution_);
    std::vector<std::vector<float>*> values;
    for (const Info& l : layers_) values.push_back(&g.add(l.name, l.unit, l.meaning).values);
    // Tile by tile over the window: only allocated tiles are copied.
    const std::int64_t tx0 = floorDiv(x0, kTile), tx1 = floorDiv(x0 + width - 1, kTile);
    const std::int64_t ty0 = floorDiv(y0, kTile), ty1 = floorDiv(y0 + height - 1, kTile);
    const bool few = double(tx1 - tx0 + 1) * double(ty1 - ty0 + 1) <= double(tiles_.size());
    auto copy = [&](std::int64_t tx, std::int64_t ty, const std::vector<float>& t) {
        const std::int64_t xa = std::max(x0, tx * kTile), xb = std::min(x0 + width, (tx + 1) * kTile);
        const std::int64_t ya = std::max(y0, ty * kTile), yb = std::min(y0 + height, (ty + 1) * kTile);
        for (std::size_t l = 0; l < layers_.size(); ++l)
            for (std::int64_t iy = ya; iy < yb; ++iy)
                for (std::int64_t ix = xa; ix < xb; ++ix)
                    (*values[l])[g.index(int(ix - x0), int(iy - y0))] = t[l * kCells + inTile(ix, iy)];
    };
    if (few) {
        for (std::int64_t ty = ty0; ty <= ty1; ++ty)
            for (std::int64_t tx = tx0; tx <= tx1; ++tx)
                if (const auto it = tiles_.find(key(tx, ty)); it != tiles_.end()) copy(tx, ty, it->second);
    } else {
        for (const auto& kv : tiles_) {
            const std::int64_t tx = keyX(kv.first), ty = keyY(kv.first);
            if (tx >= tx0 && tx <= tx1 && ty >= ty0 && ty <= ty1) copy(tx, ty, kv.second);
        }
    }
    return g;
}

LayerGrid LayerTiles::dense(std::int64_t maxSide) const {
    if (boxWidth() > maxSide || boxHeight() > maxSide)
        throw std::length_error("layer tiles: the map's box of " + std::to_string(boxWidth()) + " x " + std::to_string(boxHeight()) +
                                " cells is too big for one dense grid (at most " + std::to_string(maxSide) + " a side)");
    return window(lo_[0], lo_[1], int(boxWidth()), int(boxHeight()));
}

LayerTiles LayerTiles::overview(int factor) const {
    if (factor < 1) throw std::invalid_argument("layer tiles: an overview needs a factor >= 1");
    LayerTiles o(resolution_ * factor, layers_);
    if (boxWidth() > 0 && boxHeight() > 0)
        o.setBox(floorDiv(lo_[0], factor), floorDiv(lo_[1], factor), floorDiv(hi_[0], factor), floorDiv(hi_[1], factor));
    const std::size_t n = layers_.size();
    std::vector<bool> largest(n);
    for (std::size_t l = 0; l < n; ++l) largest[l] = layers_[l].name == "class" || layers_[l].name == "cost";
    // Sums and counts per overview cell for the mean layers (scratch tiles: 2 per layer).
    std::vector<Info> scratchInfo(2 * n);
    LayerTiles sums(o.resolution_, scratchInfo);
    for (const auto& [k, t] : tiles_) {
        const std::int64_t tx = keyX(k), ty = keyY(k);
        for (int j = 0; j < kTile; ++j)
            for (int i = 0; i < kTile; ++i) {
                const std::size_t c = std::size_t(j * kTile + i);
                const std::int64_t ox = floorDiv(tx * kTile + i, factor), oy = floorDiv(ty * kTile + j, factor);
                for (std::size_t l = 0; l < n; ++l) {
                    const float v = t[l * kCells + c];
                    if (std::isnan(v)) continue;
                    float& out = o.at(l, ox, oy);
                    if (largest[l]) {
                        if (std::isnan(out) || v > out) out = v;
                    } else if (std::isinf(v)) {  // all infinite alike: that infinity; else the mean of the finite ones
                        if (std::isnan(out)) out = v;
                        else if (std::isinf(out) && out != v) out = 0;  // +inf and -inf: no limit either way, mean of finite
                    } else {
                        sums.at(2 * l, ox, oy) = (std::isnan(sums.get(2 * l, ox, oy)) ? 0.f : sums.get(2 * l, ox, oy)) + v;
                        float& count = sums.at(2 * l + 1, ox, oy);
                        count = std::isnan(count) ? 1.f : count + 1.f;
                    }
                }
            }
    }
    for (const auto& [k, t] : o.tiles_) {
        (void)t;
        const std::int64_t tx = keyX(k), ty = keyY(k);
        for (int j = 0; j < kTile; ++j)
            for (int i = 0; i < kTile; ++i) {
                const std::int64_t ox = tx * kTile + i, oy = ty * kTile + j;
                for (std::size_t l = 0; l < n; ++l) {
                    if (largest[l]) continue;
                    const float count = sums.get(2 * l + 1, ox, oy);
                    if (std::isnan(count)) continue;
                    o.at(l, ox, oy) = float(double(sums.get(2 * l, ox, oy)) / double(count));
                }
            }
    }
    return o;
}

}  // namespace gseg::map
