#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/observation_points.hpp>
#include <gseg/mrpt/rawlog_io.hpp>
#include <gseg/mrpt/rawlog_segmenter.hpp>
#include <gseg/ordered_pipeline.hpp>
#include <gseg/mrpt/scan_parts.hpp>

#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CSensoryFrame.h>

#include <algorithm>
#include <chrono>
#include <functional>

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

/// One input entry and what of it is segmented.
struct RawlogSegmenter::Item {
    std::size_t entry = 0;
    std::shared_ptr<::mrpt::serialization::CSerializable> object;  ///< the entry as read
    std::shared_ptr<::mrpt::obs::CSensoryFrame> frame;  ///< sensory-frame layout (null: an observation or another object)
    std::vector<int> partTask;               ///< per observation of `frame`: its index in `tasks` (-1: passed through)
    /// The scans to segment, in order: of `frame`, or `object` itself (observation layout; empty:
    /// it passes through).
    std::vector<::mrpt::obs::CObservation::Ptr> tasks;
};

/// One scan segmented (or why not).
struct RawlogSegmenter::Segmented {
    gseg::GroundFilter::Output out;
    std::string skipped;  ///< why it could not be segmented ("" if it was)
    double ms = 0;
    bool withDrive = false;
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

void RawlogSegmenter::plan(std::size_t entry, const std::shared_ptr<::mrpt::serialization::CSerializable>& object,
                           std::vector<Item>& ready) {
    ++read_.entries;
    const auto obs = std::dynamic_pointer_cast<::mrpt::obs::CObservation>(object);
    const auto count = [this](const ::mrpt::obs::CObservation* o) {
        if (o && isLidarObservation(*o) && !isSegmentedHalf(*o)) ++read_.lidarScans[o->sensorLabel];
        if (o && isSegmentedHalf(*o)) ++read_.segmentedHalves;
    };
    count(obs.get());
    if (held_) {  // the held scan: its pair follows (passed through), or it is segmented
        Item held = std::move(*held_);
        held_.reset();
        if (obs && isGroundHalfOf(*obs, *held.tasks.front())) {
            ++read_.alreadySplit;
            held.tasks.clear();
        }
        ready.push_back(std::move(held));
    }
    Item item;
    item.entry = entry, item.object = object;
    if (obs && wanted(*obs)) {
        item.tasks = {obs};
        held_ = std::make_unique<Item>(std::move(item));
        return;
    }
    if (auto sf = std::dynamic_pointer_cast<::mrpt::obs::CSensoryFrame>(object)) {
        for (const auto& o : *sf) {
            count(o.get());
            const bool split = o && std::any_of(sf->begin(), sf->end(), [&](const auto& h) { return h && isGroundHalfOf(*h, *o); });
            if (!o || !wanted(*o) || split) {
                read_.alreadySplit += o && wanted(*o) ? 1 : 0;
                item.partTask.push_back(-1);
                continue;
            }
            item.partTask.push_back(int(item.tasks.size()));
            item.tasks.push_back(o);
        }
        item.frame = std::move(sf);
    }
    ready.push_back(std::move(item));
}

std::vector<RawlogSegmenter::Segmented> RawlogSegmenter::segment(gseg::GroundFilter& filter, const RawlogSegmenterOptions& options,
                                                                 const Item& item) {
    std::vector<Segmented> out(item.tasks.size());
    for (std::size_t i = 0; i < item.tasks.size(); ++i) {
        const ::mrpt::obs::CObservation& obs = *item.tasks[i];
        gseg::io::setActivity("segmenting entry " + std::to_string(item.entry) + " ('" + obs.sensorLabel + "')");
        Segmented& s = out[i];
        const auto start = std::chrono::steady_clock::now();
        try {
            const std::optional<::mrpt::poses::CPose3D> pose = options.poseOf ? options.poseOf(item.entry, obs.sensorLabel) : std::nullopt;
            s.out = pose ? filter.filter(obs, *pose) : filter.filter(obs);
            s.withDrive = pose.has_value();
        } catch (const std::exception& e) {  // this scan cannot be segmented: passed through, said why
            s.skipped = errorReason(e);
        }
        s.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    }
    return out;
}

std::vector<::mrpt::obs::CObservation::Ptr> RawlogSegmenter::outputOf(const ::mrpt::obs::CObservation::Ptr& obs, std::size_t entry,
                                                                     Segmented& s) {
    ScanReport report;
    report.entry = entry;
    report.label = obs->sensorLabel;
    if (!s.skipped.empty()) {
        report.skipped = s.skipped;
        totals_.skipped.push_back(report);
        if (onScan_) onScan_(report);
        return {obs};
    }
    const gseg::GroundFilter::Output& o = s.out;
    report.withDrive = s.withDrive;
    report.ms = s.ms;
    report.points = o.result.labels.size();
    report.ground = o.result.numGround;
    report.nonFinite = o.result.numNonFinite;
    report.driveRelabelled = o.driveRelabelled;
    report.driveDropped = o.driveDropped;
    totals_.withDrive += report.withDrive ? 1 : 0;
    totals_.driveRelabelled += report.driveRelabelled;
    totals_.driveDropped += report.driveDropped;
    report.distToGround = o.distToGround;
    report.distToGroundEstimated = o.distToGroundEstimated;
    // The height check is the first scan's with points (each worker's filter checks its own first).
    if (!heightChecked_) report.heightWarning = o.heightWarning;
    heightChecked_ = heightChecked_ || report.nonFinite < report.points;
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

void RawlogSegmenter::emitItem(const Item& item, std::vector<Segmented>& segmented) {
    if (!item.frame && item.tasks.empty()) {  // passed through
        emit_(*item.object);
        return;
    }
    if (!item.frame) {  // an observation: itself and its halves
        for (const auto& o : outputOf(item.tasks.front(), item.entry, segmented.front())) emit_(*o);
        return;
    }
    ::mrpt::obs::CSensoryFrame result;
    std::size_t part = 0;
    for (const auto& o : *item.frame) {
        const int task = item.partTask[part++];
        if (task < 0) {
            result.insert(o);
            continue;
        }
        for (const auto& p : outputOf(o, item.entry, segmented[std::size_t(task)])) result.insert(p);
    }
    emit_(result);
}

void RawlogSegmenter::push(std::size_t entry, const std::shared_ptr<::mrpt::serialization::CSerializable>& object) {
    std::vector<Item> ready;
    plan(entry, object, ready);
    for (const Item& item : ready) {
        std::vector<Segmented> s = segment(filter_, options_, item);
        emitItem(item, s);
    }
}

void RawlogSegmenter::finish() {
    if (!held_) return;
    const std::unique_ptr<Item> held = std::move(held_);
    std::vector<Segmented> s = segment(filter_, options_, *held);
    emitItem(*held, s);
}

void RawlogSegmenter::run(RawlogReader& reader, unsigned workers) {
    if (options_.poseOf && !options_.driveModel) workers = 1;  // a stream's causal model: scans in order
    if (workers <= 1) {
        while (const auto object = reader.next()) push(reader.index(), object);
        finish();
        return;
    }
    // Worker 0 is this segmenter's filter; the others are alike (the same configuration and model).
    std::vector<std::unique_ptr<gseg::GroundFilter>> extra;
    std::vector<gseg::GroundFilter*> filters{&filter_};
    for (unsigned w = 1; w < workers; ++w) {
        extra.push_back(std::make_unique<gseg::GroundFilter>(filter_.config(), options_.frame));
        if (options_.driveModel) extra.back()->useDriveModel(options_.driveModel);
        filters.push_back(extra.back().get());
    }
    std::vector<Item> ready;
    std::size_t next = 0;  // of `ready`
    bool ended = false;
    const std::function<bool(Item&)> produce = [&](Item& item) {
        while (next == ready.size() && !ended) {
            ready.clear(), next = 0;
            if (const auto object = reader.next()) {
                plan(reader.index(), object, ready);
            } else {
                ended = true;
                if (held_) ready.push_back(std::move(*held_)), held_.reset();
            }
        }
        if (next == ready.size()) return false;
        item = std::move(ready[next++]);
        return true;
    };
    struct Done {
        Item item;
        std::vector<Segmented> segmented;
    };
    const std::function<Done(unsigned, Item&)> work = [&](unsigned worker, Item& item) {
        Done d;
        d.segmented = segment(*filters[worker], options_, item);
        d.item = std::move(item);
        return d;
    };
    const std::function<void(std::size_t, Done&)> consume = [&](std::size_t, Done& d) { emitItem(d.item, d.segmented); };
    gseg::PipelineOptions pipeline;
    pipeline.workers = workers;
    pipeline.capacity = 2 * std::size_t(workers) + 2;
    gseg::runOrdered<Item, Done>(produce, work, consume, pipeline);
}

RawlogTotals RawlogSegmenter::totals() const {
    RawlogTotals t = totals_;
    t.entries = read_.entries, t.lidarScans = read_.lidarScans, t.segmentedHalves = read_.segmentedHalves;
    t.alreadySplit = read_.alreadySplit;
    return t;
}

}  // namespace gseg::mrpt
