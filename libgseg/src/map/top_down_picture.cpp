// The top-down picture: its layout and the PNG, on the map page of every map picture
// (gseg/map/map_page.hpp: x right, y up, as the costmap PGM).
#include <gseg/map/top_down_picture.hpp>

#include <gseg/map/map_colours.hpp>
#include <gseg/mrpt/picture.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace gseg::map {
namespace {

const gseg::mrpt::Colour kPath{40, 120, 255}, kStart{255, 255, 255};

/// The legend under the map.
std::vector<gseg::mrpt::LegendEntry> legendEntries() {
    return {{colourOf(ColumnClass::Traversable), "traversable (ground, nothing within clearance)"},
            {colourOf(ColumnClass::Obstacle), "obstacle"},
            {colourOf(ColumnClass::Unknown), "unknown: not seen"},
            {kPath, "driven path; arrowhead: direction of travel"},
            {kStart, "start of the path"},
            {{}, "voxel columns: the costmap is _costmap.pgm / _layer_class.png", false},
            {{}, "(kitti2rawlog drives: x = forward at the start)", false}};
}

/// Class of every map block (the most blocking class of the cells it covers), row-major.
std::vector<std::uint8_t> mapBlocks(const TopDownGrid& grid, const PictureLayout& l) {
    const int w = l.blocksWide();
    std::vector<std::uint8_t> px(std::size_t(w) * std::size_t(l.blocksHigh()), std::uint8_t(ColumnClass::Unknown));
    grid.forEachCell([&](std::int64_t ix, std::int64_t iy, ColumnClass c) {
        int col = 0, row = 0;
        if (!l.blockOf(ix, iy, col, row)) return;
        std::uint8_t& p = px[std::size_t(row) * std::size_t(w) + std::size_t(col)];
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
    return cellPixel(std::int64_t(std::floor(x / cell)), std::int64_t(std::floor(y / cell)), col, row);
}

namespace {

std::string scaleLine(double cell, int cellsPerPixel) {
    char scale[160];
    std::snprintf(scale, sizeof scale, "%.2f m cells%s", cell,
                  cellsPerPixel > 1 ? (", " + std::to_string(cellsPerPixel) + " x " + std::to_string(cellsPerPixel) +
                                       " cells a pixel (the most blocking class shown)").c_str()
                                    : "");
    return scale;
}

}  // namespace

PictureLayout pictureLayout(const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& path, int maxSide, const std::string& title) {
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
    MapPageOptions o;
    o.maxSide = maxSide;
    o.legend = legendEntries();
    // The title's second line depends on the reduction: the page first, then the title.
    const MapPage probe = mapPage(lo[0] - margin, lo[1] - margin, hi[0] + margin, hi[1] + margin, grid.cell(), o);
    o.title = {"gseg traversability map" + (title.empty() ? std::string() : ": " + title), scaleLine(grid.cell(), probe.cellsPerPixel)};
    static_cast<MapPage&>(l) = mapPage(lo[0] - margin, lo[1] - margin, hi[0] + margin, hi[1] + margin, grid.cell(), o);
    return l;
}

std::string encodeTopDownPng(const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath, const std::string& title) {
    const PictureLayout l = pictureLayout(grid, drivenPath, 4096, title);
    if (l.width <= 0) throw std::runtime_error("empty map: no picture to draw");
    gseg::mrpt::Picture pic = pageCanvas(l);
    const std::vector<std::uint8_t> blocks = mapBlocks(grid, l);
    std::vector<gseg::mrpt::Colour> colours(blocks.size());
    for (std::size_t i = 0; i < blocks.size(); ++i) colours[i] = colourOf(ColumnClass(blocks[i]));
    paintBlocks(pic, l, colours);
    drawPath(pic, drivenPath, l);
    drawPageFrame(pic, l);
    return pic.png();
}

}  // namespace gseg::map
