// The top-down picture: its layout and the PNG (drawn with the shared picture conventions of
// gseg/mrpt/picture.hpp: x up, y to the left, as the scan pictures).
#include <gseg/map/top_down_picture.hpp>

#include <gseg/io/atomic_file.hpp>
#include <gseg/map/map_colours.hpp>
#include <gseg/mrpt/picture.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace gseg::map {
namespace {

constexpr int kTitleBand = 56, kMargin = 12, kMinWidth = 760;  // [px] around the map
constexpr int kEnlargeTo = 640;                                   // [px] longer side of a small map

const gseg::mrpt::Colour kPath{40, 120, 255}, kStart{255, 255, 255};

/// The legend under the map.
std::vector<gseg::mrpt::LegendEntry> legendEntries() {
    return {{colourOf(ColumnClass::Traversable), "traversable (ground, nothing within clearance)"},
            {colourOf(ColumnClass::Obstacle), "obstacle"},
            {colourOf(ColumnClass::Unknown), "unknown: not seen"},
            {kPath, "driven path; arrowhead: direction of travel"},
            {kStart, "start of the path"},
            {{}, "top view: x up, y (left) to the left", false},
            {{}, "(kitti2rawlog drives: x = forward at the start)", false}};
}

/// Class of every map pixel (the most blocking class of the cells it covers), row-major.
std::vector<std::uint8_t> mapPixels(const TopDownGrid& grid, const PictureLayout& l) {
    const int w = l.mapWidth / l.pixelsPerCell, h = l.mapHeight / l.pixelsPerCell;
    std::vector<std::uint8_t> px(std::size_t(w) * std::size_t(h), std::uint8_t(ColumnClass::Unknown));
    grid.forEachCell([&](std::int64_t ix, std::int64_t iy, ColumnClass c) {
        const std::size_t col = std::size_t((l.leftCell - iy) / l.cellsPerPixel), row = std::size_t((l.topCell - ix) / l.cellsPerPixel);
        std::uint8_t& p = px[row * std::size_t(w) + col];
        p = std::max(p, std::uint8_t(c));  // Obstacle > Traversable > Unknown
    });
    return px;
}

/// The path: a line through the centres of the sensor positions' blocks, the start as a square,
/// an arrowhead at the end pointing the way the last metres went.
void drawPath(gseg::mrpt::Picture& pic, const std::vector<Eigen::Vector3d>& path, const PictureLayout& l) {
    const int half = l.pixelsPerCell / 2;
    std::vector<std::pair<int, int>> pts;
    for (const auto& p : path) {
        int c = 0, r = 0;
        if (l.toPixel(p.x(), p.y(), c, r)) pts.emplace_back(c + half, r + half);
    }
    for (std::size_t i = 1; i < pts.size(); ++i) pic.line(pts[i - 1].first, pts[i - 1].second, pts[i].first, pts[i].second, kPath, 2);
    if (pts.empty()) return;
    for (std::size_t k = pts.size() - 1; k-- > 0;) {  // the arrow: the way from a position at least 12 px back
        const int dx = pts.back().first - pts[k].first, dy = pts.back().second - pts[k].second;
        if (dx * dx + dy * dy < 144 && k > 0) continue;
        if (dx || dy) {  // 40 px long, ending at the last position, whatever the scale
            const double n = std::hypot(double(dx), double(dy)), len = 40;
            pic.arrow(pts.back().first - int(std::lround(len * dx / n)), pts.back().second - int(std::lround(len * dy / n)),
                      int(std::lround(len * dx / n)), int(std::lround(len * dy / n)), "", 3, kPath);
        }
        break;
    }
    pic.fill(pts[0].first - 3, pts[0].second - 3, pts[0].first + 3, pts[0].second + 3, kStart);
}

}  // namespace

