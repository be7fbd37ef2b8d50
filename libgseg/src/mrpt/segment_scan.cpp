#include <gseg/mrpt/segment_scan.hpp>

#include <cstdio>
#include <utility>

namespace gseg::mrpt {

ScanSegmenter::ScanSegmenter(const LoadedConfig& config)
    : config_(config), fixed_(config.params), auto_(config.params, config.sensorHeight) {}

ScanSegmentation ScanSegmenter::segment(const PointCloudView& cloud, bool keepCellDiagnostics, HeightCheck check) {
    ScanSegmentation out;
    out.autoHeight = config_.distToGroundAuto;
    out.distToGround = config_.params.distToGround;
    if (cloud.empty()) return out;  // nothing to label
    if (config_.distToGroundAuto) {
        // The rule: this scan's own estimate or the fallback height, never an earlier scan's.
        AutoHeightResult a = auto_.segment(cloud, keepCellDiagnostics);
        out.result = std::move(a.result);
        out.height = std::move(a.decision);
        out.distToGround = out.height.height;
        out.distToGroundEstimated = out.height.source == HeightDecision::Source::Estimated;
    } else {
        out.result = fixed_.segment(cloud, keepCellDiagnostics);
        const bool hasPoints = out.result.numNonFinite < cloud.size();
        const bool checkNow = check == HeightCheck::Now || (check == HeightCheck::FirstScan && !heightChecked_);
        if (checkNow && hasPoints)
            out.heightWarning = checkDistToGround(cloud, config_.params.distToGround, config_.params.seedHeightTolerance,
                                                 config_.sensorHeight);
        heightChecked_ = heightChecked_ || hasPoints;
    }
    return out;
}

std::string heightSummary(const LoadedConfig& config, const std::string& configPath) {
    char height[120];
    if (config.distToGroundAuto)
        std::snprintf(height, sizeof height, "distToGround: auto, estimated per scan (fallback %.3f m)", config.params.distToGround);
    else
        std::snprintf(height, sizeof height, "distToGround: %.3f m, fixed", config.params.distToGround);
    return std::string(height) + " " + configOrigin(configPath);
}

std::string configOrigin(const std::string& configPath) {
    return "[" + (configPath.empty() ? std::string("the default: no configuration file") : configPath) + "]";
}

}  // namespace gseg::mrpt
