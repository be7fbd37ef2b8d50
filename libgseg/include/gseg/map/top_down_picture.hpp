#pragma once
/// \file top_down_picture.hpp
/// The top-down picture of a traversability map (`<prefix>_traversability.png`): the top-down
/// grid with the driven path, title, legend, scale bar and axes; its layout, and the PNG.
/// World frame: metres, x to the right and y up in the picture (as the costmap PGM).

#include <gseg/map/map_page.hpp>
#include <gseg/map/top_down_grid.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace gseg::map {

/// Where the top-down picture puts the grid: a MapPage (gseg/map/map_page.hpp), so x to the right
/// and y up as the costmap PGM. It frames the cells with data and the driven path, with a margin
/// of 5 cells: a small map is enlarged (pixelsPerCell, about 640 pixels on its longer side), a
/// large one reduced to at most maxSide pixels a side (cellsPerPixel, the most blocking class of
/// the cells a pixel covers wins). Around the map: a title band above, a legend band below.
struct PictureLayout : MapPage {
    /// Top-left pixel (in the picture) of the block that shows world (x, y) [m]; false outside the map.
    bool toPixel(double x, double y, int& col, int& row) const;
};
/// `title`: the first line of the title after "gseg traversability map: ".
PictureLayout pictureLayout(const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath, int maxSide = 4096,
                            const std::string& title = "");

/// The picture (pictureLayout(): traversable green, obstacle red, unknown grey, the page around
/// the mapped area darker; the path as a blue line from a white start square to an arrowhead in
/// the direction of travel; title, legend naming every colour, scale bar and the x / y arrows: x
/// right, y up) as PNG bytes. `title` is the first line (e.g. "6 scans, 3.55 m driven").
std::string encodeTopDownPng(const TopDownGrid& grid, const std::vector<Eigen::Vector3d>& drivenPath,
                             const std::string& title = "");

}  // namespace gseg::map
