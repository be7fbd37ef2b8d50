#pragma once
// rawlog-octomap over MPI (#12): the per-scan work of ranks 1..N-1 as more workers of rank 0's
// pipeline. Rank 0 reads the rawlog and integrates the scans in scan order (runOrdered, as in
// one process); each worker thread of another rank is one more worker there: rank 0 sends it a
// scan (the observations and the pose, as bytes), it segments and ray-casts the scan and sends the
// ScanUpdate back. A scan goes to whichever worker is free, so fast and slow ranks share the work
// by themselves. At most the pipeline's capacity of scans is in flight; a worker's error comes
// back as the scan's error (named), never as a hang.
//
// The voxels are shared (#35): ranks 0..3 each hold the bricks gseg::map::voxelOwner() gives them
// (2 ranks: half each) and apply their part of every scan's update, in scan order, on a thread of
// their own; the worker that cast a scan sends each holder its part (VoxelHolder), a rank's own
// part stays there. Before writing, rank 0 merges the other holders' voxels. Every voxel sees the
// same updates in the same order as in one process, so the maps are the same bytes.

#include "rawlog_octomap.hpp"

#include "common/ranks.hpp"

#include <string>
#include <utility>
#include <vector>

namespace rawlog_octomap {

/// The bytes between the ranks are gseg/map/scan_message.hpp's.

/// Rank 0's side: one slot per worker thread of every other rank.
class RemoteWorkers {
public:
    /// Learns how many worker threads each other rank runs (one process: none).
    explicit RemoteWorkers(gseg::tools::Ranks& ranks);
    /// Tells every remote worker that there is no more work.
    ~RemoteWorkers();
    RemoteWorkers(const RemoteWorkers&) = delete;
    RemoteWorkers& operator=(const RemoteWorkers&) = delete;

    unsigned count() const { return unsigned(slots_.size()); }
    int processes() const { return ranks_.size(); }
    /// Has remote worker `slot` (< count()) do the scan; blocks (sleeping) until its result is back.
    /// Throws std::runtime_error naming the scan if it failed there.
    ScanResult operator()(unsigned slot, const ScanJob& job);

    /// Ranks holding voxels: min(processes, 4) (gseg::map::voxelOwner()).
    int holders() const;
    /// On a worker thread of rank 0, each scan's result (BuildOptions::worked): sends the other
    /// holders their part of its voxels (but the rank that cast it, which kept its own) and drops
    /// them from `r`.
    void route(const ScanJob& job, ScanResult& r);
    /// After the last scan (`scans` of them, skipped ones included): has every other holder apply
    /// its last parts and merges its voxels into `builder`'s map. Throws std::runtime_error with
    /// a holder's error. Returns the bricks each other holder had (ranks 1, 2, ...).
    std::vector<std::size_t> mergeVoxels(gseg::map::MapBuilder& builder, std::size_t scans);

private:
    gseg::tools::Ranks& ranks_;
    std::vector<std::pair<int, int>> slots_;  ///< (rank, its worker thread)
    bool merged_ = false;  ///< mergeVoxels() done (else the destructor tells the holders to stop)
};

/// Ranks 1..N-1: `--threads` worker threads (at least one) serving rank 0 until it says stop.
/// A setup failure (say, a config file missing on this machine) is sent back as the error of each
/// scan asked for, naming the scan and the rank.
void serveScans(gseg::tools::Ranks& ranks, const Cli& cli);

}  // namespace rawlog_octomap
