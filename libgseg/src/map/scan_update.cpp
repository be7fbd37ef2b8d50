#include <gseg/map/scan_update.hpp>

#include <gseg/io/bytes.hpp>

#include "voxel_keys.hpp"

#include <octomap/OcTree.h>

#include <cmath>
#include <cstring>
#include <iomanip>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <algorithm>

namespace gseg::map {
namespace {

using detail::BrickSet;
using detail::mortonCode;

constexpr std::uint64_t kAxisMask[3] = {0x249249249249ULL, 0x249249249249ULL << 1, 0x249249249249ULL << 2};

/// Ray casting of one scan. The voxels are exactly those OcTree::computeRayKeys() gives (the same
/// traversal with the same floating-point operations), so the maps are OctoMap's; but the keys go
/// straight into the brick sets as Morton codes. Buffers are kept between scans (one per thread).
class Caster {
public:
    /// Prepares a scan: throws std::out_of_range if the origin lies outside the map's extent.
    void begin(const TraversabilityOptions& o, const Eigen::Vector3d& sensorOrigin) {
        if (!geometry_ || geometry_->getResolution() != o.resolution) geometry_ = std::make_unique<octomap::OcTree>(o.resolution);
        maxRange_ = o.maxRange, limit_ = 2 * o.extent();
        origin_ = octomap::point3d(float(sensorOrigin.x()), float(sensorOrigin.y()), float(sensorOrigin.z()));
        if (!keyOf(origin_, originKey_)) {
            std::ostringstream s;
            s.precision(3);
            s << std::fixed << "sensor position (" << sensorOrigin.x() << ", " << sensorOrigin.y() << ", " << sensorOrigin.z()
              << ") m lies outside the map's extent of +-" << std::setprecision(1) << o.extent() << " m ("
              << std::setprecision(2) << o.resolution << " m voxels)";
            throw std::out_of_range(s.str());
        }
        originCode_ = mortonCode(originKey_);
        for (BrickSet* b : {&ends_, &groundHits_, &obstacleHits_, &crossed_}) b->clear();
        endPoints_.clear();
        endCodes_.clear();
    }

    BrickSet& groundHits() { return groundHits_; }

    /// Per-cell sums of the ground points within maxRange (sorted by cell).
    std::vector<GroundCellSample> groundCells(const PointCloudView& pts) {
        cells_.clear();
        for (std::size_t i = 0; i < pts.size(); ++i) {
            const octomap::point3d p(pts.x(i), pts.y(i), pts.z(i));
            const double range = (p - origin_).norm();
            octomap::OcTreeKey key;
            if (!(range <= maxRange_) || !keyOf(p, key)) continue;
            const std::uint32_t cell = (std::uint32_t(key[0]) << 16) | key[1];
            auto [it, added] = cells_.try_emplace(cell);
            GroundCellSample& c = it->second;
            const double z = pts.z(i);
            if (added) c.cell = cell, c.minZ = c.maxZ = float(z);
            ++c.count, c.sumZ += z, c.sumZ2 += z * z, c.sumX += pts.x(i), c.sumY += pts.y(i);
            c.minZ = std::min(c.minZ, float(z)), c.maxZ = std::max(c.maxZ, float(z));
        }
        std::vector<GroundCellSample> out;
        out.reserve(cells_.size());
        for (const auto& kv : cells_) out.push_back(kv.second);
        std::sort(out.begin(), out.end(), [](const GroundCellSample& a, const GroundCellSample& b) { return a.cell < b.cell; });
        return out;
    }
    BrickSet& obstacleHits() { return obstacleHits_; }

    /// Hits and ray ends of a point set (the first point of each endpoint voxel ends a ray).
    void collect(const PointCloudView& pts, BrickSet& hits, ScanUpdate& u) {
        for (std::size_t i = 0; i < pts.size(); ++i) {
            octomap::point3d p(pts.x(i), pts.y(i), pts.z(i));
            const octomap::point3d d = p - origin_;
            const double range = d.norm();
            const bool hit = range <= maxRange_;
            if (!hit) p = origin_ + d * float(maxRange_ / range);
            octomap::OcTreeKey key;
            if (!std::isfinite(range) || !keyOf(p, key)) {
                ++u.pointsSkipped;
                continue;
            }
            const std::uint64_t code = mortonCode(key);
            if (hit) hits.insert(code);
            if (ends_.insert(code)) endPoints_.push_back(p), endCodes_.push_back(code);
        }
    }

    /// Every voxel from the origin's up to (not including) each ray end's.
    void castRays() {
        for (std::size_t r = 0; r < endPoints_.size(); ++r) castRay(endPoints_[r], endCodes_[r]);
    }
    std::size_t rays() const { return endPoints_.size(); }
    const BrickSet& crossed() const { return crossed_; }

private:
    std::unique_ptr<octomap::OcTree> geometry_;  ///< an empty tree: key arithmetic only
    double maxRange_ = 0, limit_ = 0;
    octomap::point3d origin_;
    octomap::OcTreeKey originKey_;
    std::uint64_t originCode_ = 0;
    BrickSet ends_, groundHits_, obstacleHits_, crossed_;
    std::vector<octomap::point3d> endPoints_;
    std::vector<std::uint64_t> endCodes_;
    std::unordered_map<std::uint32_t, GroundCellSample> cells_;

