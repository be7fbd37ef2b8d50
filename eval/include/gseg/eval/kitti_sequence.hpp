#pragma once
/// \file kitti_sequence.hpp
/// The scans of a KITTI sequence folder (`velodyne/NNNNNN.bin`, labels in `labels/NNNNNN.label`),
/// listed once for every tool that reads a sequence: gseg eval, gseg eval-map (map_score.hpp) and
/// kitti2rawlog. Each caller keeps its own rule for names that are not frame numbers and its own
/// messages; the velodyne poses of the frames are gseg::map::kittiToVelodyneFrame (gseg/map/poses.hpp).

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace gseg::eval {

/// One scan of a sequence.
struct KittiScan {
    std::string name;   ///< the file name without ".bin", e.g. "000042"
    std::string scan;   ///< SEQUENCE/velodyne/NAME.bin
    std::string label;  ///< SEQUENCE/labels/NAME.label (it may not exist)
};

/// The frame number a scan's name stands for (the line of poses.txt and times.txt it uses): the
/// name read as a decimal number when it is 1 to `maxDigits` digits (at most 18), else nullopt.
std::optional<std::size_t> kittiFrameNumber(const std::string& name, std::size_t maxDigits = 18);

/// Every scan (`*.bin`) of SEQUENCE/velodyne, sorted by name (frame order for KITTI's zero-padded
/// names). Throws std::runtime_error "SEQUENCE/velodyne: cannot list the scans (why)" when the
/// folder cannot be listed (missing, a symbolic link loop, no permission).
std::vector<KittiScan> listKittiScans(const std::string& sequenceDir);

}  // namespace gseg::eval