bool PictureLayout::toPixel(double x, double y, int& col, int& row) const {
    const std::int64_t across = leftCell - std::int64_t(std::floor(y / cell)), down = topCell - std::int64_t(std::floor(x / cell));
    if (across < 0 || down < 0) return false;
    const std::int64_t c = across / cellsPerPixel * pixelsPerCell, r = down / cellsPerPixel * pixelsPerCell;
    if (c >= mapWidth || r >= mapHeight) return false;
    col = mapLeft + int(c), row = mapTop + int(r);
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
    l.topCell = hi[0] + margin;   // x up
    l.leftCell = hi[1] + margin;  // y to the left
    l.cellsHigh = std::uint64_t(hi[0] - lo[0] + 1 + 2 * margin);
    l.cellsWide = std::uint64_t(hi[1] - lo[1] + 1 + 2 * margin);
    const std::uint64_t side = std::max(l.cellsWide, l.cellsHigh);
    l.cellsPerPixel = int((side + std::uint64_t(maxSide) - 1) / std::uint64_t(maxSide));
    if (l.cellsPerPixel == 1) l.pixelsPerCell = std::clamp(int(std::uint64_t(kEnlargeTo) / side), 1, 8);
    const auto s = std::uint64_t(l.cellsPerPixel);
    l.mapWidth = int((l.cellsWide + s - 1) / s) * l.pixelsPerCell;
    l.mapHeight = int((l.cellsHigh + s - 1) / s) * l.pixelsPerCell;
    l.width = std::max(l.mapWidth + 2 * kMargin, kMinWidth);
    l.mapLeft = (l.width - l.mapWidth) / 2;
    l.mapTop = kTitleBand;
    l.height = kTitleBand + l.mapHeight + kMargin + gseg::mrpt::Picture::legendHeight(legendEntries().size()) + kMargin;
    return l;
}

std::string encodeTopDownPng(const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath, const std::string& title) {
    const PictureLayout l = pictureLayout(grid, drivenPath);
    if (l.width <= 0) throw std::runtime_error("empty map: no picture to draw");
    gseg::mrpt::Picture pic(l.width, l.height, backgroundColour());
    const std::vector<std::uint8_t> px = mapPixels(grid, l);
    const int w = l.mapWidth / l.pixelsPerCell, p = l.pixelsPerCell;
    for (int row = 0; row < l.mapHeight; ++row)
        for (int col = 0; col < l.mapWidth; ++col)
            pic.pixel(l.mapLeft + col, l.mapTop + row, colourOf(ColumnClass(px[std::size_t(row / p) * std::size_t(w) + std::size_t(col / p)])));
    drawPath(pic, drivenPath, l);
    char scale[96];
    std::snprintf(scale, sizeof scale, "%.2f m cells%s", l.cell,
                  l.cellsPerPixel > 1 ? (", " + std::to_string(l.cellsPerPixel) + " x " + std::to_string(l.cellsPerPixel) +
                                         " cells a pixel (the most blocking class shown)").c_str()
                                      : "");
    pic.title("gseg traversability map" + (title.empty() ? std::string() : ": " + title), scale);
    const int legendTop = l.mapTop + l.mapHeight + kMargin;
    pic.legend(kMargin, legendTop, legendEntries());
    // Axes and scale at the right of the legend band.
    const int ax = l.width - 70, ay = legendTop + 70;
    pic.arrow(ax, ay, 0, -48, "x");
    pic.arrow(ax, ay, -48, 0, "y");
    pic.scaleBar(l.width - kMargin - 4, legendTop + 124, l.pixelsPerMetre(), 200);
    return pic.png();
}

void writeTopDownPng(const std::string& path, const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath,
                     const std::string& title) {
    std::string png;
    try {
        png = encodeTopDownPng(grid, drivenPath, title);
    } catch (const std::exception& e) {
        throw std::runtime_error(path + ": " + e.what());
    }
    gseg::io::writeFileAtomic(path, png.data(), png.size());
}

}  // namespace gseg::map
