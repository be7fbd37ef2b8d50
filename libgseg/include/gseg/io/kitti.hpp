#pragma once
/// \file kitti.hpp
/// KITTI / SemanticKITTI files: velodyne scans (.bin), point labels (.label) and gseg's own
/// prediction files (one byte per point).

#include <cstdint>
#include <string>
#include <vector>

namespace gseg::io {

/// Reads a KITTI velodyne scan: float32 little-endian x, y, z, intensity per point (16 bytes).
/// Returns the raw floats (4 per point). Throws std::runtime_error naming the file if it is
/// missing, unreadable, empty, or its size is not a multiple of 16 bytes.
std::vector<float> readKittiBin(const std::string& path);

/// Reads a SemanticKITTI .label file (one uint32 per point). If `expectedPoints` is not
/// SIZE_MAX, throws std::runtime_error if the count differs (the message gives both counts).
std::vector<std::uint32_t> readKittiLabels(const std::string& path, std::size_t expectedPoints = SIZE_MAX);

/// Writes `bytes` to `path` atomically: to a temporary file beside it, then renamed. Throws
/// std::runtime_error on failure (and leaves no partial file).
void writeFileAtomic(const std::string& path, const void* bytes, std::size_t size);

/// Reads a whole file as bytes; throws std::runtime_error naming the file on failure.
std::vector<std::uint8_t> readFileBytes(const std::string& path);

}  // namespace gseg::io
