#include <gseg/mrpt/segment_scan.hpp>

#include <cmath>
#include <stdexcept>

namespace gseg::mrpt {
namespace {

bool finite(const float* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

}  // namespace

FinitePoints::FinitePoints(const PointCloudView& cloud) : inputSize_(cloud.size()), view_(cloud) {
    std::size_t first = 0;
    while (first < cloud.size() && finite(cloud.point(first))) ++first;
    if (first == cloud.size()) return;  // all finite: the input itself
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const float* p = cloud.point(i);
        if (!finite(p)) continue;
        xyz_.insert(xyz_.end(), p, p + 3);
        source_.push_back(std::uint32_t(i));
    }
    view_ = PointCloudView(xyz_.data(), source_.size());
}

std::vector<std::uint8_t> FinitePoints::toInputOrder(const std::vector<std::uint8_t>& finiteLabels) const {
    if (finiteLabels.size() != view_.size())
        throw std::invalid_argument("FinitePoints: " + std::to_string(finiteLabels.size()) + " labels for " +
                                    std::to_string(view_.size()) + " finite points");
    if (view_.size() == inputSize_) return finiteLabels;
    std::vector<std::uint8_t> out(inputSize_, 0);
    for (std::size_t k = 0; k < source_.size(); ++k) out[source_[k]] = finiteLabels[k];
    return out;
}

ScanSegmenter::ScanSegmenter(const LoadedConfig& config) : config_(config) { config_.params.validate(); }

Params ScanSegmenter::paramsFor(const PointCloudView& finitePoints, SensorHeightEstimate* estimate) const {
    Params params = config_.params;
    if (!config_.distToGroundAuto) return params;
    const SensorHeightEstimate h = estimateSensorHeight(finitePoints);
    if (estimate) *estimate = h;
    if (!h.valid)
        throw std::runtime_error("distToGround: auto found no ground level around the sensor (" +
                                 std::to_string(h.columns) + " usable columns); give the height in metres");
    params.distToGround = h.height;
    return params;
}

ScanSegmentation ScanSegmenter::segment(const PointCloudView& cloud, bool keepCellDiagnostics) {
    const FinitePoints finite(cloud);
    ScanSegmentation out;
    out.nonFinitePoints = finite.nonFinite();
    out.distToGround = config_.params.distToGround;
    if (finite.view().empty()) {  // nothing to segment: every point non-ground
        out.result.labels.assign(cloud.size(), 0);
        out.result.numNonGround = cloud.size();
        return out;
    }
    const Params params = paramsFor(finite.view(), &out.heightEstimate);
    out.distToGroundEstimated = config_.distToGroundAuto;
    out.distToGround = params.distToGround;
    if (!segmenter_ || segmenter_->params().distToGround != params.distToGround)
        segmenter_ = std::make_unique<GroundSegmenter>(params);
    out.result = segmenter_->segment(finite.view(), keepCellDiagnostics);
    out.result.labels = finite.toInputOrder(out.result.labels);
    out.result.numNonGround += out.nonFinitePoints;
    return out;
}

}  // namespace gseg::mrpt