    bool keyOf(const octomap::point3d& p, octomap::OcTreeKey& key) const {
        for (int a = 0; a < 3; ++a)  // far outside: rejected before OctoMap's int conversion can overflow
            if (!(std::abs(double(p(a))) < limit_)) return false;
        return geometry_->coordToKeyChecked(p, key);
    }

    /// OcTree::computeRayKeys(origin, end) (OctoMap 1.9.7), marking each key in crossed_.
    void castRay(const octomap::point3d& end, std::uint64_t endCode) {
        if (endCode == originCode_) return;
        crossed_.insert(originCode_);
        octomap::point3d direction = (end - origin_);
        const float length = float(direction.norm());
        direction /= length;
        int step[3];
        double tMax[3], tDelta[3];
        const double resolution = geometry_->getResolution();
        for (int i = 0; i < 3; ++i) {
            step[i] = direction(i) > 0.0 ? 1 : direction(i) < 0.0 ? -1 : 0;
            if (step[i] != 0) {
                double voxelBorder = geometry_->keyToCoord(originKey_[unsigned(i)]);
                voxelBorder += float(step[i] * resolution * 0.5);
                tMax[i] = (voxelBorder - origin_(i)) / direction(i);
                tDelta[i] = resolution / std::fabs(direction(i));
            } else {
                tMax[i] = tDelta[i] = std::numeric_limits<double>::max();
            }
        }
        // The same choices as OctoMap's loop, without branches on the axis (they mispredict).
        // One voxel along axis a: the axis bits of the code counted up or down, the others kept.
        std::uint64_t pick[3], fill[3], add[3];
        for (int a = 0; a < 3; ++a) {
            pick[a] = step[a] > 0 ? ~0ULL : kAxisMask[a];  // up: carry through the other bits (filled)
            fill[a] = step[a] > 0 ? ~kAxisMask[a] : 0;     // down: borrow within the axis bits only
            add[a] = step[a] > 0 ? 1 : ~0ULL;
        }
        std::uint64_t code = originCode_;
        double t0 = tMax[0], t1 = tMax[1], t2 = tMax[2];
        while (true) {
            const int d01 = !(t0 < t1);  // OctoMap: tMax[0] < tMax[1] ? 0 : 1, then that one < tMax[2] ? it : 2
            const int dim = (d01 ? t1 : t0) < t2 ? d01 : 2;
            const std::uint64_t m = kAxisMask[dim];
            code = ((((code & pick[dim]) | fill[dim]) + add[dim]) & m) | (code & ~m);
            t0 += dim == 0 ? tDelta[0] : 0.0;  // + 0.0 leaves the other two exact
            t1 += dim == 1 ? tDelta[1] : 0.0;
            t2 += dim == 2 ? tDelta[2] : 0.0;
            if (code == endCode) return;
            if ((t0 > length) & (t1 > length) & (t2 > length)) return;  // min(tMax) > length
            crossed_.insert(code);
        }
    }
};

// ---- byte encoding (gseg/io/bytes.hpp) ----

/// Reads the lists of a scan update; errors say "scan update: ...".
class Reader {
public:
    Reader(const std::string& s, std::size_t start) : in_(s, "scan update", start) {}
    std::uint64_t varint() { return in_.varint(); }
    std::uint64_t raw64() { return in_.u64(); }
    double real64() { return in_.f64(); }
    float real32() { return in_.f32(); }
    bool atEnd() const { return in_.done(); }
    std::vector<std::uint64_t> codes() {
        const std::uint64_t n = varint();
        if (n > in_.remaining()) throw std::runtime_error("scan update: list longer than the data");
        std::vector<std::uint64_t> out(n);
        std::uint64_t prev = 0;
        for (auto& c : out) prev = c = prev + varint();
        return out;
    }
    std::vector<GroundCellSample> groundCells() {
        const std::uint64_t n = varint();
        if (n > in_.remaining() / 42) throw std::runtime_error("scan update: list longer than the data");
        std::vector<GroundCellSample> out(n);
        std::uint64_t prev = 0;
        for (auto& c : out) {
            prev += varint();
            if (prev > 0xffffffffULL) throw std::runtime_error("scan update: cell out of range");
            c.cell = std::uint32_t(prev);
            const std::uint64_t count = varint();
            if (count > 0xffffffffULL) throw std::runtime_error("scan update: count out of range");
            c.count = std::uint32_t(count);
            c.sumZ = real64(), c.sumZ2 = real64(), c.sumX = real64(), c.sumY = real64(), c.minZ = real32(), c.maxZ = real32();
        }
        return out;
    }

