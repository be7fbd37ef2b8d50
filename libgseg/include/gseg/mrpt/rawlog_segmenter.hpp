#pragma once
/// \file rawlog_segmenter.hpp
/// What rawlog-gseg does to a stream of rawlog entries: every LiDAR scan followed by its
/// `<label>_ground` and `<label>_obstacles` point clouds, every other entry passed through
/// unchanged and in order, in both rawlog layouts. One bad scan does not sink the run: a scan that
/// cannot be segmented is passed through unchanged, named and counted; its non-finite points are
/// labelled non-ground and counted. A scan that already has its pair (a rawlog-gseg output read
/// again) is passed through, and a `_ground` / `_obstacles` cloud is never split again.

#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/ground_filter.hpp>

#include <cstddef>
#include <functional>
#include <memory>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace mrpt::serialization {
class CSerializable;
}

namespace gseg::mrpt {

class RawlogReader;

/// Options of RawlogSegmenter (rawlog-gseg's command line).
struct RawlogSegmenterOptions {
    std::vector<std::string> sensors;  ///< segment only these sensorLabels (empty: every LiDAR observation)
    bool replace = false;              ///< drop the segmented scans, keep only their two halves
    gseg::GroundFilter::OutputFrame frame = gseg::GroundFilter::OutputFrame::Sensor;
    /// The drive's context (#31): the vehicle pose of the scan with this sensorLabel at this rawlog
    /// entry, where known. A scan with a pose is labelled by GroundFilter::filter(obs, pose): with
    /// `driveModel` (the whole drive's, offline) or, without one, the causal model of the scans
    /// before it. Empty: every scan alone.
    std::function<std::optional<::mrpt::poses::CPose3D>(std::size_t entry, const std::string& label)> poseOf;
    std::shared_ptr<const gseg::TerrainModel> driveModel;
};

/// What happened to one scan.
struct ScanReport {
    std::size_t entry = 0;     ///< index of the rawlog entry (a sensory frame holds several scans)
    std::string label;         ///< the scan's sensorLabel
    std::size_t points = 0;    ///< input points
    std::size_t ground = 0;    ///< points labelled ground
    std::size_t nonFinite = 0; ///< points with a NaN or infinite coordinate (labelled non-ground)
    double distToGround = 0;   ///< [m] sensor height used
    bool distToGroundEstimated = false;
    std::string heightWarning; ///< the first scan contradicts a fixed distToGround (GroundFilter::Output)
    double ms = 0;             ///< segmentation time
    std::size_t driveRelabelled = 0;  ///< points the drive's terrain model turned ground
    std::size_t driveDropped = 0;     ///< ground points it turned non-ground (the feet of what stands)
    bool withDrive = false;    ///< labelled with the drive's context (it had a pose)
    std::string skipped;       ///< why it could not be segmented ("" if it was)
};

/// Totals of a run.
struct RawlogTotals {
    std::size_t entries = 0;       ///< input entries seen
    std::size_t scans = 0;         ///< scans segmented
    std::size_t points = 0, ground = 0, nonFinite = 0;
    std::size_t withDrive = 0, driveRelabelled = 0, driveDropped = 0;  ///< scans labelled with the drive's context, points it turned ground, non-ground
    std::size_t alreadySplit = 0;  ///< scans passed through because their pair was already there
    double ms = 0;                 ///< segmentation time of all scans
    std::vector<ScanReport> skipped;  ///< scans that could not be segmented (passed through)
    std::map<std::string, std::size_t> lidarScans;  ///< LiDAR observations seen per sensorLabel (selected by `sensors` or not)
    std::size_t segmentedHalves = 0;  ///< `_ground` / `_obstacles` observations seen (a segmented rawlog's)
};

/// Turns input entries into output entries. Output order is input order; an observation-layout
/// scan is held until the next entry shows whether its pair follows, so call finish() at the end.
/// run() does the same to a whole rawlog with several scans segmented at once: the same output,
/// reports and totals for any number of workers.
class RawlogSegmenter {
public:
    using Emit = std::function<void(const ::mrpt::serialization::CSerializable&)>;
    using OnScan = std::function<void(const ScanReport&)>;

    /// `emit` receives the output entries; `onScan` (optional) each scan's report.
    RawlogSegmenter(const LoadedConfig& config, RawlogSegmenterOptions options, Emit emit, OnScan onScan = {});
    ~RawlogSegmenter();

    /// One input entry.
    void push(std::size_t entry, const std::shared_ptr<::mrpt::serialization::CSerializable>& object);
    /// Emits what is still held; call once after the last entry.
    void finish();
    /// Every entry of `reader` (then finish()), read on the calling thread while `workers` scans are
    /// segmented at once (gseg::runOrdered); `emit` and `onScan` are called in entry order, from one
    /// thread at a time. Scans labelled with a stream's causal model (`poseOf` without
    /// `driveModel`) are segmented one at a time, in order. Throws as RawlogReader::next(), after
    /// emitting every entry before the bad one.
    void run(RawlogReader& reader, unsigned workers);

    RawlogTotals totals() const;

private:
    struct Item;
    struct Segmented;
    bool wanted(const ::mrpt::obs::CObservation& obs) const;
    /// Input order: one entry read; the items it makes ready (the held scan, then this entry
    /// unless it is held) appended to `ready`.
    void plan(std::size_t entry, const std::shared_ptr<::mrpt::serialization::CSerializable>& object, std::vector<Item>& ready);
    /// Any worker: the item's scans segmented by `filter`.
    static std::vector<Segmented> segment(gseg::GroundFilter& filter, const RawlogSegmenterOptions& options, const Item& item);
    /// Input order: the item's reports, totals and output entries.
    void emitItem(const Item& item, std::vector<Segmented>& segmented);
    /// The entries that replace `obs`: itself (unless replaced) and its two halves, or itself alone.
    std::vector<std::shared_ptr<::mrpt::obs::CObservation>> outputOf(const std::shared_ptr<::mrpt::obs::CObservation>& obs,
                                                                     std::size_t entry, Segmented& s);

    RawlogSegmenterOptions options_;
    Emit emit_;
    OnScan onScan_;
    gseg::GroundFilter filter_;
    RawlogTotals totals_;  ///< emitItem()'s (scans, points, reports)
    RawlogTotals read_;    ///< plan()'s (entries, LiDAR observations, halves, already split)
    bool heightChecked_ = false;  ///< a scan with points was emitted (its height check is the run's)
    std::unique_ptr<Item> held_;
};

/// True for a `<label>_ground` or `<label>_obstacles` point cloud (a half made by gseg).
bool isSegmentedHalf(const ::mrpt::obs::CObservation& obs);

}  // namespace gseg::mrpt
