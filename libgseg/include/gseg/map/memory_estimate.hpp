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
/// all of them). Counted for voxels (c = resolution: the voxels a scan crosses), words of 4x4x4
/// voxels (the maps' value blocks) and bricks of 8x8x8 (the maps', the ray caster's and a scan's
/// free space's unit),
/// with bytes per unit from the map layer's data structures, the estimate was calibrated against
/// the peak resident memory of rawlog-octomap on the six SemanticKITTI sequence-00 scans (README,
/// Robustness): within 25 % at 0.2, 0.1 and 0.05 m while integrating; a worker thread beyond the
/// first adds its own buffers (perWorker).

#include <gseg/traversability_options.hpp>
#include <gseg/point_cloud.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <cstdint>
#include <unordered_set>

namespace gseg::map {

/// What one scan's rays touch, from which the memory follows.
struct RayFootprint {
    double solidAngle = 0;   ///< [sr] covered by the points' directions (1 x 1 degree bins)
    std::size_t rays = 0;    ///< finite points (an upper bound of the rays: one per endpoint voxel)
    double voxels = 0;       ///< voxels crossed (a scan's update)
    double sparseVoxels = 0; ///< of those, where rays are sparser than voxels (new for every scan)
    double words = 0, sparseWords = 0;    ///< the same for words of 4x4x4 voxels
    double bricks = 0, sparseBricks = 0;  ///< the same for bricks of 8x8x8 voxels
    std::size_t endVoxels = 0;  ///< distinct voxels the rays end in within maxRange (the scan's occupied voxels)
};

/// Counts the cells the rays of `points` from `sensorOrigin` cross (points beyond maxRange end
/// their ray there; non-finite points are left out). O(points + maxRange / resolution).
RayFootprint rayFootprint(const PointCloudView& points, const Eigen::Vector3d& sensorOrigin, const TraversabilityOptions& options);

/// [bytes] The parts of a run's memory.
struct MemoryEstimate {
    double process = 0;      ///< the process before any scan (libraries, segmenters): a constant
    double perScan = 0;      ///< one scan in flight: its free bricks and the caster's brick sets
    double firstMap = 0;     ///< the maps after the first scan
    double growthPerScan = 0;  ///< the maps grow by this with every further scan
    /// Each worker thread beyond the first (whose share `process` holds): its segmenter's and ray
    /// caster's buffers, which its own malloc arena keeps between scans.
    double perWorker = 0;
    /// [bytes] The peak with `workers` local worker threads and `inFlight` scans being cast or
    /// waiting at once, after `scans` scans.
    double peak(std::size_t workers, std::size_t inFlight, std::size_t scans) const {
        return process + perWorker * double(workers > 1 ? workers - 1 : 0) + perScan * double(inFlight) + maps(scans);
    }
    double firstOccupied = 0;  ///< [voxels] occupied after the first scan (the voxels its rays end in)
    /// [bytes] The maps after `scans` scans.
    double maps(std::size_t scans) const { return firstMap + growthPerScan * double(scans > 0 ? scans - 1 : 0); }
    /// [voxels] Occupied (ground and obstacle) after `scans` scans.
    double occupied(std::size_t scans) const;
    /// [bytes] The peak of a whole run, writing included: peak() and then, while the files are
    /// written, what they take beside the maps (per occupied voxel: the voxel lists and the
    /// scene's boxes; a constant part: the compressors' buffers and the ground mesh) and the 2.5D
    /// layers' `layers` bytes (layerBytes()).
    /// Under MPI (rawlog-octomap, #35) this is rank 0's peak, above the other ranks': ranks 1-3
    /// hold a share of the maps while integrating and rank 0 all of them after merging; the merge
    /// holds the other shares as bytes (about their size) for a moment, less than the writing.
    double peakWithWriting(std::size_t workers, std::size_t inFlight, std::size_t scans, double layers) const;
};

/// The estimate for scans like `footprint`'s (rayFootprint()).
MemoryEstimate estimateMemory(const RayFootprint& footprint);

struct ScanUpdate;

/// The 2.5D layers' extent, grown scan by scan with add(): the box of map cells (x, y columns, at
/// the map resolution) of every column with a ground point or an obstacle hit of a scan, and the
/// tiles of LayerTiles::kTile x kTile cells those columns fall in. The layers are sparse in such
/// tiles (gseg/map/layer_tiles.hpp), so their memory follows the tiles; the box decides whether
/// the outputs are one dense grid of it or tiles (MapOutputOptions::tiled()).
class LayerBox {
public:
    /// Extends the box and the tiles by the columns of the update's ground cells and obstacle hits.
    void add(const ScanUpdate& update);
    bool empty() const { return hi_[0] < lo_[0]; }
    /// [cells] along x and y (0 when empty)
    double cellsX() const { return empty() ? 0 : double(hi_[0] - lo_[0] + 1); }
    double cellsY() const { return empty() ? 0 : double(hi_[1] - lo_[1] + 1); }
    double cells() const { return cellsX() * cellsY(); }
    /// [m] the box's lower-left corner and its size, at cells of edge `resolution`
    double minX(double resolution) const { return (lo_[0] - 32768) * resolution; }
    double minY(double resolution) const { return (lo_[1] - 32768) * resolution; }
    /// The tiles with a column seen.
    double tiles() const { return double(tiles_.size()); }

private:
    long lo_[2] = {1L << 20, 1L << 20}, hi_[2] = {-1, -1};  ///< OctoMap key x, y (cell index + 32768)
    std::unordered_set<std::uint32_t> tiles_;  ///< key x / kTile, key y / kTile
};

/// [bytes] The 2.5D layers at their peak: `tiles` tiles of the sparse layers with the scratch
/// layers of their computation, or, while written, the 8 layers' tiles and `denseCells` cells of
/// dense grids written from them (the box of a map written untiled: the grid, GDAL's copy for the
/// GeoTIFF, the costmap; a tiled map: its overview and one costmap tile), whichever is more.
/// With `writers` 2 (MapOutputOptions::writers) a layer picture is encoded beside them: its page
/// (the grid enlarged to 640 pixels a side or reduced to 2048) and the thread's allocator arena.
double layerBytes(double tiles, double denseCells, int writers = 1);

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
