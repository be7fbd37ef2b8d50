#include <gseg/map/memory_estimate.hpp>

#include <gseg/map/layer_tiles.hpp>
#include <gseg/map/scan_update.hpp>

#include "voxel_keys.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include <sys/resource.h>

namespace gseg::map {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// Voxels a ray crosses per cell of its length (OctoMap's traversal steps one axis at a time:
/// |dx| + |dy| + |dz| over the length, 4 / pi for level rays in every direction).
constexpr double kStepsPerCell = 1.3;

// Bytes per unit, from the data structures (brick_map.hpp, voxel_keys.hpp), times what the
// calibration on the sequence-00 scans added (allocator slack, vectors at twice their size).
constexpr double kBytesPerFreeBrick = 8 + 64;      // a scan's free space (VoxelBricks): code and 512 bits
constexpr double kBytesPerCastBrick = 110 * 1.5;   // a ray caster's brick set: code, 512 bits, hash slot
constexpr double kBytesPerMapBrick = 390;          // a map brick: two maps' words, the ever-obstacle bits, code, index
constexpr double kBytesPerMapWord = 2 * 256;       // a word of 64 values in each of the two maps
constexpr double kProcessBytes = 100e6;            // the process before any scan (MRPT's libraries, segmenters), measured
// A second worker thread (rawlog-octomap --threads 2 against 1, the peak while integrating, six
// sequence-00 scans and the shared drives' ten, 2026-12-07): 10-30 MB more at 0.4 and 0.2 m, 57-99
// MB at 0.1 m, of which the two more scans in flight explain 1, 9 and 46 MB; the rest, about 25 MB
// whatever the resolution, is the worker's segmenter and its malloc arena, kept between scans.
constexpr double kWorkerBytes = 25e6;
// Each worker's ray caster marks the voxels near the sensor in a bit cube of 512 voxels a side
// (scan_update.cpp): 16 MB of zeroed pages, resident where rays marked them: about a page (64
// bricks' bits) per brick crossed, as the crossed bricks are spread, up to the whole cube (0.1 m
// and finer, where the cube spans less than the rays).
constexpr double kCastWindowBytes = double(1ULL << 27) / 8;
constexpr double kCastWindowPerBrick = 4096;
// Calibration (peak RSS of rawlog-octomap, six sequence-00 scans, 2 workers, 0.2 to 0.04 m):
constexpr double kInFlightShare = 0.35;   // at the peak about a third of the scans in flight hold full voxel lists
constexpr double kSparseGrowth = 0.06;    // of a scan's sparse cells, new in the next one (scans 0.7 m apart)
constexpr double kMapGrowth = 0.02;       // of the first map, new with every further scan (driving on)

/// Cells crossed, in all and where rays are sparse, for cells of edge `cell`, from the ray
/// lengths' histogram `longer` (longer[k]: rays of length >= k * resolution).
/// `angle[k]`: the solid angle of the directions with a ray of length >= k * resolution.
void countCells(const std::vector<double>& longer, const std::vector<double>& angle, int cellVoxels, double& all,
                double& sparse) {
    all = sparse = 0;
    for (std::size_t j = 0;; ++j) {
        const std::size_t k = j * std::size_t(cellVoxels);
        if (k >= longer.size() || longer[k] <= 0) break;
        const double rays = longer[k];
        const double shell = std::max(1.0, angle[k] * (double(j) + 0.5) * (double(j) + 0.5));
        if (rays * kStepsPerCell >= shell) {
            all += shell;
        } else {
            all += rays * kStepsPerCell;
            sparse += rays * kStepsPerCell;
        }
    }
}

}  // namespace

