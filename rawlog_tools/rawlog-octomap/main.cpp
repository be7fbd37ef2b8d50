// rawlog-octomap: traversability OctoMaps (ground / obstacles) from a rawlog of 3D LiDAR scans.
//
// One pass over the rawlog, streamed: the reader assembles each scan with its pose (see
// scan_stream.hpp), worker threads segment it (or take the `_ground` / `_obstacles` pair written
// by rawlog-gseg as it is), put it into the world frame and ray-cast it into a ScanUpdate, and one
// thread applies the updates to the maps strictly in scan order (gseg::runOrdered, in gseg::map::MapBuilder), so the
// maps do not depend on the number of threads. At most a few scans are in memory at a time.
// Under mpirun/srun the worker threads of the other ranks are more workers of the same pipeline,
// and ranks 0-3 each hold and update a share of the voxels, merged on rank 0 before writing
// (remote_workers.hpp): the maps are the same bytes as one process's.

#include "rawlog_octomap.hpp"
#include "remote_workers.hpp"

#include "common/cli.hpp"

#include <gseg/io/atomic_file.hpp>
#include <gseg/map/memory_policy.hpp>
#include <gseg/map/world_scan.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/segment_scan.hpp>
#include <gseg/progress.hpp>
#include <gseg/text.hpp>
#include <gseg/ordered_pipeline.hpp>

#include <chrono>
#include <cmath>
#include <deque>
#include <new>
#include <optional>
#include <malloc.h>
#include <sys/resource.h>
#include <cstdio>
#include <iostream>
#include <stdexcept>
#include <thread>

