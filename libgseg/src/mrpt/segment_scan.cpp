#include <gseg/mrpt/segment_scan.hpp>

namespace gseg::mrpt {

ScanSegmenter::ScanSegmenter(const LoadedConfig& config)
    : config_(config), fixed_(config.params), auto_(config.params, config.sensorHeight) {}

ScanSegmentation ScanSegmenter::segment(const PointCloudView& cloud, bool keepCellDiagnostics) {
    ScanSegmentation out;
    out.distToGround = config_.params.distToGround;
    if (cloud.empty()) return out;  // nothing to label
    if (config_.distToGroundAuto) {
        out.result = auto_.segment(cloud, keepCellDiagnostics);
        out.height = auto_.lastDecision();
        out.distToGround = out.height.height;
        out.distToGroundEstimated = out.height.source == HeightDecision::Source::Estimated;
    } else {
        out.result = fixed_.segment(cloud, keepCellDiagnostics);
        out.distToGround = config_.params.distToGround;
        if (!heightChecked_ && out.result.numNonFinite < cloud.size()) {
            heightChecked_ = true;
            out.heightWarning = checkDistToGround(cloud, config_.params.distToGround, config_.params.seedHeightTolerance, config_.sensorHeight);
        }
    }
    out.nonFinitePoints = out.result.numNonFinite;
    return out;
}

}  // namespace gseg::mrpt
