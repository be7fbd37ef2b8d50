#pragma once
/// \file memory_policy.hpp
/// When a map build refuses for memory, and the one wording of every memory message: the check
/// before any work (the maps and the scans in flight, estimated from the first scan's rays, against
/// the limit), the check after every scan (the 2.5D layers seen so far, #35) and the message of an
/// allocation that failed anyway. rawlog-octomap, Python's MapBuilder and the map plugin say the
/// same words (the options named as rawlog-octomap's flags, which every route's key maps to:
/// `--resolution` is TraversabilityOptions::resolution, `--max-range` maxRange).

#include <gseg/map/memory_estimate.hpp>
#include <gseg/map/scan_stream.hpp>
#include <gseg/map/traversability_map.hpp>
#include <gseg/traversability_options.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <string>

namespace gseg::map {

struct ScanResult;

/// " (at --resolution 0.01 m, --max-range 50 m)": the options memory follows, for messages.
std::string memoryOptionsText(const TraversabilityOptions& options);

/// "out of memory while <what> (at --resolution ..., --max-range ...); nothing written": the one
/// message of an allocation that failed while building maps. `what` is what was being done
/// ("reading the first scans"), or a whole "out of memory while ..." (OutOfMemory::what()).
std::string outOfMemoryMessage(const std::string& what, const TraversabilityOptions& options);

/// The memory policy of a map build: refuses (std::runtime_error naming the option to change) a
/// drive whose maps, scans in flight and 2.5D layers would not fit the limit.
class MemoryGuard {
public:
    /// No check (nothing to estimate from).
    MemoryGuard() = default;

    /// Before any work (#18): the maps, `workers` local worker threads and `inFlight` scans, estimated from the first scan's rays at
    /// `options` (the second scan, if any, gives the rawlog's bytes per scan and so the number of
    /// scans), against `maxMemory` [bytes] (0: what the machine and the process's limits leave,
    /// memoryLimit()); refuseIfTooBig() says whether it fits. A first scan that gives nothing to
    /// estimate from (a 2D scan the builder will skip) checks nothing.
    MemoryGuard(const ScanJob& first, const ScanJob* second, std::size_t workers, std::size_t inFlight,
                const TraversabilityOptions& options, const MapOutputOptions& outputs, double maxMemory);

    /// Throws std::runtime_error naming the options and the estimate when the estimate before any
    /// work is over the limit.
    void refuseIfTooBig() const;

    /// After every scan `k`, in scan order: the 2.5D layers (sparse in tiles of 64 x 64 cells where
    /// scans saw something, #35; a map written untiled adds dense grids over its box, the costmap
    /// and the GeoTIFF, a tiled one an overview and one costmap tile) with the maps against the
    /// limit; throws std::runtime_error at the scan that makes them too big, with what to change.
    void add(std::size_t k, const ScanResult& result);

    /// Whether the first scan gave an estimate (add() checks only then).
    bool known() const { return known_; }
    /// "memory estimated from ...": the estimate before any work ("" when none; for --verbose).
    const std::string& estimateLine() const { return estimateLine_; }
    /// "... with writing (... while integrating, maps ..., layers in N tiles ...)": the estimate
    /// with the layers of the whole drive.
    std::string summary() const;

private:
    bool tiled() const;
    double layerBytes() const;  ///< [bytes] the layers' tiles and the dense grids written from them
    double need(double layers) const { return estimate_.peakWithWriting(workers_, inFlight_, scans_, layers); }
    std::string advice() const;  ///< what to change when the layers do not fit

    bool known_ = false;
    TraversabilityOptions options_;
    MapOutputOptions outputs_;
    MemoryEstimate estimate_;
    std::size_t workers_ = 1, inFlight_ = 0, scans_ = 0;  ///< as estimated (scans from the rawlog's bytes per scan)
    MemoryLimit limit_;
    std::string estimateLine_;
    std::string refusal_;  ///< the message of refuseIfTooBig() ("" when it fits)
    LayerBox box_;
    bool haveOrigin_ = false;
    Eigen::Vector3d lastOrigin_ = Eigen::Vector3d::Zero();
    double jump_ = 0;
    std::size_t jumpScan_ = 0;
};

}  // namespace gseg::map
