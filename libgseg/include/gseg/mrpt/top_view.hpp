#pragma once
/// \file top_view.hpp
/// The top view of one scan: its points coloured by class on a Picture, as every scan picture of
/// gseg draws it (gseg segment, rawlog-gseg, gseg eval's breakdown).

#include <gseg/mrpt/picture.hpp>
#include <gseg/point_cloud.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace gseg::mrpt {

/// One class of points in a top view of a scan.
struct PointClass {
    Colour colour;
    std::string name;  ///< legend text; the count is appended ("ground: 81122")
    int layer = 0;     ///< drawn in increasing layer (errors last, over the rest)
    int sizePx = 2;    ///< [px] edge of a point's square
};

/// How a top view of a scan is drawn: the sensor at the centre, x forward up, y left to the left.
struct TopViewOptions {
    int sizePx = 800;          ///< [px] width and height
    double rangeM = 0;         ///< [m] half-width shown; 0: fit the 98th percentile of the points' range (5 to 80 m)
    double ringStepM = 10;     ///< [m] distance between range circles (0: none)
    std::string title;         ///< first line (name files with displayName())
};

/// Draws a top view: every point i in the colour of classes[classOf[i]] (points with a NaN or
/// infinite coordinate, or a class index out of range, are not drawn), range circles, the sensor
/// at the centre with an arrow along x (forward), a scale bar, the title, the orientation and a
/// legend with every class and its count. Throws std::invalid_argument if classOf and the cloud
/// differ in size.
Picture drawTopView(const PointCloudView& cloud, const std::vector<std::uint8_t>& classOf,
                    const std::vector<PointClass>& classes, const TopViewOptions& options);

}  // namespace gseg::mrpt
