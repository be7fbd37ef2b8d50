#pragma once
// rawlog-octomap over MPI (#12): the per-scan work of ranks 1..N-1 as more workers of rank 0's
// pipeline. Rank 0 reads the rawlog and applies the map updates in scan order (runOrdered, as in
// one process); each worker thread of another rank is one more worker there: rank 0 sends it a
// scan (the observations and the pose, as bytes), it segments and ray-casts the scan and sends the
// ScanUpdate back. A scan goes to whichever worker is free, so fast and slow ranks share the work
// by themselves, and the maps are the same bytes as one process's: per-scan results do not depend
// on the map or on the worker, and only rank 0 touches the map. At most the pipeline's capacity of
// scans is in flight; a worker's error comes back as the scan's error (named), never as a hang.

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

private:
    gseg::tools::Ranks& ranks_;
    std::vector<std::pair<int, int>> slots_;  ///< (rank, its worker thread)
};

/// Ranks 1..N-1: `--threads` worker threads (at least one) serving rank 0 until it says stop.
/// A setup failure (say, a config file missing on this machine) is sent back as the error of each
/// scan asked for, naming the scan and the rank.
void serveScans(gseg::tools::Ranks& ranks, const Cli& cli);

}  // namespace rawlog_octomap