RayFootprint rayFootprint(const PointCloudView& points, const Eigen::Vector3d& sensorOrigin, const TraversabilityOptions& options) {
    options.validate();
    const double res = options.resolution;
    const std::size_t bins = std::size_t(std::ceil(options.maxRange / res)) + 2;
    std::vector<double> ending(bins, 0.0);  // rays ending in each voxel-thick shell
    std::vector<double> reach(360 * 180, -1.0);  // [m] the longest ray of each direction bin
    RayFootprint f;
    std::vector<std::uint64_t> ends;  // the voxels rays end in, as 21-bit keys from the sensor
    ends.reserve(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        const float* p = points.point(i);
        const Eigen::Vector3d d = Eigen::Vector3d(p[0], p[1], p[2]) - sensorOrigin;
        const double r = d.norm();
        if (!std::isfinite(r) || r <= 0) continue;
        ++f.rays;
        const int az = std::clamp(int(std::floor((std::atan2(d.y(), d.x()) + kPi) * 180 / kPi)), 0, 359);
        const int el = std::clamp(int(std::floor((std::asin(std::clamp(d.z() / r, -1.0, 1.0)) + kPi / 2) * 180 / kPi)), 0, 179);
        double& longest = reach[std::size_t(el * 360 + az)];
        longest = std::max(longest, std::min(r, options.maxRange));
        ending[std::min(bins - 1, std::size_t(std::min(r, options.maxRange) / res))] += 1;
        if (r <= options.maxRange) {
            std::uint64_t key = 0;
            for (int a = 0; a < 3; ++a) key = key << 21 | (std::uint64_t(std::int64_t(std::floor(d[a] / res)) + (1 << 20)) & 0x1fffff);
            ends.push_back(key);
        }
    }
    std::sort(ends.begin(), ends.end());
    f.endVoxels = std::size_t(std::unique(ends.begin(), ends.end()) - ends.begin());
    // The solid angle still reached at each distance: rays to the road end early, so far away
    // only the level directions are left.
    std::vector<double> angleEnding(bins, 0.0);
    const double bin = (kPi / 180) * (kPi / 180);
    for (int el = 0; el < 180; ++el)
        for (int az = 0; az < 360; ++az)
            if (const double longest = reach[std::size_t(el * 360 + az)]; longest >= 0) {
                const double a = bin * std::cos((el + 0.5) * kPi / 180 - kPi / 2);
                f.solidAngle += a;
                angleEnding[std::min(bins - 1, std::size_t(longest / res))] += a;
            }
    std::vector<double> longer(bins, 0.0), angle(bins, 0.0);
    double rays = 0, solid = 0;
    for (std::size_t k = bins; k-- > 0;) longer[k] = (rays += ending[k]), angle[k] = (solid += angleEnding[k]);
    countCells(longer, angle, 1, f.voxels, f.sparseVoxels);
    countCells(longer, angle, 4, f.words, f.sparseWords);
    countCells(longer, angle, 8, f.bricks, f.sparseBricks);
    return f;
}

MemoryEstimate estimateMemory(const RayFootprint& f) {
    MemoryEstimate e;
    const double window = std::min(kCastWindowBytes, kCastWindowPerBrick * f.bricks);
    e.process = kProcessBytes + window;
    e.perWorker = kWorkerBytes + window;
    e.firstOccupied = double(f.endVoxels);
    e.perScan = kInFlightShare * (kBytesPerFreeBrick + kBytesPerCastBrick) * f.bricks;
    e.firstMap = kBytesPerMapBrick * f.bricks + kBytesPerMapWord * f.words;
    e.growthPerScan = kSparseGrowth * (kBytesPerMapBrick * f.sparseBricks + kBytesPerMapWord * f.sparseWords) + kMapGrowth * e.firstMap;
    return e;
}

void LayerBox::add(const ScanUpdate& u) {
    auto extend = [&](long x, long y) {
        lo_[0] = std::min(lo_[0], x), hi_[0] = std::max(hi_[0], x);
        lo_[1] = std::min(lo_[1], y), hi_[1] = std::max(hi_[1], y);
        tiles_.insert((std::uint32_t(x / LayerTiles::kTile) << 16) | std::uint32_t(y / LayerTiles::kTile));
    };
    for (const GroundCellSample& c : u.groundCells) extend(long(c.cell >> 16), long(c.cell & 0xffffu));
    // Obstacle hits are sorted by Morton code: the ones of a column are not together, but their
    // x, y come from the code's low two bits of each triple.
    for (std::uint64_t code : u.obstacleHits) extend(long(detail::compactBits(code)), long(detail::compactBits(code >> 1)));
}

// Per tile of the sparse layers and layer: 64 x 64 floats and the hash map's node, times the
// slack of the allocator. While computed a tile holds 14 layers (8 and 6 scratch), while written 8.
constexpr double kBytesPerTileLayer = LayerTiles::kTileBytes * 1.1;
// Per cell of a dense grid written: the 8 layers (32 B), GDAL's in-memory copy of them beside it
// (32 B) and its compressed output (at most about the copy, a few B for mostly unknown cells), the
// costmap and its PGM (2 B).
constexpr double kBytesPerDenseCell = 32 + 32 + 4 + 2;

// A layer picture being encoded on the second writer (MapOutputOptions::writers 2) beside the
// scene: per pixel of its map area the canvas (3 B), the block values and colours (8 B) and the
// PNG's share, and the second thread's malloc arena. (The layers are built there while the voxel
// maps' files are written, whose memory the estimate already adds to the layers'.) Measured on the
// 60-scan drive (0.27 M cells): the peak with writing 273-277 MB with one writer, 286-288 MB with
// two; since the layers are built beside the voxel files (2026-12-07), 600 scans: 860-869 MB ->
// 893-921 MB, 4,542 scans: 3,663-3,687 -> 3,761-3,763 MB (the shared drives' whole runs stay within 25 % of the
// estimate: MemoryEstimate.TheWholeRunIsWithin25PercentOfThePeakOnTheSharedDrives).
constexpr double kBytesPerPicturePixel = 16;
constexpr double kSecondWriterBytes = 8e6;