    std::vector<gseg::TerrainSample> terrainSamples() {
        const std::uint64_t n = varint();
        if (n > in_.remaining() / 25) throw std::runtime_error("scan update: list longer than the data");
        std::vector<gseg::TerrainSample> out(n);
        for (auto& t : out) {
            const std::uint64_t cell = raw64();
            t.ix = std::int32_t(std::uint32_t(cell >> 32)), t.iy = std::int32_t(std::uint32_t(cell));
            const std::uint64_t count = varint();
            if (count > 0xffffffffULL) throw std::runtime_error("scan update: count out of range");
            t.groundCount = std::uint32_t(count);
            t.groundSumZ = real64(), t.lowZ = real32(), t.highZ = real32();
        }
        return out;
    }

private:
    io::ByteReader in_;
};

const char kMagic[] = "GSU3", kMagicV2[] = "GSU2", kMagicV1[] = "GSU1";

}  // namespace

bool ScanUpdate::operator==(const ScanUpdate& o) const {
    return origin == o.origin && free == o.free && groundHits == o.groundHits && obstacleHits == o.obstacleHits &&
           groundPoints == o.groundPoints && obstaclePoints == o.obstaclePoints && rays == o.rays &&
           pointsSkipped == o.pointsSkipped && groundCells == o.groundCells && terrain == o.terrain;
}

ScanUpdate castScan(const PointCloudView& ground, const PointCloudView& obstacles, const Eigen::Vector3d& sensorOrigin,
                    const TraversabilityOptions& options) {
    options.validate();
    if (!sensorOrigin.allFinite()) throw std::invalid_argument("castScan: sensor origin is not finite");
    thread_local std::unique_ptr<Caster> buffers;  // reused scan after scan, one set per thread
    if (!buffers) buffers = std::make_unique<Caster>();
    Caster& caster = *buffers;  // a plain pointer from here: no thread-local lookups in the loops
    caster.begin(options, sensorOrigin);
    ScanUpdate u;
    u.origin = sensorOrigin;
    u.groundPoints = ground.size();
    u.obstaclePoints = obstacles.size();
    caster.collect(ground, caster.groundHits(), u);
    caster.collect(obstacles, caster.obstacleHits(), u);
    caster.castRays();
    u.rays = caster.rays();
    u.free = caster.crossed().sortedCodes({&caster.groundHits(), &caster.obstacleHits()});
    u.groundHits = caster.groundHits().sortedCodes();
    u.obstacleHits = caster.obstacleHits().sortedCodes();
    u.groundCells = caster.groundCells(ground);
    if (options.driveTerrain) u.terrain = gseg::terrainSamples(ground, obstacles, options.resolution, options.maxRange, sensorOrigin);
    return u;
}

std::string serializeScanUpdate(const ScanUpdate& u) {
    io::ByteWriter out;
    out.raw(kMagic, 4);
    for (int a = 0; a < 3; ++a) out.f64(u.origin[a]);
    for (std::uint64_t v : {u.groundPoints, u.obstaclePoints, u.rays, u.pointsSkipped}) out.varint(v);
    for (const auto* list : {&u.free, &u.groundHits, &u.obstacleHits}) {
        out.varint(list->size());
        std::uint64_t prev = 0;
        for (std::uint64_t c : *list) out.varint(c - prev), prev = c;
    }
    out.varint(u.groundCells.size());
    std::uint64_t prev = 0;
    for (const GroundCellSample& c : u.groundCells) {
        out.varint(c.cell - prev), prev = c.cell;
        out.varint(c.count);
        out.f64(c.sumZ).f64(c.sumZ2).f64(c.sumX).f64(c.sumY).f32(c.minZ).f32(c.maxZ);
    }
    out.varint(u.terrain.size());
    for (const gseg::TerrainSample& t : u.terrain) {
        out.u64((std::uint64_t(std::uint32_t(t.ix)) << 32) | std::uint32_t(t.iy));
        out.varint(t.groundCount);
        out.f64(t.groundSumZ).f32(t.lowZ).f32(t.highZ);
    }
    return out.take();
}

ScanUpdate deserializeScanUpdate(const std::string& bytes) {
    const bool v1 = bytes.compare(0, 4, kMagicV1) == 0, v2 = bytes.compare(0, 4, kMagicV2) == 0;
    if (!v1 && !v2 && bytes.compare(0, 4, kMagic) != 0) throw std::runtime_error("scan update: not a gseg scan update (bad magic)");
    ScanUpdate u;
    Reader in(bytes, 4);
    for (int a = 0; a < 3; ++a) u.origin[a] = in.real64();
    u.groundPoints = in.varint(), u.obstaclePoints = in.varint(), u.rays = in.varint(), u.pointsSkipped = in.varint();
    u.free = in.codes();
    u.groundHits = in.codes();
    u.obstacleHits = in.codes();
    if (!v1) u.groundCells = in.groundCells();
    if (!v1 && !v2) u.terrain = in.terrainSamples();
    if (!in.atEnd()) throw std::runtime_error("scan update: trailing bytes");
    return u;
}

}  // namespace gseg::map
