#pragma once
/// \file map_builder.hpp
/// The map builder: the per-scan work of map building and its ordered integration, the one
/// implementation behind every route (rawlog-octomap in one process or under MPI, and the
/// observations2map plugin, gseg_maps::CTraversabilityOctoMap).
///
/// One scan, start to end: ScanStream (scan_stream.hpp) assembles it with its pose (a ScanJob);
/// a ScanWorker segments it with the configured height policy (gseg::mrpt::ScanSegmenter), or
/// takes its `_ground` / `_obstacles` pair as it is, moves it into the world frame
/// (world_scan.hpp) and ray-casts it into a ScanUpdate (scan_update.hpp), independent of the map
/// and of every other scan (a ScanResult, a plain value that can travel between processes); the
/// MapBuilder applies the results to the TraversabilityMap strictly in scan order (gseg::runOrdered(),
/// gseg/ordered_pipeline.hpp). So the maps do not depend on the number of threads or processes.

#include <gseg/map/scan_stream.hpp>
#include <gseg/map/scan_update.hpp>
#include <gseg/map/traversability_map.hpp>
#include <gseg/map/world_scan.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/segment_scan.hpp>

#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace gseg::map {

/// Seconds per phase of a run (the per-scan work summed over threads).
struct PhaseTimes {
    double read = 0, segmentation = 0, transform = 0, rayCasting = 0, mapUpdate = 0, writing = 0;
    PhaseTimes& operator+=(const ScanTimes& scan);  ///< adds one scan's work
};

/// What the work gives for one scan.
struct ScanResult {
    ScanUpdate update;
    ScanTimes times;
    std::string skipped;    ///< why the scan could not be used ("" when it was)
    std::string describe;   ///< the scan, for messages
    bool presegmented = false;
    double fraction = 0;    ///< of the rawlog read (progress)
    ScanNotes notes;              ///< the WorldScan's (heightWarning: checked on scan 0 only)
    int rank = 0;                 ///< the process that did the work (MPI rank; 0 in one process)
};

/// One scan's observations, borrowed: the raw scan, or one or both parts of its pair.
struct ScanParts {
    const ::mrpt::obs::CObservation* raw = nullptr;
    const ::mrpt::obs::CObservation* ground = nullptr;
    const ::mrpt::obs::CObservation* obstacles = nullptr;
};

/// The per-scan work, independent of the map. One ScanWorker per thread (each has its own segmenter).
class ScanWorker {
public:
    ScanWorker(const gseg::mrpt::LoadedConfig& config, const TraversabilityOptions& options);
    /// A scan that cannot be segmented (no points) comes back skipped with the reason; the height
    /// follows gseg::mrpt::ScanSegmenter's rule (with `distToGround: auto` a scan without an
    /// estimate uses the configured height, never another scan's), and a fixed height is checked
    /// against scan 0; a sensor outside the map's extent or a non-finite pose throws
    /// std::runtime_error naming the scan.
    ScanResult operator()(const ScanJob& job);
    /// The same for observations held elsewhere; `describe` names the scan in messages.
    ScanResult operator()(const ScanParts& parts, const ::mrpt::poses::CPose3D& robotPose, const std::string& describe,
                          gseg::mrpt::HeightCheck check = gseg::mrpt::HeightCheck::Never);

private:
    gseg::mrpt::ScanSegmenter segmenter_;
    TraversabilityOptions options_;
};

/// What the ordered integration counted.
struct BuildTally {
    PhaseTimes times;              ///< of the work (all workers) and of the map updates
    std::size_t presegmented = 0;  ///< scans taken from a _ground/_obstacles pair
    std::size_t reflections = 0;   ///< points left out of both maps: far below the ground
    std::vector<std::string> heightFallbacks;  ///< distToGround: auto found no estimate: "scan k (...): what was used"
    std::vector<std::string> skipped;          ///< "scan k (...): reason"
    std::vector<std::size_t> scansByRank;      ///< scans worked on by each MPI rank (ScanResult::rank)
};

