#pragma once
// rawlog-octomap: the command line, one map-building run (gseg::map::MapBuilder), and the
// benchmark against plain OctoMap. The per-scan work and the ordered integration are the map
// layer's (gseg/map/map_builder.hpp); the tool adds the command line, progress, the report and the
// MPI transport (remote_workers.hpp).

#include <gseg/map/map_builder.hpp>
#include <gseg/mrpt/config.hpp>

#include <optional>
#include <string>
#include <vector>

namespace rawlog_octomap {

using gseg::map::PhaseTimes;
using gseg::map::PoseConfig;
using gseg::map::ScanJob;
using gseg::map::ScanResult;
using gseg::map::ScanStream;
using gseg::map::ScanWorker;

struct Cli {
    std::string input, prefix, config;
    gseg::mrpt::LoadedConfig loaded = gseg::mrpt::defaultConfig();  ///< -c (or the default), loaded once per run
    PoseConfig poses;
    gseg::map::TraversabilityOptions options;
    unsigned threads = 0;  ///< worker threads (0: everything on one thread)
    bool rank0MapsOnly = false;  ///< under MPI, rank 0 works on no scan (it reads, maps and writes)
    int benchRounds = 0;   ///< --bench N
    bool overwrite = false;  ///< -w: replace map files that exist
    double maxMemory = 0;    ///< [bytes] --max-memory (0: the machine's available memory)
    double mpiTimeout = 0;   ///< [s] --mpi-timeout (gseg::tools::Ranks::setTimeout())
    gseg::map::MapOutputOptions outputs;  ///< --tiles, --tiled-above: the costmap and GeoTIFF of a big map as tiles
    /// Rank 0 under MPI: the CPUs of the ranks on its machine, idle while it writes (its writing
    /// threads may use them); empty otherwise.
    std::vector<int> machineCpus;
};

class RemoteWorkers;

/// What a run did.
struct RunReport {
    gseg::map::MapStats stats;
    gseg::map::BuildTally tally;  ///< the builder's counts; tally.times.writing added by the tool
    double wallSeconds = 0;
    double peakMbBeforeWriting = 0, peakMb = 0;  ///< [MB] peak resident memory of the process (ru_maxrss)
    std::size_t rawWithPair = 0;   ///< raw scans not segmented again because their pair was there
    std::string height;  ///< the sensor height and where it came from (gseg::mrpt::heightSummary)
    std::vector<std::string> written;
    std::optional<Eigen::Vector3d> origin;  ///< world shift (--origin)
    std::string poseSource;                 ///< "the rawlog" or the pose file
    unsigned workers = 0;                   ///< worker threads, on every process
    std::vector<std::size_t> bricksByHolder;  ///< under MPI, the voxel bricks ranks 1, 2, ... held (rank 0: the rest)
};

/// Builds the maps of `cli.input` and writes them to `cli.prefix`; progress on stderr unless
/// `quiet` (or --quiet). `remote`: the worker threads of the other MPI ranks, used beside this process's
/// `cli.threads` (null: this process alone). Throws std::invalid_argument (bad usage) or
/// std::runtime_error (bad input, naming it).
RunReport buildMaps(const Cli& cli, bool quiet = false, RemoteWorkers* remote = nullptr);

/// --bench: alternates plain OctoMap and rawlog-octomap on the same rawlog, prints both timings.
void runBench(const Cli& cli);

}  // namespace rawlog_octomap
