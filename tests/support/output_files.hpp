#pragma once
/// \file output_files.hpp
/// Files a test writes the way the map route writes its outputs: an encoder's bytes
/// (encodeLayersGeoTiff(), encodeLayerPng(), encodePng(), encodePgm() ...) through gseg::io's one
/// atomic writer. The library has no write-to-a-path wrapper per format. Header-only.

#include <gseg/io/atomic_file.hpp>
#include <gseg/io/ros_map.hpp>

#include <filesystem>
#include <string>

namespace gseg::test {

/// Writes `bytes` to `path` with gseg::io::writeFileAtomic() (complete or absent).
inline void writeBytes(const std::string& path, const std::string& bytes) {
    gseg::io::writeFileAtomic(path, bytes.data(), bytes.size());
}

/// `<prefix>.pgm` and `<prefix>.yaml` of a map_server map, committed together (all or none), the
/// YAML naming the PGM by its file name: as TraversabilityMap::write() writes a costmap. Throws
/// std::invalid_argument on an inconsistent map (gseg::io::validate()) before any file is made.
inline void writeRosMap(const std::string& prefix, const gseg::io::RosMap& map) {
    const std::string pgm = gseg::io::encodePgm(map);
    const std::string yaml = gseg::io::encodeRosMapYaml(map, std::filesystem::path(prefix).filename().string() + ".pgm");
    gseg::io::AtomicFileSet files({prefix + ".pgm", prefix + ".yaml"});
    files[0].write(pgm.data(), pgm.size());
    files[1].write(yaml.data(), yaml.size());
    files.commit();
}

}  // namespace gseg::test
