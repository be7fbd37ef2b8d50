#pragma once
/// \file map_page.hpp
/// The one page every map picture is drawn on: the traversability picture
/// (`PREFIX_traversability.png`, top_down_picture.hpp), the layer pictures
/// (`PREFIX_layer_<name>.png`, layer_picture.hpp) and `gseg eval-map`'s scored cells
/// (`PREFIX_map_cells.png`). Its layout and its decorations in one place: a title band (the first
/// line bold, every line wrapped to the page), the map area, an optional block right of the map
/// (a colour bar), and a band under the map with the legend on the left and the x / y arrows and
/// the scale bar on the right.
///
/// Orientation: map-frame x to the right and y up, as the costmap PGM (`PREFIX_costmap.pgm`) is
/// drawn by map_server, RViz and QGIS: pixel column = cell x, row 0 = the largest y. A map picture
/// and the costmap can be laid over each other without a turn. The legend ends with a line that
/// says so (kMapOrientation) and the arrows show it.

#include <gseg/mrpt/picture.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace gseg::map {

/// The legend line that states the orientation of every map picture.
extern const char* const kMapOrientation;

/// What a page holds besides the cells.
struct MapPageOptions {
    int maxSide = 4096;    ///< [pixels] longest side of the map area: a larger box is reduced (several cells a pixel)
    int enlargeTo = 640;   ///< [pixels] a small box is enlarged to about this on its longer side ...
    int maxEnlarge = 8;    ///< ... with at most this many pixels a cell
    int minWidth = 760;    ///< [pixels] narrowest page
    int sideWidth = 0;     ///< [pixels] a block right of the map (a colour bar and its labels); 0: none
    int sideHeight = 0;    ///< [pixels] its height (the band of the map is the taller of the two)
    std::vector<std::string> title;                 ///< paragraphs, each wrapped to the page; the first line is drawn bold
    std::vector<gseg::mrpt::LegendEntry> legend;    ///< under the map; kMapOrientation is added after them
};

/// Where a page puts things (computed before drawing; tests check it).
struct MapPage {
    static constexpr int kMargin = 12;          ///< [pixels] around the map and the bands
    static constexpr int kAxesBlock = 240;      ///< [pixels] right of the legend: axes and scale bar
    static constexpr int kAxesBandHeight = 140; ///< [pixels] the height they need

    std::int64_t minX = 0, maxY = 0;  ///< [cells] the cell index of the map area's left column (x) and top row (y)
    std::int64_t cellsWide = 0, cellsHigh = 0;  ///< [cells] the box: along x (across), along y (down)
    double cell = 0.2;                ///< [m]
    int cellsPerPixel = 1;            ///< > 1: a large box, reduced
    int pixelsPerCell = 1;            ///< > 1: a small box, enlarged
    int mapLeft = 0, mapTop = 0;      ///< [pixels] top-left corner of the map area
    int mapWidth = 0, mapHeight = 0;  ///< [pixels] the map area
    int sideLeft = 0;                 ///< [pixels] left edge of the side block (its top is mapTop)
    int legendTop = 0;                ///< [pixels] top of the band under the map
    int width = 0, height = 0;        ///< [pixels] the whole page
    std::vector<std::string> titleLines;           ///< the title, wrapped; line i at (10, 8 + 20 i)
    std::vector<gseg::mrpt::LegendEntry> legend;   ///< as drawn, the orientation line last

    int blocksWide() const { return mapWidth / pixelsPerCell; }   ///< [blocks] of cellsPerPixel^2 cells
    int blocksHigh() const { return mapHeight / pixelsPerCell; }
    /// The block (column, row, row-major over blocksWide() x blocksHigh()) showing cell (ix, iy);
    /// false outside the box.
    bool blockOf(std::int64_t ix, std::int64_t iy, int& blockCol, int& blockRow) const;
    /// Top-left pixel (in the page) of the block showing cell (ix, iy); false outside the box.
    bool cellPixel(std::int64_t ix, std::int64_t iy, int& col, int& row) const;
    /// [pixels per metre] of the map area.
    double pixelsPerMetre() const { return double(pixelsPerCell) / (double(cellsPerPixel) * cell); }
};

/// The page for the cells minX..maxX, minY..maxY (inclusive) of `cell` metres. Throws
/// std::invalid_argument on an empty box or a cell <= 0.
MapPage mapPage(std::int64_t minX, std::int64_t minY, std::int64_t maxX, std::int64_t maxY, double cell,
                const MapPageOptions& options);

/// `text` broken at spaces into lines of at most `chars` characters (a longer word is cut).
std::vector<std::string> wrapText(const std::string& text, std::size_t chars);

/// A canvas of the page's size in the page colour (backgroundColour()).
gseg::mrpt::Picture pageCanvas(const MapPage& page);
/// Paints the map area: `blocks` holds one colour per block, row-major (blocksWide() x
/// blocksHigh()).
void paintBlocks(gseg::mrpt::Picture& pic, const MapPage& page, const std::vector<gseg::mrpt::Colour>& blocks);
/// Draws the title, the legend, the x / y arrows (x right, y up) and the scale bar.
void drawPageFrame(gseg::mrpt::Picture& pic, const MapPage& page);

}  // namespace gseg::map