double layerBytes(double tiles, double denseCells, int writers) {
    const double picture = writers >= 2 ? kSecondWriterBytes + kBytesPerPicturePixel * std::clamp(denseCells, 640.0 * 640.0, 2048.0 * 2048.0) : 0;
    return std::max(14 * kBytesPerTileLayer * tiles, 8 * kBytesPerTileLayer * tiles + kBytesPerDenseCell * denseCells + picture);
}

// What the writing takes beside the maps and the layers (2026-12-07; heaptrack of rawlog-octomap
// on the six sequence-00 scans, the allocations under TraversabilityMap::write(): at 0.2 m about
// 30 MB beside the layers (the ground mesh 10 MB, vectors 14 MB, a gzip member 4 MB), at 0.05 m 15
// MB; the rest is the layers (GDAL's copy, the dense window, the tiles: 350 MB at 0.05 m). Until
// then the estimate counted 1.9 bytes per byte of the maps, which at fine voxels are mostly free
// space that no file holds in memory: 2.9 GB for a run of 1.38 GB at 0.05 m, 4.9 GB for 2.03 GB
// at 0.04 m.) Per occupied voxel (the voxel lists of the .ply and the scene, the scene's boxes):
// fitted on the 600-scan drive at 0.2 m (1.30 M occupied voxels; the peak with writing 924-938
// MB, 426 MB before writing, 268 MB of layers).
constexpr double kWritingBytes = 25e6;
constexpr double kWritingPerOccupiedVoxel = 163;
// Occupied voxels after n scans: the first scan's times 1 + g (n - 1). Measured at 0.2 m along
// sequence 00 (6, 10, 60 and 600 scans: 2.1, 2.3, 6.5 and 43.6 times the first scan's): g 0.07 to
// 0.22 a scan, 0.1 taken; finer voxels grow faster (six scans: 3.8 times at 0.05 m), which the
// writing at fine voxels does not need (it reuses the freed buffers of the scans in flight there).
constexpr double kOccupiedGrowth = 0.1;

double MemoryEstimate::occupied(std::size_t scans) const {
    return firstOccupied * (1 + kOccupiedGrowth * double(scans > 0 ? scans - 1 : 0));
}

double MemoryEstimate::peakWithWriting(std::size_t workers, std::size_t inFlight, std::size_t scans, double layers) const {
    return peak(workers, inFlight, scans) + kWritingBytes + kWritingPerOccupiedVoxel * occupied(scans) + layers;
}

namespace {

/// A "Key:   123 kB" line of a /proc file, in bytes; -1 if absent.
double procKilobytes(const char* file, const std::string& key) {
    std::ifstream in(file);
    for (std::string line; std::getline(in, line);)
        if (line.compare(0, key.size(), key) == 0 && line.size() > key.size() && line[key.size()] == ':') {
            std::istringstream v(line.substr(key.size() + 1));
            double kb = -1;
            if (v >> kb) return kb * 1024;
        }
    return -1;
}

}  // namespace

MemoryLimit memoryLimit() {
    MemoryLimit m{std::numeric_limits<double>::infinity(), "the available memory", true};
    if (const double avail = procKilobytes("/proc/meminfo", "MemAvailable"); avail >= 0) m.bytes = avail;
    // Address space goes faster than memory: malloc reserves 64 MB per thread's arena, threads
    // their stacks (measured: 1.3 GB of address space for 1.0 GB resident at 0.05 m).
    auto limit = [&](int resource, const char* inUseKey, const char* what, double overhead) {
        rlimit l{};
        if (::getrlimit(resource, &l) != 0 || l.rlim_cur == RLIM_INFINITY) return;
        const double used = std::max(0.0, procKilobytes("/proc/self/status", inUseKey));
        const double left = std::max(0.0, double(l.rlim_cur) - used) / overhead;
        if (left < m.bytes) m = {left, what, false};
    };
    limit(RLIMIT_AS, "VmSize", "the address-space limit (ulimit -v)", 1.3);
    limit(RLIMIT_DATA, "VmData", "the data limit (ulimit -d)", 1.3);
    return m;
}

std::string formatBytes(double bytes) {
    char text[32];
    if (bytes >= 10e9) std::snprintf(text, sizeof text, "%.0f GB", bytes / 1e9);
    else if (bytes >= 1e9) std::snprintf(text, sizeof text, "%.1f GB", bytes / 1e9);
    else std::snprintf(text, sizeof text, "%.0f MB", bytes / 1e6);
    return text;
}

}  // namespace gseg::map
