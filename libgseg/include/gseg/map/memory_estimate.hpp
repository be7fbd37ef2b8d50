#pragma once
/// \file memory_estimate.hpp
/// How much memory a drive's maps and ray casting will take, estimated before any work from the
/// options and one scan (the first): a tool can refuse an option that cannot fit (say
/// `--resolution 0.01`, over 24 GB on six KITTI scans) in one line, instead of being killed by the
/// kernel a minute later.
///
/// The model: the rays of a scan leave the sensor over a solid angle Omega (measured from the
/// points' directions). At distance r, a shell of cells of edge c holds about Omega (r / c)^2
/// cells; N(r) rays are longer than r. Where N(r) exceeds the cells, every cell of the shell is
/// crossed (saturated: the same cells again for the next scans, which see the same space); beyond,
/// each ray crosses cells of its own (sparse: new cells for every scan, at fine resolutions nearly
/// all of them). Counted for voxels (c = resolution: a scan's list of crossed voxels), words of
/// 4x4x4 voxels (the maps' value blocks) and bricks of 8x8x8 (the maps' and the ray caster's unit),
/// with bytes per unit from the map layer's data structures, the estimate was calibrated against
/// the peak resident memory of rawlog-octomap on the six SemanticKITTI sequence-00 scans (README,
/// Robustness): within 25 % at 0.2, 0.1 and 0.05 m.

#include <gseg/traversability_options.hpp>
#include <gseg/point_cloud.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <string>

namespace gseg::map {

/// What one scan's rays touch, from which the memory follows.
struct RayFootprint {
    double solidAngle = 0;   ///< [sr] covered by the points' directions (1 x 1 degree bins)
    std::size_t rays = 0;    ///< finite points (an upper bound of the rays: one per endpoint voxel)
    double voxels = 0;       ///< voxels crossed (a scan's update)
    double sparseVoxels = 0; ///< of those, where rays are sparser than voxels (new for every scan)
    double words = 0, sparseWords = 0;    ///< the same for words of 4x4x4 voxels
    double bricks = 0, sparseBricks = 0;  ///< the same for bricks of 8x8x8 voxels
};

/// Counts the cells the rays of `points` from `sensorOrigin` cross (points beyond maxRange end
/// their ray there; non-finite points are left out). O(points + maxRange / resolution).
RayFootprint rayFootprint(const PointCloudView& points, const Eigen::Vector3d& sensorOrigin, const TraversabilityOptions& options);

/// [bytes] The parts of a run's memory.
struct MemoryEstimate {
    double process = 0;      ///< the process before any scan (libraries, segmenters): a constant
    double perScan = 0;      ///< one scan in flight: its voxel lists and the caster's brick sets
    double firstMap = 0;     ///< the maps after the first scan
    double growthPerScan = 0;  ///< the maps grow by this with every further scan
    /// [bytes] The peak with `inFlight` scans being cast or waiting at once, after `scans` scans.
    double peak(std::size_t inFlight, std::size_t scans) const {
        return process + perScan * double(inFlight) + firstMap + growthPerScan * double(scans > 0 ? scans - 1 : 0);
    }
};

/// The estimate for scans like `footprint`'s (rayFootprint()).
MemoryEstimate estimateMemory(const RayFootprint& footprint);

/// [bytes] What this process may still allocate: the smallest of the machine's available memory
/// (MemAvailable of /proc/meminfo), RLIMIT_AS less the address space in use and RLIMIT_DATA less
/// the data in use (those two divided by 1.3: malloc's per-thread arenas and the threads' stacks
/// take address space beyond the memory used). `what` says which one it is ("the available memory", "the address-space limit
/// (ulimit -v)", "the data limit (ulimit -d)").
struct MemoryLimit {
    double bytes = 0;
    std::string what;
    bool machine = true;  ///< the available memory (not a limit of the process)
};
MemoryLimit memoryLimit();

/// "1.2 GB", "324 MB": bytes for messages.
std::string formatBytes(double bytes);

}  // namespace gseg::map
