#pragma once
// The per-scan work of rawlog-octomap, independent of the map: segmentation (or the pre-segmented
// pair), transformation into the world, ray casting into a ScanUpdate. One ScanWorker per thread.

#include "scan_stream.hpp"

#include <gseg/ground_segmenter.hpp>
#include <gseg/sensor_height.hpp>
#include <gseg/map/scan_update.hpp>
#include <gseg/mrpt/config.hpp>

#include <memory>
#include <string>

namespace rawlog_octomap {

/// Seconds per phase (summed over threads when added up).
struct PhaseTimes {
    double read = 0, segmentation = 0, transform = 0, rayCasting = 0, mapUpdate = 0, writing = 0;
    PhaseTimes& operator+=(const PhaseTimes& o);
};

/// What the work gives for one scan.
struct ScanResult {
    gseg::map::ScanUpdate update;
    PhaseTimes times;
    std::string skipped;    ///< why the scan could not be used ("" when it was)
    std::string describe;   ///< the scan, for messages
    bool presegmented = false;
    double fraction = 0;    ///< of the rawlog read (progress)
    std::size_t reflections = 0;  ///< points left out: far below the ground (Result::belowGround)
    std::string heightNote;       ///< distToGround: auto found no estimate: what was used instead
    std::string heightWarning;    ///< the first scan contradicts the fixed distToGround (checked on scan 0 only)
    int rank = 0;                 ///< the process that did the work (MPI rank; 0 in one process)
};

class ScanWorker {
public:
    ScanWorker(const gseg::mrpt::LoadedConfig& config, const gseg::map::TraversabilityOptions& options);
    /// A scan that cannot be segmented (no points) comes back skipped with the reason; with
    /// `distToGround: auto` a scan without an estimate uses the configured height (not the previous
    /// scan's: workers see scans in any order, and the maps must not depend on the thread count); a sensor outside the map's extent or a non-finite pose throws
    /// std::runtime_error naming the scan.
    ScanResult operator()(const ScanJob& job);

private:
    gseg::GroundSegmenter segmenter_;
    std::unique_ptr<gseg::AutoHeightSegmenter> autoHeight_;  // distToGround: auto
    gseg::map::TraversabilityOptions options_;
};

}  // namespace rawlog_octomap
