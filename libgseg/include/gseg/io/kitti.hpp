#pragma once
/// \file kitti.hpp
/// KITTI / SemanticKITTI files: velodyne scans (.bin), point labels (.label) and gseg's own
/// prediction files (one byte per point).

#include <gseg/io/atomic_file.hpp>  // writeFileAtomic

#include <cstdint>
#include <string>
#include <vector>

namespace gseg::io {

/// Reads a KITTI velodyne scan: float32 little-endian x, y, z, intensity per point (16 bytes).
/// Returns the raw floats (4 per point). Throws std::runtime_error naming the file if it is
/// missing, unreadable, empty, or its size is not a multiple of 16 bytes.
std::vector<float> readKittiBin(const std::string& path);

/// The same for a scan already in memory; `name` stands for it in messages.
std::vector<float> parseKittiBin(const std::uint8_t* data, std::size_t size, const std::string& name);

/// Reads a SemanticKITTI .label file (one uint32 per point). If `expectedPoints` is not
/// SIZE_MAX, throws std::runtime_error if the count differs (the message gives both counts).
std::vector<std::uint32_t> readKittiLabels(const std::string& path, std::size_t expectedPoints = SIZE_MAX);

/// The same for labels already in memory; `name` stands for them in messages.
std::vector<std::uint32_t> parseKittiLabels(const std::uint8_t* data, std::size_t size, const std::string& name,
                                            std::size_t expectedPoints = SIZE_MAX);

/// Reads a whole regular file as bytes (memory: the file's size); throws std::runtime_error naming
/// the file if it is missing, not a regular file (a folder, a pipe, a device) or unreadable. The
/// file is looked at (stat) before it is opened, so a FIFO is refused instead of waited on.
/// `maxBytes`: a larger file is refused (naming its size and the bound) before anything is read.
std::vector<std::uint8_t> readFileBytes(const std::string& path, std::uint64_t maxBytes = UINT64_MAX);

/// The size [bytes] of a regular file, looked at without opening it; throws std::runtime_error
/// "PATH: not a regular file (a FIFO)" (a folder, a device, ...) or "PATH: cannot open (reason)".
/// For readers that open a file with another library: call it first, so a FIFO never blocks them.
std::uint64_t regularFileSize(const std::string& path);

}  // namespace gseg::io
