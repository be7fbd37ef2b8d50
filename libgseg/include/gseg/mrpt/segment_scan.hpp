#pragma once
/// \file segment_scan.hpp
/// The one height policy: segmenting real scans with a loaded configuration, the sensor height
/// fixed (`distToGround: 1.73`) or estimated per scan (`distToGround: auto`). Every tool and route
/// (gseg segment | eval | bench, rawlog-gseg, gseg::GroundFilter, rawlog-octomap, the
/// observations2map plugin) segments through ScanSegmenter, so they all decide alike.
///
/// The rule with `distToGround: auto`: each scan is estimated on its own
/// (gseg::estimateSensorHeight(), a mounting tilt levelled out, see AutoHeightSegmenter); a scan
/// that gives no estimate is segmented with the configured fallback height (Params::distToGround)
/// and says so in its HeightDecision (Source::Fallback, with the estimator's reason). A scan never
/// borrows an earlier scan's estimate: the labels of a scan depend on that scan alone, so they are
/// the same in any order, on any thread and any MPI rank, and in a stream or alone.
///
/// Points with NaN or infinite coordinates (a driver's "no return", the holes of an organised
/// cloud) are labelled non-ground and counted by the core.

#include <gseg/ground_segmenter.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/point_cloud.hpp>
#include <gseg/sensor_height.hpp>

#include <cmath>
#include <cstddef>
#include <string>

namespace gseg::mrpt {

/// One segmented scan, with the height decision that made it.
struct ScanSegmentation {
    /// One label per input point (non-finite points 0, counted in result.numNonFinite).
    gseg::Result result;
    double distToGround = 0;             ///< [m] the sensor height used
    bool distToGroundEstimated = false;  ///< `distToGround: auto` and this scan gave an estimate
    HeightDecision height;               ///< with `distToGround: auto`: what was used and why
    /// With a fixed distToGround, where the height was checked (HeightCheck): the scan's own
    /// estimate contradicts it (gseg::checkDistToGround()); "" otherwise.
    std::string heightWarning;
    bool autoHeight = false;             ///< the configuration said `distToGround: auto`

    /// `distToGround: auto` and this scan gave no estimate: the fallback height was used.
    bool heightFallback() const { return autoHeight && !distToGroundEstimated; }
};

/// The ground / obstacle split of a segmented scan, the one rule every output follows: calls
/// `f(i, ground)` for each point i of `cloud` (in input order) that goes into one of the two
/// classes, `ground` its label; points with a NaN or infinite coordinate and reflections below the
/// ground (Result::belowGround) go into neither.
template <class F>
void forEachSplitPoint(const PointCloudView& cloud, const gseg::Result& result, F&& f) {
    std::size_t next = 0;  // into result.belowGround (ascending)
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (next < result.belowGround.size() && result.belowGround[next] == i) {
            ++next;
            continue;
        }
        const float* p = cloud.point(i);
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
        f(i, result.labels[i] != 0);
    }
}

/// The sensor height of a tool's configuration and where it came from, one line for the tool's
/// summary. `configPath`: the file given (-c), "" for none: then the configuration is
/// defaultConfig(), the one default of every route (`distToGround: auto`). E.g.
/// "distToGround: auto, estimated per scan (fallback 1.723 m) [the default: no configuration file]",
/// "distToGround: 1.723 m, fixed [config/kitti_hdl64.yaml]".
std::string heightSummary(const LoadedConfig& config, const std::string& configPath);
/// The bracketed part of heightSummary(): "[FILE]", or "[the default: no configuration file]".
std::string configOrigin(const std::string& configPath);

/// When a fixed distToGround is checked against the scan (costs about one segmentation).
enum class HeightCheck {
    FirstScan,  ///< the first scan with points this segmenter sees (a stream read in order)
    Now,        ///< this scan (the first scan of a stream whose scans are shared out among workers)
    Never,
};

/// Segments scans with one configuration. One object per stream and thread; scans are independent
/// of each other (the only state is the FirstScan check).
class ScanSegmenter {
public:
    explicit ScanSegmenter(const LoadedConfig& config);

    /// Labels every point of `cloud` (levelled frame, sensor at the origin). A scan without finite
    /// points gets all labels 0, an empty one no labels. Never refuses a scan for its height.
    ScanSegmentation segment(const PointCloudView& cloud, bool keepCellDiagnostics = false,
                             HeightCheck check = HeightCheck::FirstScan);

    const LoadedConfig& config() const { return config_; }

private:
    LoadedConfig config_;
    GroundSegmenter fixed_;
    AutoHeightSegmenter auto_;
    bool heightChecked_ = false;
};

}  // namespace gseg::mrpt
