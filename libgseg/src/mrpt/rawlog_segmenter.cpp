#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/observation_points.hpp>
#include <gseg/mrpt/rawlog_segmenter.hpp>
#include <gseg/mrpt/scan_parts.hpp>

#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CSensoryFrame.h>

#include <algorithm>
#include <chrono>

namespace gseg::mrpt {
namespace {

// `half` is the `_ground` cloud gseg made from `scan`.
bool isGroundHalfOf(const ::mrpt::obs::CObservation& half, const ::mrpt::obs::CObservation& scan) {
    return dynamic_cast<const ::mrpt::obs::CObservationPointCloud*>(&half) && half.sensorLabel == partLabel(scan.sensorLabel, ScanPart::Ground) &&
           half.timestamp == scan.timestamp;
}

}  // namespace

bool isSegmentedHalf(const ::mrpt::obs::CObservation& obs) {
    return dynamic_cast<const ::mrpt::obs::CObservationPointCloud*>(&obs) &&
           scanPartOfLabel(obs.sensorLabel) != ScanPart::Raw;
}

struct RawlogSegmenter::Pending {
    std::size_t entry;
    ::mrpt::obs::CObservation::Ptr obs;
};

RawlogSegmenter::RawlogSegmenter(const LoadedConfig& config, RawlogSegmenterOptions options, Emit emit, OnScan onScan)
    : options_(std::move(options)), emit_(std::move(emit)), onScan_(std::move(onScan)), filter_(config, options_.frame) {
    if (options_.driveModel) filter_.useDriveModel(options_.driveModel);
}

RawlogSegmenter::~RawlogSegmenter() = default;

bool RawlogSegmenter::wanted(const ::mrpt::obs::CObservation& obs) const {
    return isLidarObservation(obs) && !isSegmentedHalf(obs) &&
           (options_.sensors.empty() ||
            std::find(options_.sensors.begin(), options_.sensors.end(), obs.sensorLabel) != options_.sensors.end());
}

std::vector<::mrpt::obs::CObservation::Ptr> RawlogSegmenter::process(const ::mrpt::obs::CObservation::Ptr& obs,
                                                                    std::size_t entry) {
    ScanReport report;
    report.entry = entry;
    report.label = obs->sensorLabel;
    gseg::io::setActivity("segmenting entry " + std::to_string(entry) + " ('" + obs->sensorLabel + "')");
    gseg::GroundFilter::Output o;
    const auto start = std::chrono::steady_clock::now();
    try {
        const std::optional<::mrpt::poses::CPose3D> pose = options_.poseOf ? options_.poseOf(entry, obs->sensorLabel) : std::nullopt;
        o = pose ? filter_.filter(*obs, *pose) : filter_.filter(*obs);
        report.withDrive = pose.has_value();
    } catch (const std::exception& e) {  // this scan cannot be segmented: pass it through, say why
        report.skipped = errorReason(e);
        totals_.skipped.push_back(report);
        if (onScan_) onScan_(report);
        return {obs};
    }
    report.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    report.points = o.result.labels.size();
    report.ground = o.result.numGround;
    report.nonFinite = o.nonFinitePoints;
    report.driveRelabelled = o.driveRelabelled;
    totals_.withDrive += report.withDrive ? 1 : 0;
    totals_.driveRelabelled += report.driveRelabelled;
    report.distToGround = o.distToGround;
    report.distToGroundEstimated = o.distToGroundEstimated;
    report.heightWarning = o.heightWarning;
    ++totals_.scans;
    totals_.points += report.points;
    totals_.ground += report.ground;
    totals_.nonFinite += report.nonFinite;
    totals_.ms += report.ms;
    if (onScan_) onScan_(report);
    std::vector<::mrpt::obs::CObservation::Ptr> out;
    if (!options_.replace) out.push_back(obs);
    out.push_back(o.ground);
    out.push_back(o.obstacles);
    return out;
}

void RawlogSegmenter::flushPending(const ::mrpt::obs::CObservation* next) {
    if (!pending_) return;
    const std::unique_ptr<Pending> p = std::move(pending_);
    if (next && isGroundHalfOf(*next, *p->obs)) {  // already split: its pair follows
        ++totals_.alreadySplit;
        emit_(*p->obs);
        return;
    }
    for (const auto& o : process(p->obs, p->entry)) emit_(*o);
}

void RawlogSegmenter::push(std::size_t entry, const std::shared_ptr<::mrpt::serialization::CSerializable>& object) {
    ++totals_.entries;
    const auto obs = std::dynamic_pointer_cast<::mrpt::obs::CObservation>(object);
    const auto count = [this](const ::mrpt::obs::CObservation* o) {
        if (o && isLidarObservation(*o) && !isSegmentedHalf(*o)) ++totals_.lidarScans[o->sensorLabel];
        if (o && isSegmentedHalf(*o)) ++totals_.segmentedHalves;
    };
    count(obs.get());
    flushPending(obs.get());
    if (obs && wanted(*obs)) {
        pending_ = std::make_unique<Pending>(Pending{entry, obs});
        return;
    }
    const auto sf = std::dynamic_pointer_cast<::mrpt::obs::CSensoryFrame>(object);
    if (!sf) {
        emit_(*object);
        return;
    }
    ::mrpt::obs::CSensoryFrame result;
    for (const auto& o : *sf) {
        count(o.get());
        const bool split = o && std::any_of(sf->begin(), sf->end(), [&](const auto& h) { return h && isGroundHalfOf(*h, *o); });
        if (!o || !wanted(*o) || split) {
            totals_.alreadySplit += o && wanted(*o) ? 1 : 0;
            result.insert(o);
            continue;
        }
        for (const auto& p : process(o, entry)) result.insert(p);
    }
    emit_(result);
}

void RawlogSegmenter::finish() { flushPending(nullptr); }

}  // namespace gseg::mrpt
