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

/// The laser ring of each point of a KITTI velodyne scan, numbered from 0 in file order, found from
/// the order the points are stored in: ring by ring, each ring sweeping once round in azimuth
/// (counter-clockwise, atan2(y, x) rising). A new ring begins where the azimuth falls back by more
/// than half a turn, if the ring before holds more than `minRingPoints` points (the few points right
/// behind the sensor jitter across the wrap; an HDL-64E ring holds 1,000-2,200 points). A point
/// with a non-finite x or y, and the point after it, never begin a ring. `xyzi`: 4 floats per point (x, y, z, intensity).
std::vector<std::uint32_t> kittiRings(const float* xyzi, std::size_t points, std::size_t minRingPoints = 600);

/// The points of a sparser sensor's scan taken out of a KITTI scan: the indices, in file order, of
/// the points of every `ringStep`-th ring (rings 0, ringStep, 2 ringStep, ... of kittiRings()) whose
/// index in the file is a multiple of `pointStep` (every pointStep-th point along the rings).
/// 1 and 1 keep every point. Throws std::invalid_argument if a step is 0.
std::vector<std::size_t> kittiThinned(const float* xyzi, std::size_t points, unsigned ringStep, unsigned pointStep);

/// Thins a scan and its labels in place to the points kittiThinned() keeps (their order kept).
/// Throws std::invalid_argument if a step is 0 or there is not one label per point.
void thinKittiScan(std::vector<float>& xyzi, std::vector<std::uint32_t>& labels, unsigned ringStep, unsigned pointStep);

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
