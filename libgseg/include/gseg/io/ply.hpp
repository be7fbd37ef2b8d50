#pragma once
/// \file ply.hpp
/// PLY point clouds: reading vertices (x, y, z, optional intensity) and writing a cloud coloured
/// by ground labels for viewers.

#include <gseg/point_cloud.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace gseg::io {

/// Reads the vertices of a PLY file (ascii or binary_little_endian; the vertex element must come
/// first and appear once; properties x, y, z required, intensity optional, any other scalar
/// property skipped; property names unique). Returns 4 floats per point: x, y, z, intensity (0
/// where absent); values beyond the float range become +-infinity. Throws std::runtime_error naming
/// the file on a missing, malformed or truncated file. Memory follows the file: a header that
/// announces more vertices than the rest of the file can hold is rejected before anything is
/// allocated for them.
std::vector<float> readPly(const std::string& path);

/// The same for a PLY file already in memory; `name` stands for it in messages.
std::vector<float> parsePly(const std::uint8_t* data, std::size_t size, const std::string& name);

/// Colours of writeLabelledPly (RGB).
struct PlyColours {
    std::uint8_t ground[3] = {40, 200, 60};     ///< green
    std::uint8_t nonGround[3] = {230, 60, 40};  ///< red
};

/// Writes `cloud` as binary little-endian PLY with x, y, z (float) and red, green, blue (uchar)
/// from `labels` (1 ground, 0 non-ground), atomically (temporary file, then rename). Throws
/// std::invalid_argument if the label count differs from the point count.
void writeLabelledPly(const std::string& path, const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                      const PlyColours& colours = PlyColours());

/// The bytes writeLabelledPly() writes (to commit several outputs together).
std::string labelledPlyBytes(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                             const PlyColours& colours = PlyColours());

}  // namespace gseg::io
