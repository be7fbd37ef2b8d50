#pragma once
/// \file ply.hpp
/// PLY point clouds: reading vertices (x, y, z, optional intensity, any property by name) and
/// writing a cloud coloured by ground labels, with the class as a scalar field CloudCompare loads
/// by default and a `label` property for programs.

#include <gseg/palette.hpp>
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
    std::uint8_t ground[3] = {palette::kGround[0], palette::kGround[1], palette::kGround[2]};  ///< label 1
    std::uint8_t nonGround[3] = {palette::kNonGround[0], palette::kNonGround[1], palette::kNonGround[2]};  ///< label 0
    std::string groundName = "green", nonGroundName = "red";
};

/// What else writeLabelledPly writes.
struct PlyOptions {
    /// The float after each point's z is its intensity: written as `property float intensity`
    /// (needs a stride of at least 16 bytes, as a KITTI buffer viewed in place).
    bool intensity = false;
    std::string comment = "gseg ground segmentation";  ///< first comment line of the header
    /// What labels 1 and 0 mean, in the header's comments ("ground" / "non-ground"; a map's
    /// PLY: "ground" / "obstacle").
    std::string groundName = "ground", nonGroundName = "non-ground";
};

/// The name of the class scalar-field property: "scalar_class" (whatever `options`; one name in
/// every gseg PLY).
std::string classScalarProperty(const PlyOptions& options = PlyOptions());

/// Writes `cloud` as binary little-endian PLY with x, y, z (float), the class scalar field
/// `scalar_class` (uchar: 1 ground, 2 non-ground, the values of the map's `class` layer),
/// optionally intensity (float), red, green, blue (uchar, by label: palette green ground, red
/// non-ground) and label (uchar: 1 ground, 0 non-ground, as the labels file), atomically
/// (temporary file, then rename). One convention in the file: 1 is the ground in every field.
///
/// For CloudCompare (2.11, Debian): a vertex property named `scalar_*` is a scalar field it loads
/// by default, in its PLY dialog and with `-SILENT` (which drops other unknown properties such as
/// `label`), named without the prefix ("class"); it shows the first scalar field of the header,
/// over the RGB colours, on its default Blue>Green>Yellow>Red ramp from the minimum to the
/// maximum: its first view shows non-ground red (as the RGB) and ground blue (the ramp's low end;
/// no value of a two-valued field lands on its green), and choosing Colors: RGB in its properties
/// shows gseg's palette (ground green). Throws std::invalid_argument if the label
/// count differs from the point count, or intensity is asked for points packed closer than 16
/// bytes.
void writeLabelledPly(const std::string& path, const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                      const PlyColours& colours = PlyColours(), const PlyOptions& options = PlyOptions());

/// The bytes writeLabelledPly() writes (to commit several outputs together).
std::string labelledPlyBytes(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                             const PlyColours& colours = PlyColours(), const PlyOptions& options = PlyOptions());

}  // namespace gseg::io
