#pragma once
/// \file ply.hpp
/// PLY point clouds: reading vertices (x, y, z, optional intensity, any property by name) and
/// writing a cloud coloured by ground labels, with a `label` property, for viewers (CloudCompare
/// filters by a scalar field such as `label`).

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

/// The values of the vertex property `property` (e.g. "label"), one per vertex, as double. Same
/// checks as readPly(); throws std::runtime_error naming the file if the property is absent.
std::vector<double> readPlyProperty(const std::string& path, const std::string& property);
std::vector<double> parsePlyProperty(const std::uint8_t* data, std::size_t size, const std::string& name,
                                     const std::string& property);

/// Colours of writeLabelledPly (RGB) and their names (written into the header's comments).
struct PlyColours {
    std::uint8_t ground[3] = {40, 200, 60};     ///< label 1
    std::uint8_t nonGround[3] = {230, 60, 40};  ///< label 0
    std::string groundName = "green", nonGroundName = "red";
};

/// What else writeLabelledPly writes.
struct PlyOptions {
    /// The float after each point's z is its intensity: written as `property float intensity`
    /// (needs a stride of at least 16 bytes, as a KITTI buffer viewed in place).
    bool intensity = false;
    std::string comment = "gseg ground segmentation";  ///< first comment line of the header
    std::string groundName = "ground", nonGroundName = "non-ground";  ///< what labels 1 and 0 mean
};

/// Writes `cloud` as binary little-endian PLY with x, y, z (float), optionally intensity (float),
/// red, green, blue (uchar, by label) and label (uchar: 1 ground, 0 non-ground), atomically
/// (temporary file, then rename). Throws std::invalid_argument if the label count differs from the
/// point count, or intensity is asked for points packed closer than 16 bytes.
void writeLabelledPly(const std::string& path, const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                      const PlyColours& colours = PlyColours(), const PlyOptions& options = PlyOptions());

/// The bytes writeLabelledPly() writes (to commit several outputs together).
std::string labelledPlyBytes(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                             const PlyColours& colours = PlyColours(), const PlyOptions& options = PlyOptions());

}  // namespace gseg::io
