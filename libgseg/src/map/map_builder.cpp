#include <gseg/map/map_builder.hpp>

#include <gseg/ordered_pipeline.hpp>
#include <gseg/map/memory_policy.hpp>
#include <gseg/map/world_scan.hpp>
#include <gseg/mrpt/observation_points.hpp>
#include <gseg/text.hpp>

#include <mrpt/obs/CObservation.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <new>
#include <stdexcept>

namespace gseg::map {

PhaseTimes& PhaseTimes::operator+=(const ScanTimes& scan) {
    segmentation += scan.segmentation, transform += scan.transform, rayCasting += scan.rayCasting;
    return *this;
}

ScanWorker::ScanWorker(const gseg::mrpt::LoadedConfig& config, const TraversabilityOptions& options)
    : segmenter_(config), options_(options) {}

ScanResult ScanWorker::operator()(const ScanJob& job) {
    ScanResult r = (*this)(ScanParts{job.raw.get(), job.ground.get(), job.obstacles.get()}, job.robotPose, job.describe(),
                           job.index == 0 ? gseg::mrpt::HeightCheck::Now : gseg::mrpt::HeightCheck::Never);
    r.fraction = job.fraction;
    return r;
}

namespace {

/// A scan's first step: its ground and obstacle points in the world frame, segmented (a raw scan)
/// or a rawlog-gseg pair's parts as they are. False (the reason in r.skipped) for a scan the
/// segmenter cannot take.
bool toWorld(const ScanParts& parts, const ::mrpt::poses::CPose3D& robotPose, gseg::mrpt::ScanSegmenter& segmenter,
             gseg::mrpt::HeightCheck check, WorldScan& world, ScanResult& r) {
    if (!parts.raw) {
        const auto t0 = std::chrono::steady_clock::now();
        if (parts.ground) world.sensorOrigin = appendWorldPoints(*parts.ground, robotPose, world.ground);
        if (parts.obstacles) world.sensorOrigin = appendWorldPoints(*parts.obstacles, robotPose, world.obstacles);
        r.times.transform = secondsSince(t0);
        return true;
    }
    try {
        world = segmentToWorld(*parts.raw, robotPose, segmenter, &r.times, check);
    } catch (const std::invalid_argument& e) {
        r.skipped = e.what();
        return false;
    }
    r.notes = world.notes;
    return true;
}

/// Its second step: the rays from the sensor to its points, cast into the scan's update.
void castRays(const WorldScan& world, const TraversabilityOptions& options, ScanResult& r) {
    const auto t0 = std::chrono::steady_clock::now();
    try {
        r.update = castScan(world.groundView(), world.obstaclesView(), world.sensorOrigin, options);
    } catch (const std::out_of_range& e) {
        throw std::runtime_error(r.describe + ": " + e.what() + "; for poses in UTM or other large coordinates use --origin first");
    } catch (const std::bad_alloc&) {
        throw;  // MapBuilder::run() and insert() name the phase and the options memory follows
    } catch (const std::exception& e) {
        throw std::runtime_error(r.describe + ": " + e.what());
    }
    r.times.rayCasting = secondsSince(t0);
}

}  // namespace

ScanResult ScanWorker::operator()(const ScanParts& parts, const ::mrpt::poses::CPose3D& robotPose,
                                  const std::string& describe, gseg::mrpt::HeightCheck check) {
    ScanResult r;
    r.describe = describe;
    r.presegmented = parts.ground || parts.obstacles;
    WorldScan world;
    if (toWorld(parts, robotPose, segmenter_, check, world, r)) castRays(world, options_, r);
    return r;
}

MapBuilder::MapBuilder(const gseg::mrpt::LoadedConfig& config, const TraversabilityOptions& options)
    : config_(config), map_(options) {
    tally_.scansByRank.assign(1, 0);
}

void MapBuilder::integrate(const ScanResult& r) {
    tally_.times += r.times;
    const std::size_t rank = std::size_t(std::max(0, r.rank));
    if (rank >= tally_.scansByRank.size()) tally_.scansByRank.resize(rank + 1, 0);
    ++tally_.scansByRank[rank];
    if (!r.skipped.empty()) {
        tally_.skipped.push_back(r.describe + ": " + r.skipped);
        return;
    }
    const auto t0 = std::chrono::steady_clock::now();
    map_.apply(r.update);
    tally_.times.mapUpdate += secondsSince(t0);
    tally_.presegmented += r.presegmented;
    tally_.reflections += r.notes.reflections;
    if (!r.notes.heightNote.empty()) tally_.heightFallbacks.push_back(r.describe + ": " + r.notes.heightNote);
}

std::size_t MapBuilder::inFlight(const BuildOptions& o) { return 2 * std::size_t(std::max(1u, o.threads + o.remoteWorkers)) + 2; }

namespace {

/// Runs `f`; an allocation failure becomes OutOfMemory naming what was being done (`what()`, built
/// only then) and the options memory follows.
template <class What, class F>
auto guarded(const TraversabilityOptions& options, const What& what, F&& f) -> decltype(f()) {
    try {
        return f();
    } catch (const std::bad_alloc&) {
        throw OutOfMemory(outOfMemoryMessage(what(), options));
    }
}

/// The three steps of MapBuilder::run() for one scan, each guarded: read it (the calling thread),
/// work on it (a worker: local threads first, then the remote ones, if any), integrate it (in scan
/// order, then `onScan`).
class RunSteps {
public:
    RunSteps(MapBuilder& builder, std::vector<ScanWorker>& workers, ScanStream& stream, const BuildOptions& o)
        : builder_(builder), workers_(workers), stream_(stream), o_(o) {}