namespace rawlog_octomap {
namespace {

/// A number > 0 given as `flag` (gseg::parseNumber); throws std::invalid_argument naming `flag`.
double positiveNumber(const std::string& flag, const std::string& v) {
    const std::optional<double> d = gseg::parseNumber<double>(v);
    if (!d || !(*d > 0) || !std::isfinite(*d)) throw std::invalid_argument(flag + " needs a number > 0, got '" + v + "'");
    return *d;
}

/// A whole number from 0 to `max` given as `flag`; throws std::invalid_argument naming `flag`.
unsigned parseCount(const std::string& flag, const std::string& v, unsigned max) {
    const std::optional<long> n = gseg::parseNumber<long>(v);
    if (!n || *n < 0 || *n > long(max))
        throw std::invalid_argument(flag + " needs a whole number from 0 to " + std::to_string(max) + ", got '" + v + "'");
    return unsigned(*n);
}

/// Parses the command line into `c` (TCLAP, the same on every MPI rank; only `printing` prints).
/// Returns -1 to go on, else the exit code (0 after --help / --version, 2 on bad usage).
int parseCli(int argc, char** argv, bool printing, Cli& c) {
    const std::vector<std::string> files = gseg::map::TraversabilityMap::outputPaths("PREFIX");
    std::string fileList;
    for (std::size_t k = 0; k < files.size(); ++k) fileList += (k ? ", " : "") + files[k];
    gseg::tools::CommandLine line(
        "rawlog-octomap",
        "Traversability OctoMaps (ground / obstacles), the costmap a planner loads (PREFIX_costmap.pgm + .yaml, "
        "map_server format) and the 2.5D layers from a rawlog of 3D LiDAR scans. Writes " + std::to_string(files.size()) +
        " files: " + fileList + " (refused if one exists, unless -w). Scans are segmented with GSeg3D unless a _ground / _obstacles pair (rawlog-gseg) follows them. Under "
        "mpirun or srun rank 0 reads, merges and writes the maps, ranks 0-3 each update their share of the voxels, and every rank works on scans. Exit code: 0 done, 1 bad input, 2 bad "
        "usage, 3 maps written but scans skipped (named).",
        true, printing);
    TCLAP::CmdLine& cmd = line.cmd();
    TCLAP::ValueArg<std::string> input("i", "input", "input rawlog (plain or gzip)", true, "", "IN.rawlog", cmd);
    TCLAP::ValueArg<std::string> prefix("o", "output", "prefix of the " + std::to_string(files.size()) + " map files (listed above)", true, "", "PREFIX", cmd);
    TCLAP::ValueArg<std::string> poses("", "poses", "TUM trajectory (t x y z qx qy qz qw, vehicle pose, matched by time "
                                       "stamp) or KITTI poses (3x4 per scan, with calib.txt beside it or --calib); "
                                       "default: poses in the rawlog", false, "", "FILE", cmd);
    TCLAP::ValueArg<std::string> calib("", "calib", "KITTI calib.txt (Tr) for KITTI poses", false, "", "FILE", cmd);
    TCLAP::ValueArg<std::string> tolerance("", "pose-tolerance", "[s] largest time difference between a scan and its "
                                           "TUM pose (default 0.02)", false, "", "S", cmd);
    TCLAP::ValueArg<std::string> resolution("", "resolution", "[m] voxel edge, 0.01 to 10 (default 0.2)", false, "",
                                            "M", cmd);
    TCLAP::ValueArg<std::string> maxRange("", "max-range", "[m] ray length limit (default 50)", false, "", "M", cmd);
    TCLAP::ValueArg<std::string> clearance("", "clearance", "[m] obstacles higher than this above the ground do not "
                                           "block a cell (default 2)", false, "", "M", cmd);
    TCLAP::ValueArg<std::string> config("c", "config", "gseg parameters (YAML or INI, see config/)", false, "", "FILE",
                                        cmd);
    TCLAP::ValueArg<std::string> origin("", "origin", "'first': subtract the first sensor position (whole metres) from "
                                        "every position, for poses in UTM or other large coordinates (the maps span "
                                        "+-32768 voxels); or X,Y,Z", false, "", "first|X,Y,Z", cmd);
    TCLAP::ValueArg<std::string> threads("", "threads", "worker threads for segmentation and ray casting in each "
                                         "process (default: one per core this process may use; 0: none); under mpirun/srun every rank works "
                                         "with N threads, at least one (--threads 0: one rank per core)", false, "", "N",
                                         cmd);
    TCLAP::SwitchArg rank0MapsOnly("", "rank0-maps-only", "under mpirun/srun rank 0 reads, maps and writes but works on "
                                   "no scan (a rank 0 on a node of its own, or a slow disk)", cmd);
    TCLAP::ValueArg<std::string> maxMemory("", "max-memory", "refuse to start (exit 1) if the maps and ray casting are "
                                           "estimated to need more (from the first scan; MB, or 2G; default: the "
                                           "memory available, or ulimit -v / -d if lower)", false, "", "SIZE", cmd);
    TCLAP::SwitchArg tiles("", "tiles", "write the costmap as tiles (PREFIX_costmap_metadata.yaml naming each "
                           "PREFIX_costmap_X_Y.pgm + .yaml by its origin, Autoware's divided-map layout) and the layers as "
                           "one Cloud-Optimized GeoTIFF with overviews, whatever the map's size", cmd);
    TCLAP::ValueArg<std::string> tiledAbove("", "tiled-above", "[cells] write tiles (as --tiles) when the map is wider or "
                                            "higher than this (default 4096; below it one costmap and one GeoTIFF)",
                                            false, "", "N", cmd);
    line.addMpiTimeout();
    TCLAP::ValueArg<std::string> bench("", "bench", "time plain OctoMap (insertPointCloud, discretized) and "
                                       "rawlog-octomap alternately, N rounds each, on the same rawlog; maps go to "
                                       "PREFIX_bench*", false, "", "N", cmd);
    if (const int code = line.parse(argc, argv); code >= 0) return code;
    try {
        c.threads = gseg::usableCores();
        c.input = input.getValue(), c.prefix = prefix.getValue(), c.config = config.getValue();
        c.poses.poses = poses.getValue(), c.poses.calib = calib.getValue(), c.poses.origin = origin.getValue();
        auto number = [](TCLAP::ValueArg<std::string>& a, double& to) {
            if (a.isSet()) to = positiveNumber("--" + a.getName(), a.getValue());
        };
        number(tolerance, c.poses.poseTolerance);
        // The configuration (loaded once per run), its traversability options, then the command line's.
        try {
            c.loaded = gseg::mrpt::loadConfigOrDefault(c.config);
        } catch (const std::runtime_error& e) {
            if (printing) std::cerr << "rawlog-octomap: " << e.what() << "\n";
            return 1;
        }
        c.options = c.loaded.traversability;
        number(resolution, c.options.resolution);
        number(maxRange, c.options.maxRange);
        number(clearance, c.options.clearance);
        if (threads.isSet()) c.threads = parseCount("--threads", threads.getValue(), 256);
        c.rank0MapsOnly = rank0MapsOnly.getValue();
        if (bench.isSet()) c.benchRounds = int(std::max(1u, parseCount("--bench", bench.getValue(), 100)));
        c.overwrite = line.overwrite();
        if (maxMemory.isSet()) c.maxMemory = gseg::tools::parseMemorySize("--max-memory", maxMemory.getValue());
        c.mpiTimeout = line.mpiTimeout();
        c.outputs.tiles = tiles.getValue();
        // After the last scan the workers are idle: with two or more, a second thread encodes the
        // pictures while the other files are written (--threads 1: one file at a time).
        c.outputs.writers = c.threads >= 2 ? 2 : 1;
        if (tiledAbove.isSet()) c.outputs.tiledAbove = int(parseCount("--tiled-above", tiledAbove.getValue(), 1u << 20));
        c.outputs.validate();
        c.poses.input = c.input;
        c.options.validate();
    } catch (const std::invalid_argument& e) {
        return line.usageError(e.what());
    }
    return -1;
}

double peakResidentMb() {
    rusage u{};
    ::getrusage(RUSAGE_SELF, &u);
    return double(u.ru_maxrss) / 1024.0;
}

void printReport(const RunReport& r, double resolution) {
    const gseg::map::MapStats& s = r.stats;
    const gseg::map::BuildTally& tally = r.tally;
    const double cellArea = resolution * resolution;
    gseg::tools::say("rawlog-octomap: %zu scans (%zu from _ground/_obstacles pairs, %zu raw scans not segmented again, %zu "
                "skipped), poses from %s, sensor path %.2f m; points: %zu ground, %zu obstacle, %zu not used; %zu rays\n",
                s.scans + tally.skipped.size(), tally.presegmented, r.rawWithPair, tally.skipped.size(), r.poseSource.c_str(),
                s.pathLength, s.groundPoints, s.obstaclePoints, s.pointsSkipped, s.rays);
    gseg::tools::say("%s\n", r.height.c_str());
    if (tally.reflections)
        gseg::tools::say("%zu points more than belowGroundMargin below the ground left out (reflections)\n", tally.reflections);
    if (!tally.heightFallbacks.empty())
        gseg::tools::say("distToGround: auto found no estimate in %zu scan(s), first: %s\n", tally.heightFallbacks.size(),
                    tally.heightFallbacks[0].c_str());
    if (r.origin)
        gseg::tools::say("map origin: (%.3f, %.3f, %.3f) m of the poses' world is (0, 0, 0) in the maps\n", r.origin->x(),
                    r.origin->y(), r.origin->z());
    gseg::tools::say("voxels (%.2f m): %zu ground, %zu obstacle, %zu free; %zu obstacle voxels cleared (seen through), "
                "%zu ground voxels under obstacles\n",
                resolution, s.groundVoxels, s.obstacleVoxels, s.freeVoxels, s.clearedObstacleVoxels, s.groundUnderObstacle);
    gseg::tools::say("map memory: %.1f MB (%zu bricks of 8x8x8 voxels, %zu words of 4x4x4 with a value per voxel)\n",
                double(s.mapBytes) / 1e6, s.bricks, s.brickValueBlocks);
    // The map a planner loads first; the voxel picture's own grid after it, said to be that.
    std::string pgm = "the costmap", yaml;
    for (const auto& p : r.written)
        if (p.size() > 12 && p.compare(p.size() - 12, 12, "_costmap.pgm") == 0) pgm = p, yaml = p.substr(0, p.size() - 3) + "yaml";
    gseg::tools::say("costmap %s%s%s: %zu free (%.1f m^2), %zu occupied (%.1f m^2), %zu unknown cells\n", pgm.c_str(),
                yaml.empty() ? "" : " + ", yaml.c_str(), s.costmapFree, double(s.costmapFree) * cellArea, s.costmapOccupied,
                double(s.costmapOccupied) * cellArea, s.costmapUnknown);
    gseg::tools::say("voxel columns (_traversability.png, not the costmap): %zu traversable, %zu obstacle, %zu unknown cells\n",
                s.cellsTraversable, s.cellsObstacle, s.cellsUnknown);
    const PhaseTimes& t = tally.times;
    const std::size_t processes = tally.scansByRank.size();
    std::string where = r.workers ? "summed over " + std::to_string(r.workers) + " worker thread(s)" : "one thread";
    if (processes > 1) where += " in " + std::to_string(processes) + " processes";
    gseg::tools::say("time [s]: read %.2f, segmentation %.2f, transform %.2f, ray casting %.2f (%s), map update %.2f, "
                "writing %.2f; wall %.2f, %.1f scans/s\n",
                t.read, t.segmentation, t.transform, t.rayCasting, where.c_str(), t.mapUpdate, t.writing, r.wallSeconds,
                r.wallSeconds > 0 ? double(s.scans) / r.wallSeconds : 0.0);
    gseg::tools::say("peak memory: %.0f MB while integrating, %.0f MB with writing%s\n", r.peakMbBeforeWriting, r.peakMb,
                processes > 1 ? " (rank 0)" : "");
    if (processes > 1) {
        std::string split;
        for (std::size_t p = 0; p < processes; ++p)
            split += (p ? ", " : "") + std::to_string(tally.scansByRank[p]) + " on rank " + std::to_string(p);
        gseg::tools::say("scans worked on: %s\n", split.c_str());
        if (!r.bricksByHolder.empty()) {  // #35: the voxels the ranks held and updated, merged on rank 0
            std::size_t others = 0;
            std::string held;
            for (std::size_t q = 0; q < r.bricksByHolder.size(); ++q)
                others += r.bricksByHolder[q], held += ", " + std::to_string(r.bricksByHolder[q]) + " on rank " + std::to_string(q + 1);
            gseg::tools::say("voxel bricks held and updated: %zu on rank 0%s\n", s.bricks - std::min(s.bricks, others), held.c_str());
        }
    }
    for (const auto& p : r.written) gseg::tools::say("wrote %s\n", p.c_str());
}

/// Runs `f`, turning an allocation failure into an error that says what was being done.
template <class F>
auto phase(const std::string& what, const Cli& cli, F&& f) -> decltype(f()) {
    try {
        return f();
    } catch (const std::bad_alloc&) {
        throw std::runtime_error(gseg::map::outOfMemoryMessage(what, cli.options));
    }
}

}  // namespace

RunReport buildMaps(const Cli& cli, bool quiet, RemoteWorkers* remote) {
    const auto start = std::chrono::steady_clock::now();
    // Fail early: every output can be written, none is an input or exists (unless -w), before any work.
    std::vector<gseg::io::NamedPath> outputs;
    for (const std::string& path : gseg::map::TraversabilityMap::pathsToCheck(cli.prefix)) outputs.push_back({"-o", path});
    gseg::io::checkOutputs({{"input", cli.input}, {"--poses", cli.poses.poses}, {"--calib", cli.poses.calib}, {"-c", cli.config}},
                           outputs, {cli.overwrite, false});
    const gseg::mrpt::LoadedConfig& cfg = cli.loaded;
    ScanStream stream(cli.poses);
    gseg::map::MapBuilder builder(cfg, cli.options);

    // Under mpirun/srun rank 0 works too, with at least one thread like every other rank (with
    // --threads 0 one rank per core is the usual MPI layout): otherwise it would only read and map.
    gseg::map::BuildOptions how;
    how.remoteWorkers = remote ? remote->count() : 0;
    how.threads = how.remoteWorkers == 0 ? cli.threads : cli.rank0MapsOnly ? 0u : std::max(1u, cli.threads);
    if (remote) how.remoteWork = [remote](unsigned slot, const ScanJob& job) { return (*remote)(slot, job); };
    how.ranks = std::size_t(remote ? remote->processes() : 1);
    if (remote && remote->holders() > 1) {  // the voxels shared by the ranks (#35): each applies its own
        how.voxelRanks = remote->processes();
        how.worked = [remote](const ScanJob& job, ScanResult& r) { remote->route(job, r); };
    }
    gseg::Progress progress(gseg::tools::progressOut(), "rawlog-octomap", "scans");
    // Memory, before any work: the first two scans (the second gives the rawlog's bytes per scan).
    const std::deque<ScanJob>& first = phase("reading the first scans", cli, [&]() -> const std::deque<ScanJob>& { return stream.prefetch(2); });
    gseg::map::MemoryGuard memory;
    if (!first.empty()) {
        memory = gseg::map::MemoryGuard(first[0], first.size() > 1 ? &first[1] : nullptr, std::max(1u, how.threads),
                                        gseg::map::MapBuilder::inFlight(how),
                                        cli.options, cli.outputs, cli.maxMemory);
        if (!memory.estimateLine().empty()) gseg::tools::detail("rawlog-octomap: %s\n", memory.estimateLine().c_str());
        memory.refuseIfTooBig();
    }
    how.onScan = [&](std::size_t k, const ScanResult& r) {
        memory.add(k, r);
        if (!r.skipped.empty()) {
            const std::string& skipped = builder.tally().skipped.back();
            if (!quiet) progress.message("rawlog-octomap: skipped " + skipped);
            if (!quiet && !gseg::tools::progressOut())  // --quiet: a skipped scan is still an error
                std::fprintf(stderr, "rawlog-octomap: skipped %s\n", skipped.c_str());
        } else if (!r.notes.heightWarning.empty() && !quiet) {  // a warning, not an error: the maps go on
            const std::string line = "rawlog-octomap: " + r.describe + ": " + r.notes.heightWarning;
            if (gseg::tools::progressOut()) progress.message(line);
            else gseg::tools::note("%s\n", line.c_str());
        }
        if (!quiet) progress.update(k + 1, r.fraction);
        if (!quiet && r.skipped.empty()) gseg::tools::detail("rawlog-octomap: %s mapped\n", r.describe.c_str());
    };
    builder.run(stream, how);  // gseg::map::OutOfMemory says what was being done and the options memory follows
    double mergeSeconds = 0;  // counted as map update
    std::vector<std::size_t> bricksByHolder;
    if (how.voxelRanks > 1) {  // the other ranks' voxels, after their last scan
        const auto t0 = std::chrono::steady_clock::now();
        phase("merging the voxels of the other ranks", cli, [&] {
            bricksByHolder = remote->mergeVoxels(builder, builder.map().path().size() + builder.tally().skipped.size());
        });
        mergeSeconds = gseg::secondsSince(t0);
    }
    if (memory.known()) gseg::tools::detail("rawlog-octomap: memory estimated for the drive: %s\n", memory.summary().c_str());
    const gseg::map::TraversabilityMap& map = builder.map();
    const gseg::map::BuildTally& tally = builder.tally();
    const std::size_t total = map.path().size() + tally.skipped.size();
    if (!quiet) progress.finish(total);
    if (total == 0)
        throw std::runtime_error(cli.input + ": no 3D LiDAR scan in the rawlog (CObservationPointCloud, "
                                             "CObservationVelodyneScan, CObservation3DRangeScan)");
    if (map.empty()) throw std::runtime_error(cli.input + ": none of the " + std::to_string(total) + " scans could be used");
    RunReport report;
    report.workers = how.threads + how.remoteWorkers;
    report.tally = tally;
    report.tally.times.mapUpdate += mergeSeconds;
    report.bricksByHolder = bricksByHolder;
    report.height = gseg::mrpt::heightSummary(cfg, cli.config);
    report.rawWithPair = stream.rawScansSeenWithTheirPair();
    report.origin = stream.origin();
    report.poseSource = stream.poseSource();
    report.peakMbBeforeWriting = peakResidentMb();
    const auto t0 = std::chrono::steady_clock::now();
    if (!quiet && gseg::tools::progressOut())  // the writing takes seconds on a drive: say it is going on
        std::fprintf(gseg::tools::progressOut(), "rawlog-octomap: writing %zu map files (%s_*) ...\n",
                     gseg::map::TraversabilityMap::outputPaths(cli.prefix).size(), cli.prefix.c_str());
    report.written = phase("writing the maps", cli, [&] {
        const gseg::tools::WiderAffinity cores(cli.machineCpus);  // the other ranks are done
        if (remote && cli.outputs.writers >= 2)
            gseg::tools::detail("rawlog-octomap: writing on %d threads, %u CPUs (the ranks' on this machine)\n",
                                cli.outputs.writers, cores.cpus());
        return map.write(cli.prefix, cli.outputs);
    });
    report.tally.times.writing = gseg::secondsSince(t0);
    report.stats = map.stats();
    report.wallSeconds = gseg::secondsSince(start);
    report.peakMb = peakResidentMb();
    return report;
}

}  // namespace rawlog_octomap

