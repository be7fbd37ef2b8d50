#pragma once
/// \file top_down_picture.hpp
/// The top-down picture of a traversability map (`<prefix>_traversability.png`): the top-down
/// grid with the driven path, title, legend, scale bar and axes; its layout, and the PNG.
/// World frame: metres, x up and y to the left in the picture.

#include <gseg/map/top_down_grid.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace gseg::map {

/// Where the top-down picture puts the grid. The picture follows the convention of gseg's scan
/// pictures: world x up, y to the left (for a kitti2rawlog drive, x is the vehicle's forward
/// direction at the first scan). It frames the cells with data and the driven path, with a margin
/// of 5 cells: a small map is enlarged (pixelsPerCell, about 640 pixels on its longer side), a
/// large one reduced to at most maxSide pixels a side (cellsPerPixel, the most blocking class of
/// the cells a pixel covers wins). Around the map: a title band above, a legend band below.
struct PictureLayout {
    std::int64_t topCell = 0;   ///< cell index along x of the map's first row (x up: rows go to smaller x)
    std::int64_t leftCell = 0;  ///< cell index along y of the map's first column (y left: columns go to smaller y)
    int cellsPerPixel = 1;      ///< > 1: a large map, reduced
    int pixelsPerCell = 1;      ///< > 1: a small map, enlarged
    int mapLeft = 0, mapTop = 0;      ///< [pixels] top-left corner of the map in the picture
    int mapWidth = 0, mapHeight = 0;  ///< [pixels] the map area
    int width = 0, height = 0;        ///< [pixels] the whole picture (0: nothing to draw)
    double cell = 0.2;                ///< [m]
    std::uint64_t cellsWide = 0, cellsHigh = 0;  ///< [cells] the framed area: along y (across), along x (down)

    /// Top-left pixel (in the picture) of the block that shows world (x, y); false outside the map.
    bool toPixel(double x, double y, int& col, int& row) const;
    /// [pixels per metre] of the map area.
    double pixelsPerMetre() const { return double(pixelsPerCell) / (double(cellsPerPixel) * cell); }
};
PictureLayout pictureLayout(const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath, int maxSide = 4096);

/// Writes the picture (pictureLayout(): traversable green, obstacle red, unknown grey, the page
/// around the mapped area darker; the path as a blue line from a white start square to an
/// arrowhead in the direction of travel; title, legend naming every colour, scale bar and the
/// x / y axes) as a PNG, atomically. `title` is the first line (e.g. "6 scans, 3.55 m driven").
/// Throws std::runtime_error naming the file on failure.
void writeTopDownPng(const std::string& path, const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath,
                     const std::string& title = "");
/// The same PNG as bytes.
std::string encodeTopDownPng(const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath,
                             const std::string& title = "");

}  // namespace gseg::map
