#pragma once
/// \file scan_source.hpp
/// One scan from a file: a KITTI `.bin`, a PLY file, or a LiDAR observation of an MRPT rawlog.

#include <string>
#include <vector>

namespace gseg::mrpt {

/// A scan ready for GroundSegmenter: 4 floats per point (x, y, z, intensity). Rawlog scans are in
/// the levelled frame (see observation_points.hpp); files are taken as they are.
struct Scan {
    std::vector<float> xyzi;
    std::string description;  ///< what was read, e.g. "rawlog entry 3: CObservationVelodyneScan 'VELODYNE1'"
    std::size_t size() const { return xyzi.size() / 4; }
};

/// Reads `path`: `.bin` (KITTI), `.ply`, or a rawlog (`.rawlog`, `.rawlog.gz`, `.gz`). For a
/// rawlog, `index` picks the index-th LiDAR observation (0-based, counting observations inside
/// sensory frames too); -1 means the first. Throws std::runtime_error with a clear message on a
/// missing/bad file, no LiDAR observation, or an index past the last one.
Scan loadScan(const std::string& path, int index = -1);

}  // namespace gseg::mrpt