namespace rawlog_octomap {
namespace {

/// One rank's part of the run; the exit code (rank 0's decides for all).
int run(int argc, char** argv, gseg::tools::Ranks& ranks) {
    Cli cli;  // every rank parses the same arguments and stops alike; rank 0 prints
    if (const int code = parseCli(argc, argv, ranks.root(), cli); code >= 0) return code;
    ranks.setTimeout("rawlog-octomap", cli.mpiTimeout);
    if (cli.benchRounds > 0 && ranks.size() > 1) {
        std::cerr << "rawlog-octomap: --bench times one process: start it without mpirun\n";
        return gseg::tools::kBadUsage;
    }
    // mpirun binds each rank to its cores; once the scans are done only rank 0 works (it writes):
    // its writing threads may use the cores of the ranks on its machine.
    cli.machineCpus = gseg::tools::cpusOfRanksOnThisMachine(ranks);
    if (ranks.size() > 1 && cli.machineCpus.size() >= 2) cli.outputs.writers = 2;
    if (!ranks.root()) {
        serveScans(ranks, cli);
        return 0;
    }
    RemoteWorkers remote(ranks);  // told to stop when this returns, whatever happened
    gseg::io::installTemporaryCleanup("rawlog-octomap");  // an interrupted run leaves no temporary
    try {
        gseg::tools::noteWarnings("rawlog-octomap", cli.loaded.warnings);
        if (!cli.config.empty())
            gseg::tools::detail("parameters (%s):\n%s", cli.config.c_str(),
                                gseg::mrpt::toYaml(cli.loaded).c_str());
        if (cli.benchRounds > 0) {
            runBench(cli);
            return 0;
        }
        const RunReport r = buildMaps(cli, false, &remote);
        printReport(r, cli.options.resolution);
        if (!r.tally.skipped.empty()) {
            std::cerr << "rawlog-octomap: " << r.tally.skipped.size() << " scan(s) skipped, first: " << r.tally.skipped[0]
                      << "\n";
            return gseg::tools::kPartlyDone;
        }
        return gseg::tools::kDone;
    } catch (...) {
        return gseg::tools::reportError("rawlog-octomap", gseg::tools::InvalidArgument::BadUsage);
    }
}

}  // namespace
}  // namespace rawlog_octomap

int main(int argc, char** argv) {
#ifdef __GLIBC__
    // Each scan allocates and frees a few MB (its points, its voxel lists): keep them in the heap
    // instead of mapping fresh pages for every scan (measured: a third less time in ray casting).
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
    mallopt(M_TRIM_THRESHOLD, 512 << 20);
#endif
    gseg::tools::Ranks ranks(argc, argv);
    return ranks.exitCode(rawlog_octomap::run(argc, argv, ranks));
}