/// How MapBuilder::run() shares the work out.
struct BuildOptions {
    unsigned threads = 0;  ///< local worker threads (0 and no remote workers: everything on the calling thread)
    /// More workers elsewhere (e.g. the other MPI ranks' threads): `remoteWork(slot, job)` with
    /// slot < remoteWorkers does a scan there and returns its result (blocking).
    unsigned remoteWorkers = 0;
    std::function<ScanResult(unsigned slot, const ScanJob& job)> remoteWork;
    std::size_t ranks = 1;  ///< processes taking part (the size of BuildTally::scansByRank)
    /// Processes sharing the voxels (TraversabilityMap::shareVoxels(); 1: this map holds them
    /// all): this map holds process 0's and the caller sends the others theirs (`worked`) and
    /// merges them back (MapBuilder::mergeVoxels()) before the map is written.
    int voxelRanks = 1;
    /// Called on the worker's thread with each scan's result (local or remote) before it is
    /// integrated: e.g. sends other processes their voxels (takeVoxels()).
    std::function<void(const ScanJob& job, ScanResult& result)> worked;
    /// Called on the integrating thread after each scan, in scan order (k = 0, 1, ...), skipped
    /// scans included: progress and messages.
    std::function<void(std::size_t k, const ScanResult& result)> onScan;
};

/// An allocation failed while building: what() says what was being done and the options memory
/// follows ("out of memory while segmenting and ray casting scan 5 (...) (at --resolution 0.01 m,
/// --max-range 50 m); nothing written": gseg::map::outOfMemoryMessage()).
struct OutOfMemory : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// Builds a TraversabilityMap scan by scan: the ordered integration of ScanWorker results.
class MapBuilder {
public:
    /// Throws std::invalid_argument on invalid options.
    MapBuilder(const gseg::mrpt::LoadedConfig& config, const TraversabilityOptions& options);

    /// The whole stream: scans read on the calling thread, worked on by `options.threads` local
    /// workers and the remote ones, integrated in scan order with at most 2 N + 2 scans in flight
    /// (N workers). An error of any scan is rethrown once every thread has ended (that of the
    /// earliest scan); the scans before it are integrated.
    /// An allocation failure throws OutOfMemory naming the scan and the phase (reading, segmenting
    /// and ray casting, adding to the maps).
    void run(ScanStream& stream, const BuildOptions& options);
    /// The scans run() holds at once with these options (read, being worked on, waiting to be integrated).
    static std::size_t inFlight(const BuildOptions& options);
    /// Integrates the next scan's result (results in scan order): applies its update or, if it was
    /// skipped, counts it.
    void integrate(const ScanResult& result);
    /// One observation, worked on and integrated here (the plugin's route): a 3D LiDAR scan, or
    /// one part of a rawlog-gseg pair (`_ground` / `_obstacles`, used as it is). False for other
    /// observation kinds and for a scan that was skipped (its reason in tally().skipped). An
    /// allocation failure throws OutOfMemory naming the observation.
    bool insert(const ::mrpt::obs::CObservation& obs, const ::mrpt::poses::CPose3D& robotPose);
    /// Forgets every scan (the same options and configuration).
    void clear();

    const TraversabilityMap& map() const { return map_; }
    /// After run() with BuildOptions::voxelRanks > 1: another process's voxels (TraversabilityMap::mergeVoxels()).
    void mergeVoxels(const std::string& bytes) { map_.mergeVoxels(bytes); }
    const BuildTally& tally() const { return tally_; }
    const gseg::mrpt::LoadedConfig& config() const { return config_; }

private:
    /// `count` ScanWorkers for run(), and as many threads for the maps' updates.
    void startWorkers(unsigned count);

    gseg::mrpt::LoadedConfig config_;
    TraversabilityMap map_;
    BuildTally tally_;
    std::vector<ScanWorker> workers_;  ///< of run() / insert(), one per local thread
    std::size_t inserted_ = 0;         ///< observations given to insert()
};

}  // namespace gseg::map
