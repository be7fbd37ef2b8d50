// The top-down grid (sparse tiles), its picture layout and the PNG.
#include <gseg/map/output_files.hpp>
#include <gseg/map/traversability_map.hpp>

#include "png.hpp"
#include "voxel_keys.hpp"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

namespace gseg::map {
namespace {

std::int64_t floorDiv(std::int64_t a, std::int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

constexpr std::uint8_t kPathPixel = 3, kStartPixel = 4;  // drawn over the cell classes

Rgb pixelColour(std::uint8_t v) {
    if (v == kPathPixel) return {40, 120, 255};
    if (v == kStartPixel) return {255, 255, 255};
    return colourOf(CellClass(v));
}

/// Pixel classes of the picture (the most blocking class of the cells a pixel covers), path on top.
std::vector<std::uint8_t> renderPixels(const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& path, const PictureLayout& l) {
    std::vector<std::uint8_t> px(std::size_t(l.width) * std::size_t(l.height), std::uint8_t(CellClass::Unknown));
    grid.forEachCell([&](std::int64_t ix, std::int64_t iy, CellClass c) {
        const std::size_t col = std::size_t((ix - l.leftCell) / l.cellsPerPixel), row = std::size_t((l.topCell - iy) / l.cellsPerPixel);
        std::uint8_t& p = px[row * std::size_t(l.width) + col];
        p = std::max(p, std::uint8_t(c));  // Obstacle > Traversable > Unknown
    });
    auto put = [&](int c, int r, std::uint8_t v) {
        if (c >= 0 && r >= 0 && c < l.width && r < l.height) px[std::size_t(r) * std::size_t(l.width) + std::size_t(c)] = v;
    };
    int pc = 0, pr = 0;
    bool havePrevious = false;
    for (const auto& p : path) {
        int c = 0, r = 0;
        if (!l.toPixel(p.x(), p.y(), c, r)) continue;
        if (havePrevious) {  // Bresenham line from the previous position
            const int dc = std::abs(c - pc), dr = -std::abs(r - pr), sc = pc < c ? 1 : -1, sr = pr < r ? 1 : -1;
            for (int err = dc + dr, x = pc, y = pr;;) {
                put(x, y, kPathPixel);
                if (x == c && y == r) break;
                const int e2 = 2 * err;
                if (e2 >= dr) err += dr, x += sc;
                if (e2 <= dc) err += dc, y += sr;
            }
        }
        pc = c, pr = r, havePrevious = true;
    }
    int c = 0, r = 0;
    if (!path.empty() && l.toPixel(path[0].x(), path[0].y(), c, r))
        for (int dr = -1; dr <= 1; ++dr)
            for (int dc = -1; dc <= 1; ++dc) put(c + dc, r + dr, kStartPixel);
    return px;
}

}  // namespace

std::uint64_t TopDownGrid::tileKey(std::int64_t tx, std::int64_t ty) { return detail::pairKey(tx, ty); }
std::int64_t TopDownGrid::tileX(std::uint64_t key) { return detail::splitPairKey(key).first; }
std::int64_t TopDownGrid::tileY(std::uint64_t key) { return detail::splitPairKey(key).second; }

CellClass TopDownGrid::atCell(std::int64_t ix, std::int64_t iy) const {
    const auto it = tiles_.find(tileKey(floorDiv(ix, kTile), floorDiv(iy, kTile)));
    if (it == tiles_.end()) return CellClass::Unknown;
    const std::int64_t i = ix - floorDiv(ix, kTile) * kTile, j = iy - floorDiv(iy, kTile) * kTile;
    return it->second[std::size_t(j * kTile + i)];
}

void TopDownGrid::set(std::int64_t ix, std::int64_t iy, CellClass c) {
    const std::int64_t tx = floorDiv(ix, kTile), ty = floorDiv(iy, kTile);
    auto& tile = tiles_[tileKey(tx, ty)];
    if (tile.empty()) tile.assign(std::size_t(kTile * kTile), CellClass::Unknown);
    CellClass& cell = tile[std::size_t((iy - ty * kTile) * kTile + (ix - tx * kTile))];
    if (cell != CellClass::Unknown) --counts_[std::size_t(cell)];
    if (c != CellClass::Unknown) ++counts_[std::size_t(c)];
    cell = c;
    if (c == CellClass::Unknown) return;
    lo_[0] = any_ ? std::min(lo_[0], ix) : ix, hi_[0] = any_ ? std::max(hi_[0], ix) : ix;
    lo_[1] = any_ ? std::min(lo_[1], iy) : iy, hi_[1] = any_ ? std::max(hi_[1], iy) : iy;
    any_ = true;
}

std::size_t TopDownGrid::count(CellClass c) const { return counts_[std::size_t(c)]; }

bool PictureLayout::toPixel(double x, double y, int& col, int& row) const {
    const std::int64_t dx = std::int64_t(std::floor(x / cell)) - leftCell, dy = topCell - std::int64_t(std::floor(y / cell));
    if (dx < 0 || dy < 0 || dx / cellsPerPixel >= width || dy / cellsPerPixel >= height) return false;
    col = int(dx / cellsPerPixel), row = int(dy / cellsPerPixel);
    return true;
}

PictureLayout pictureLayout(const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& path, int maxSide) {
    PictureLayout l;
    l.cell = grid.cell();
    bool any = !grid.empty();
    std::int64_t lo[2] = {grid.minX(), grid.minY()}, hi[2] = {grid.maxX(), grid.maxY()};
    for (const auto& p : path) {
        if (!p.allFinite()) continue;
        const std::int64_t c[2] = {grid.cellIndex(p.x()), grid.cellIndex(p.y())};
        for (int a = 0; a < 2; ++a) lo[a] = any ? std::min(lo[a], c[a]) : c[a], hi[a] = any ? std::max(hi[a], c[a]) : c[a];
        any = true;
    }
    if (!any) return l;
    const int margin = 5;  // cells around the content
    l.leftCell = lo[0] - margin;
    l.topCell = hi[1] + margin;
    l.cellsWide = std::uint64_t(hi[0] - lo[0] + 1 + 2 * margin);
    l.cellsHigh = std::uint64_t(hi[1] - lo[1] + 1 + 2 * margin);
    const std::uint64_t side = std::max(l.cellsWide, l.cellsHigh);
    l.cellsPerPixel = int((side + std::uint64_t(maxSide) - 1) / std::uint64_t(maxSide));
    const auto s = std::uint64_t(l.cellsPerPixel);
    l.width = int((l.cellsWide + s - 1) / s);
    l.height = int((l.cellsHigh + s - 1) / s);
    return l;
}

std::string encodeTopDownPng(const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath) {
    const PictureLayout l = pictureLayout(grid, drivenPath);
    if (l.width <= 0) throw std::runtime_error("empty map: no picture to draw");
    const std::vector<std::uint8_t> px = renderPixels(grid, drivenPath, l);
    return detail::encodePngRgb(l.width, l.height, [&](int row, std::uint8_t* rgb) {
        const std::uint8_t* in = &px[std::size_t(row) * std::size_t(l.width)];
        for (int c = 0; c < l.width; ++c, rgb += 3) {
            const Rgb v = pixelColour(in[c]);
            rgb[0] = v.r, rgb[1] = v.g, rgb[2] = v.b;
        }
    });
}

void writeTopDownPng(const std::string& path, const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath) {
    std::string png;
    try {
        png = encodeTopDownPng(grid, drivenPath);
    } catch (const std::exception& e) {
        throw std::runtime_error(path + ": " + e.what());
    }
    AtomicFiles file({path});
    writeFileChecked(file.temporary(0), png);
    file.commit();
}

}  // namespace gseg::map
