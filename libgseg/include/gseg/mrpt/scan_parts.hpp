#pragma once
/// \file scan_parts.hpp
/// The one naming rule of segmented scans: gseg splits the scan labelled `L` into the point clouds
/// `L_ground` and `L_obstacles` (gseg::GroundFilter, rawlog-gseg), and whatever reads them back
/// (rawlog-gseg not splitting twice, the map builder taking a pair as it is) recognises them by
/// that suffix.

#include <string>

namespace gseg::mrpt {

/// What an observation holds, by its sensor label.
enum class ScanPart { Raw, Ground, Obstacles };

inline constexpr const char* kGroundSuffix = "_ground";
inline constexpr const char* kObstaclesSuffix = "_obstacles";

/// Ground for `L_ground`, Obstacles for `L_obstacles`, Raw for anything else.
ScanPart scanPartOfLabel(const std::string& label);
/// `L` for `L_ground` and `L_obstacles`; other labels as they are.
std::string baseLabelOf(const std::string& label);
/// `base` + the part's suffix (`base` itself for Raw).
std::string partLabel(const std::string& base, ScanPart part);

}  // namespace gseg::mrpt
