#pragma once
/// \file render.hpp
/// Top-down pictures of a labelled scan (PNG, via MRPT's CImage).

#include <gseg/point_cloud.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace mrpt::img {
class CImage;
}

namespace gseg::mrpt {

/// Writes `image` (8-bit grey or colour) as a PNG through gseg::io::AtomicFile: encoded in memory
/// by gseg (zlib), every write and the close checked, so a full disk is an error and leaves
/// nothing (MRPT's CImage::saveToFile reports success on a truncated file). Throws
/// std::runtime_error naming `path`.
void writePng(const std::string& path, const ::mrpt::img::CImage& image);

/// The PNG file writePng() writes, in memory (to commit several outputs together).
std::string encodePng(const ::mrpt::img::CImage& image);

/// How the picture is drawn. The sensor is at the centre; x (forward) points up, y (left) points left.
struct RenderOptions {
    int sizePx = 800;          ///< [px] width and height
    double rangeM = 0;         ///< [m] half-width shown; 0: fit the 98th percentile of the points' range (at most 80 m)
    double ringStepM = 10;     ///< [m] distance between range circles
    std::string title;         ///< text at the top-left (e.g. the scan's name)
};

/// Writes a top-down PNG: ground green, non-ground red (drawn over the ground), range circles,
/// the sensor as a white cross, a legend with the counts; points with a NaN or infinite
/// coordinate are not drawn. Written with writePng(). Throws
/// std::invalid_argument if the label count differs from the point count, std::runtime_error if
/// the file cannot be written.
void writeTopDownPng(const std::string& path, const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                     const RenderOptions& options = RenderOptions());

/// The PNG file writeTopDownPng() writes, in memory.
std::string topDownPng(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                       const RenderOptions& options = RenderOptions());

}  // namespace gseg::mrpt
