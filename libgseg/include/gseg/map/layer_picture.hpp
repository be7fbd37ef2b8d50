#pragma once
/// \file layer_picture.hpp
/// A picture of one layer of a LayerGrid (gseg/map/layer_grid.hpp) as a PNG, drawn with gseg's
/// picture conventions (gseg/mrpt/picture.hpp) on the page of every map picture
/// (gseg/map/map_page.hpp): map-frame x to the right, y up, with x / y arrows, as the costmap PGM
/// (the `class` layer's picture and `PREFIX_costmap.pgm` agree cell for cell).
///
/// Colours: a continuous layer (`elevation`, `slope`, ...) through the viridis colour map
/// (matplotlib's perceptually uniform map, dark blue at the low end, yellow at the high end),
/// with a colour bar labelled with its range and unit. The range is the 2nd to 98th percentile of
/// the layer's finite values (a few outliers, a 63 deg slope at a wall, would otherwise leave the
/// rest of the map in one dark colour); values beyond it take the end colours and the bar's end
/// labels say so ("<= 0.00 deg", ">= 12.4 deg"), the title keeps the whole range. +inf cells (the
/// clearance where no obstacle is above the ground) are white and named in the legend ("+inf: no
/// obstacle above (no limit)"), -inf cells black. The `class` layer in the class colours of
/// the map's other pictures (colourOf(): 1 traversable green, 2 not traversable red). NaN
/// (unknown) cells in the colour of unknown cells of the map's pictures (grey), named in the
/// legend; the page around the grid darker (backgroundColour()). A scale bar, the axes and a title
/// naming the layer, its meaning, unit, range and cell size. Every text fits the canvas: a long
/// title is wrapped onto more lines.

#include <gseg/map/layer_grid.hpp>
#include <gseg/map/map_page.hpp>
#include <gseg/mrpt/picture.hpp>

#include <limits>
#include <string>
#include <vector>

namespace gseg::map {

/// What the picture of a layer shows besides the layer.
struct LayerPictureOptions {
    std::string title;  ///< first line of the title after "<layer name> [unit]", e.g. the drive ("seq00: 10 scans"); may be long (wrapped)
    double min = std::numeric_limits<double>::quiet_NaN();  ///< [layer unit] low end of the colour bar; NaN: the 2nd percentile of the layer's finite values
    double max = std::numeric_limits<double>::quiet_NaN();  ///< [layer unit] high end; NaN: the 98th percentile
    int maxSide = 2048;  ///< [pixels] longest side of the map area: a larger grid is reduced (a pixel shows the largest value of its cells)
};

/// Where the picture puts things (computed before drawing; the tests check it).
struct LayerPictureLayout {
    /// One line of text, its top-left corner at (x, y) in the 9 x 15 pixel font of the canvas.
    struct Text {
        int x = 0, y = 0;
        std::string text;
    };
    int width = 0, height = 0;        ///< [pixels] the whole picture
    int mapLeft = 0, mapTop = 0;      ///< [pixels] top-left corner of the map area
    int mapWidth = 0, mapHeight = 0;  ///< [pixels] the map area: grid.width() cells across (x), grid.height() down (y)
    int pixelsPerCell = 1;            ///< > 1: a small grid, enlarged
    int cellsPerPixel = 1;            ///< > 1: a large grid, reduced
    bool classes = false;             ///< the `class` layer: class colours, no colour bar
    double low = 0, high = 0;         ///< [layer unit] the colour bar's range (equal when the layer holds one value or none)
    bool clippedLow = false, clippedHigh = false;  ///< finite values below low / above high (in the end colours)
    std::size_t positiveInfinite = 0, negativeInfinite = 0;  ///< cells at +inf / -inf (white / black, named in the legend)
    int barLeft = 0, barTop = 0, barHeight = 0;  ///< [pixels] the colour bar (high at the top); barHeight 0: none
    int legendTop = 0;                ///< [pixels] top of the legend band (legend left, axes and scale bar right)
    int gridWidth = 0, gridHeight = 0;  ///< [cells] of the grid drawn
    std::vector<Text> texts;          ///< every text of the picture (the title's lines first, the legend's last)
    MapPage page;                     ///< the page (the fields above are its)

    /// Top-left pixel of the block showing cell (cx, cy) of the grid; false outside it.
    bool toPixel(int cx, int cy, int& col, int& row) const;
    /// [pixels per metre] of the map area.
    double pixelsPerMetre(double resolution) const { return double(pixelsPerCell) / (double(cellsPerPixel) * resolution); }
};

/// The colour of +inf cells (white: beyond the colour bar's high end) and of -inf cells (black).
gseg::mrpt::Colour positiveInfinityColour();
gseg::mrpt::Colour negativeInfinityColour();

/// The layout of the picture of `layer`. Throws std::out_of_range if the grid has no such layer,
/// std::invalid_argument on a grid without cells, a layer whose values are not width * height,
/// an infinite options min or max, min above max, or maxSide below 16.
LayerPictureLayout layerPictureLayout(const LayerGrid& grid, const std::string& layer, const LayerPictureOptions& options = {});

/// The PNG bytes of the picture of `layer` (see the file comment). Throws as layerPictureLayout().
std::string encodeLayerPng(const LayerGrid& grid, const std::string& layer, const LayerPictureOptions& options = {});

/// The viridis colour of t in [0, 1] (clamped; NaN gives the low end): the colour map of
/// continuous layers (matplotlib's viridis at nine stops, interpolated linearly in RGB).
gseg::mrpt::Colour viridis(double t);

}  // namespace gseg::map
