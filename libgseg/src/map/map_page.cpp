// The page of every map picture: layout (x right, y up, as the costmap PGM) and decorations.
#include <gseg/map/map_page.hpp>

#include <gseg/map/map_colours.hpp>

#include <algorithm>
#include <stdexcept>

namespace gseg::map {

using gseg::mrpt::Colour;
using gseg::mrpt::Picture;

const char* const kMapOrientation = "top view: x right, y up (as the costmap PGM in map_server, RViz, QGIS)";

std::vector<std::string> wrapText(const std::string& text, std::size_t chars) {
    std::vector<std::string> lines;
    std::string rest = text;
    chars = std::max<std::size_t>(chars, 8);
    while (rest.size() > chars) {
        std::size_t cut = rest.rfind(' ', chars);
        if (cut == std::string::npos || cut < chars / 2) cut = chars;  // a long word: broken
        lines.push_back(rest.substr(0, cut));
        rest = rest.substr(cut);
        if (!rest.empty() && rest[0] == ' ') rest.erase(0, 1);
    }
    lines.push_back(rest);
    return lines;
}

bool MapPage::blockOf(std::int64_t ix, std::int64_t iy, int& blockCol, int& blockRow) const {
    const std::int64_t across = ix - minX, down = maxY - iy;
    if (across < 0 || down < 0 || across >= cellsWide || down >= cellsHigh) return false;
    blockCol = int(across / cellsPerPixel), blockRow = int(down / cellsPerPixel);
    return true;
}

bool MapPage::cellPixel(std::int64_t ix, std::int64_t iy, int& col, int& row) const {
    int bc = 0, br = 0;
    if (!blockOf(ix, iy, bc, br)) return false;
    col = mapLeft + bc * pixelsPerCell, row = mapTop + br * pixelsPerCell;
    return true;
}

MapPage mapPage(std::int64_t minX, std::int64_t minY, std::int64_t maxX, std::int64_t maxY, double cell, const MapPageOptions& o) {
    if (maxX < minX || maxY < minY) throw std::invalid_argument("map page: no cells");
    if (!(cell > 0)) throw std::invalid_argument("map page: the cell size must be positive");
    if (o.maxSide < 16) throw std::invalid_argument("map page: maxSide must be at least 16 pixels");
    constexpr int m = MapPage::kMargin;
    MapPage p;
    p.cell = cell;
    p.minX = minX, p.maxY = maxY;
    p.cellsWide = maxX - minX + 1, p.cellsHigh = maxY - minY + 1;
    const std::uint64_t side = std::uint64_t(std::max(p.cellsWide, p.cellsHigh));
    p.cellsPerPixel = int((side + std::uint64_t(o.maxSide) - 1) / std::uint64_t(o.maxSide));
    if (p.cellsPerPixel == 1) p.pixelsPerCell = std::clamp(int(std::uint64_t(std::max(o.enlargeTo, 1)) / side), 1, std::max(o.maxEnlarge, 1));
    const std::int64_t s = p.cellsPerPixel;
    p.mapWidth = int((p.cellsWide + s - 1) / s) * p.pixelsPerCell;
    p.mapHeight = int((p.cellsHigh + s - 1) / s) * p.pixelsPerCell;
    // The legend: the caller's lines, then the orientation.
    p.legend = o.legend;
    p.legend.push_back({{}, kMapOrientation, false});
    std::size_t legendChars = 0;
    for (const auto& e : p.legend) legendChars = std::max(legendChars, e.text.size() + (e.swatch ? 3 : 0));
    const int side_ = o.sideWidth > 0 ? 24 + o.sideWidth : 0;
    p.width = std::max({o.minWidth, m + p.mapWidth + side_ + m, m + 30 + int(legendChars) * Picture::kCharWidth + 20 + MapPage::kAxesBlock});
    // The title, wrapped to the page.
    const std::size_t chars = std::size_t((p.width - 20) / Picture::kCharWidth);
    for (const std::string& paragraph : o.title)
        for (auto& line : wrapText(paragraph, chars)) p.titleLines.push_back(line);
    const int titleBand = 8 + int(std::max<std::size_t>(p.titleLines.size(), 1)) * Picture::kLineHeight + 8;
    p.mapLeft = side_ ? m : (p.width - p.mapWidth) / 2;  // centred unless a block sits right of it
    p.mapTop = titleBand;
    p.sideLeft = p.mapLeft + p.mapWidth + 24;
    const int band = std::max(p.mapHeight, o.sideWidth > 0 ? o.sideHeight : 0);
    p.legendTop = p.mapTop + band + m;
    p.height = p.legendTop + std::max(Picture::legendHeight(p.legend.size()), MapPage::kAxesBandHeight) + m;
    return p;
}

Picture pageCanvas(const MapPage& page) { return Picture(page.width, page.height, backgroundColour()); }

void paintBlocks(Picture& pic, const MapPage& page, const std::vector<Colour>& blocks) {
    const int wide = page.blocksWide(), high = page.blocksHigh(), p = page.pixelsPerCell;
    if (blocks.size() != std::size_t(wide) * std::size_t(high)) throw std::invalid_argument("map page: one colour per block needed");
    for (int row = 0; row < high; ++row)
        for (int col = 0; col < wide; ++col) {
            const int x = page.mapLeft + col * p, y = page.mapTop + row * p;
            pic.fill(x, y, x + p - 1, y + p - 1, blocks[std::size_t(row) * std::size_t(wide) + std::size_t(col)]);
        }
}

void drawPageFrame(Picture& pic, const MapPage& page) {
    if (!page.titleLines.empty()) pic.title(page.titleLines[0]);
    for (std::size_t i = 1; i < page.titleLines.size(); ++i) pic.text(10, 8 + int(i) * Picture::kLineHeight, page.titleLines[i]);
    pic.legend(MapPage::kMargin, page.legendTop, page.legend);
    // The axes as the map is drawn: x to the right, y up; the scale bar under them.
    const int ax = page.width - 90, ay = page.legendTop + 64;
    pic.arrow(ax, ay, 48, 0, "x");
    pic.arrow(ax, ay, 0, -48, "y");
    pic.scaleBar(page.width - MapPage::kMargin - 4, page.legendTop + 124, page.pixelsPerMetre(), 200);
}

}  // namespace gseg::map
