#pragma once
/// \file ros_map.hpp
/// 2D occupancy maps in the ROS map_server format: a binary PGM (P5) image and a YAML file that
/// names it (`image`, `resolution`, `origin`, `negate`, `occupied_thresh`, `free_thresh`, `mode`).
/// That is what Nav2's map_server, ROS 1's map_server and MRPT's
/// `COccupancyGridMap2D::loadFromROSMapServerYAML` load. The one reader and encoder of gseg for it.
///
/// Frame: cell (cx, cy) covers map-frame x in [originX + cx * resolution, originX + (cx + 1) *
/// resolution) and y likewise; cy = 0 is the image's bottom row (map_server's convention: the
/// image's first row is the largest y).

#include <cstdint>
#include <string>
#include <vector>

namespace gseg::io {

/// What one cell of a RosMap says under map_server's thresholds.
enum class RosCell : std::uint8_t { Unknown = 0, Free = 1, Occupied = 2 };

/// A map_server map in memory.
struct RosMap {
    double resolution = 0.2;            ///< [m] edge of a cell (pixel)
    double originX = 0, originY = 0;    ///< [m] map-frame position of the bottom-left corner of cell (0, 0)
    double originYaw = 0;               ///< [rad] the YAML's third origin value (gseg writes 0; a reader of ours refuses others)
    int negate = 0;                     ///< 0: white (255) is free; 1: black (0) is free
    double occupiedThresh = 0.65;       ///< [-] occupied where the pixel's occupancy exceeds this
    double freeThresh = 0.196;          ///< [-] free where it is below this
    std::string mode = "trinary";       ///< trinary, scale or raw (how a planner reads the grey values)
    int width = 0, height = 0;          ///< [cells]
    std::vector<std::uint8_t> pixels;   ///< width * height grey values, image row-major (row 0: top, largest y)

    /// The pixel values gseg writes in trinary mode (those of map_server's map_saver), negate 0.
    static constexpr std::uint8_t kFree = 254, kOccupied = 0, kUnknown = 205;

    /// An all-unknown map of width x height cells.
    static RosMap unknown(int width, int height, double resolution, double originX, double originY);
    /// Pixel value of cell (cx, cy) (cy from the bottom); cells must be inside.
    std::uint8_t& value(int cx, int cy) { return pixels[std::size_t(height - 1 - cy) * std::size_t(width) + std::size_t(cx)]; }
    std::uint8_t value(int cx, int cy) const { return pixels[std::size_t(height - 1 - cy) * std::size_t(width) + std::size_t(cx)]; }
    /// The class of cell (cx, cy) under the thresholds (occupancy = (255 - v) / 255, or v / 255
    /// with negate; mode raw: occupancy = v / 100 for v up to 100, larger values unknown, as
    /// map_server loads raw maps); Unknown outside the map.
    RosCell at(long long cx, long long cy) const;
    /// The cell holding map-frame (x, y) (floor; may be outside the map).
    long long cellX(double x) const;
    long long cellY(double y) const;
};

/// Reads `yamlPath` and the image it names (relative to the YAML's folder unless absolute): a
/// binary PGM (P5, maxval below 256, comments allowed). Throws std::runtime_error naming the file
/// (and the line, for the YAML) on a missing or malformed key, a non-finite or non-positive
/// resolution, a non-zero origin yaw, an image that is not a P5 PGM or is truncated.
RosMap readRosMap(const std::string& yamlPath);

/// The PGM bytes of a map (P5, maxval 255, a comment line with the resolution).
std::string encodePgm(const RosMap& map);
/// The YAML text naming `imageName` (written as given: the PGM's file name beside the YAML).
std::string encodeRosMapYaml(const RosMap& map, const std::string& imageName);
/// Throws std::invalid_argument on an inconsistent map (size, thresholds, resolution): what
/// encodePgm() and encodeRosMapYaml() check.
void validate(const RosMap& map);

}  // namespace gseg::io