    bool read(ScanJob& job) {
        const std::size_t k = read_++;
        return guarded(options(), [k] { return "reading scan " + std::to_string(k); }, [&] { return stream_.next(job); });
    }

    ScanResult work(unsigned w, ScanJob& job) {
        return guarded(options(), [&] { return "segmenting and ray casting " + job.describe(); }, [&] {
            ScanResult r = w < o_.threads || o_.remoteWorkers == 0 ? workers_[w](job) : o_.remoteWork(w - o_.threads, job);
            if (o_.worked) o_.worked(job, r);
            return r;
        });
    }

    void integrate(std::size_t k, ScanResult& r) {
        guarded(options(), [&] { return "adding " + r.describe + " to the maps"; }, [&] { builder_.integrate(r); });
        if (o_.onScan) o_.onScan(k, r);
    }

private:
    const TraversabilityOptions& options() const { return builder_.map().options(); }

    MapBuilder& builder_;
    std::vector<ScanWorker>& workers_;
    ScanStream& stream_;
    const BuildOptions& o_;
    std::size_t read_ = 0;  ///< scans read so far
};

}  // namespace

void MapBuilder::run(ScanStream& stream, const BuildOptions& o) {
    if (o.remoteWorkers > 0 && !o.remoteWork) throw std::invalid_argument("MapBuilder::run: remote workers without remoteWork");
    startWorkers(std::max(1u, o.threads));
    map_.shareVoxels(0, std::max(1, o.voxelRanks));
    if (tally_.scansByRank.size() < o.ranks) tally_.scansByRank.resize(o.ranks, 0);
    RunSteps steps(*this, workers_, stream, o);
    const double readBefore = stream.readSeconds();
    runOrdered<ScanJob, ScanResult>([&](ScanJob& job) { return steps.read(job); },
                                    [&](unsigned w, ScanJob& job) { return steps.work(w, job); },
                                    [&](std::size_t k, ScanResult& r) { steps.integrate(k, r); },
                                    {o.threads + o.remoteWorkers, inFlight(o)});
    tally_.times.read += stream.readSeconds() - readBefore;
}

void MapBuilder::startWorkers(unsigned count) {
    workers_.clear();
    for (unsigned i = 0; i < count; ++i) workers_.emplace_back(config_, map_.options());
    map_.setUpdateThreads(count);  // the voxels of a scan's update by tiles (same maps for any number)
}

bool MapBuilder::insert(const ::mrpt::obs::CObservation& obs, const ::mrpt::poses::CPose3D& robotPose) {
    const ScanPart part = scanPartOf(obs);
    if (part == ScanPart::Raw && !gseg::mrpt::isLidarObservation(obs)) return false;
    ScanParts parts;
    (part == ScanPart::Raw ? parts.raw : part == ScanPart::Ground ? parts.ground : parts.obstacles) = &obs;
    if (workers_.empty()) workers_.emplace_back(config_, map_.options());
    char describe[200];
    std::snprintf(describe, sizeof describe, "observation %zu ('%s', t = %.6f s)", inserted_++, obs.sensorLabel.c_str(),
                  ::mrpt::Clock::toDouble(obs.timestamp));
    return guarded(map_.options(), [&] { return std::string("adding ") + describe + " to the maps"; }, [&] {
        const ScanResult r = workers_.front()(parts, robotPose, describe);
        integrate(r);
        return r.skipped.empty();
    });
}

void MapBuilder::clear() {
    map_ = TraversabilityMap(map_.options());
    tally_ = BuildTally();
    tally_.scansByRank.assign(1, 0);
    inserted_ = 0;
}

}  // namespace gseg::map
