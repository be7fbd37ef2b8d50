#include <gseg/map/scan_update.hpp>

#include <gseg/io/bytes.hpp>

#include "voxel_keys.hpp"
#include "../cpu_features.hpp"

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
#include <array>

namespace gseg::map {
namespace {

using detail::BrickSet;
using detail::mortonCode;

constexpr std::uint64_t kAxisMask[3] = {0x249249249249ULL, 0x249249249249ULL << 1, 0x249249249249ULL << 2};

/// The state of OctoMap's incremental ray loop (OcTree::computeRayKeys(), OctoMap 1.9.7).
struct Ray {
    double t[3];             ///< tMax: the ray parameter [m] at the next voxel border per axis
    double delta[3];         ///< tDelta: between two borders per axis
    std::uint64_t flip[3];   ///< the axis bits where the ray steps down (step -1), else 0
    double length;           ///< [m] of the ray, as a float widened
    std::uint64_t code, end;  ///< Morton codes of the current voxel and of the end's
};

/// The loop of OcTree::computeRayKeys(): the axis of the smallest tMax steps (ties: the later
/// axis) and its tMax grows by its tDelta, until the end's voxel or min(tMax) > length. The same
/// comparisons and additions in the same order, so the same voxels, written to path[0, n) (the
/// origin's voxel not included). Stops early when `capacity` voxels are written: returns true
/// then (call again to go on). A step along axis a counts the axis bits of the Morton code up
/// (complemented before and after where the ray steps down), the other bits kept. Not inlined:
/// without a call in its loop, the state stays in registers.
[[gnu::noinline]] bool walkRay(Ray& r, std::uint64_t* path, std::size_t capacity, std::size_t& n) {
    constexpr std::uint64_t m0 = kAxisMask[0], m1 = kAxisMask[1], m2 = kAxisMask[2];
    const std::uint64_t f0 = r.flip[0], f1 = r.flip[1], f2 = r.flip[2];
    const double d0 = r.delta[0], d1 = r.delta[1], d2 = r.delta[2], length = r.length;
    double t0 = r.t[0], t1 = r.t[1], t2 = r.t[2];
    std::uint64_t code = r.code;
    const std::uint64_t end = r.end;
    bool more = false;
    std::size_t k = 0;
    while (true) {
        if (t0 < t1 && t0 < t2) {
            code = ((((((code ^ f0) | ~m0) + 1) & m0) ^ f0) | (code & ~m0));
            t0 += d0;
        } else if (!(t0 < t1) && t1 < t2) {
            code = ((((((code ^ f1) | ~m1) + 1) & m1) ^ f1) | (code & ~m1));
            t1 += d1;
        } else {
            code = ((((((code ^ f2) | ~m2) + 1) & m2) ^ f2) | (code & ~m2));
            t2 += d2;
        }
        if (code == end) break;
        if (t0 > length && t1 > length && t2 > length) break;  // min(tMax) > length
        path[k++] = code;
        if (k == capacity) {
            more = true;
            break;
        }
    }
    r.t[0] = t0, r.t[1] = t1, r.t[2] = t2, r.code = code;
    n = k;
    return more;
}

// ---- four rays at a time ----
//
// The loop above waits on its branches: which axis steps next changes from step to step in a way
// the CPU cannot predict, and each step depends on the last. Four rays stepped together, without
// branches (the axis chosen by masks, the other axes' tMax growing by +0.0, which leaves them as
// they are), keep four independent chains busy: each lane does walkRay()'s comparisons and
// additions in its order, so the same voxels.

using V4d = double __attribute__((vector_size(32)));
using V4u = std::uint64_t __attribute__((vector_size(32)));
using V4l = std::int64_t __attribute__((vector_size(32)));

/// The state of four rays (walkRay()'s Ray, one lane each) and each lane's last voxel written.
struct Lanes {
    V4d t0, t1, t2, d0, d1, d2, length;
    V4u code, end, f0, f1, f2, last;
};

/// Steps the four lanes until a lane's ray ends (its end's voxel, or min(tMax) > length) or
/// `room` steps are taken. Every step writes the four lanes' voxels to out[4 * step + lane]; a lane
/// whose ray ends in that step writes its last voxel again instead (already written, or the
/// origin's). Returns the steps taken; `ended` gets bit i for each lane i whose ray ended.
[[gnu::always_inline]] inline std::size_t stepLanesBody(Lanes& s, std::uint64_t* out, std::size_t room, unsigned& ended) {
    const V4u m0 = V4u{} + kAxisMask[0], m1 = V4u{} + kAxisMask[1], m2 = V4u{} + kAxisMask[2];
    const V4d d0 = s.d0, d1 = s.d1, d2 = s.d2, length = s.length;
    const V4u f0 = s.f0, f1 = s.f1, f2 = s.f2, end = s.end;
    V4d t0 = s.t0, t1 = s.t1, t2 = s.t2;
    V4u code = s.code, last = s.last;
    std::size_t n = 0;
    ended = 0;
    while (n < room) {
        const V4l lt01 = t0 < t1, lt12 = t1 < t2;
        const V4l a0 = lt01 & (t0 < t2), a1 = ~lt01 & lt12, a2 = ~(a0 | a1);
        const V4u m = (V4u(a0) & m0) | (V4u(a1) & m1) | (V4u(a2) & m2);
        const V4u f = (V4u(a0) & f0) | (V4u(a1) & f1) | (V4u(a2) & f2);
        code = ((((((code ^ f) | ~m) + 1) & m) ^ f) | (code & ~m));
        t0 += V4d(V4l(d0) & a0);
        t1 += V4d(V4l(d1) & a1);
        t2 += V4d(V4l(d2) & a2);
        const V4l done = V4l(code == end) | ((t0 > length) & (t1 > length) & (t2 > length));
        last = (V4u(done) & last) | (V4u(~done) & code);
        std::memcpy(out + 4 * n, &last, sizeof last);
        ++n;
        if ((done[0] | done[1] | done[2] | done[3]) != 0) {
            for (unsigned i = 0; i < 4; ++i) ended |= unsigned(done[i] != 0) << i;
            break;
        }
    }
    s.t0 = t0, s.t1 = t1, s.t2 = t2, s.code = code, s.last = last;
    return n;
}

[[gnu::noinline]] std::size_t stepLanes(Lanes& s, std::uint64_t* out, std::size_t room, unsigned& ended) {
    return stepLanesBody(s, out, room, ended);
}

#if defined(__GNUC__) && defined(__x86_64__)
/// The same on CPUs with AVX2: one instruction for the four lanes where SSE2 takes two.
__attribute__((target("avx2"))) [[gnu::noinline]] std::size_t stepLanesAvx2(Lanes& s, std::uint64_t* out, std::size_t room, unsigned& ended) {
    return stepLanesBody(s, out, room, ended);
}
#endif

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

    /// Every voxel from the origin's up to (not including) each ray end's: four rays at a time
    /// (stepLanes()), the last ones one at a time.
    void castRays() {
        std::size_t next = 0;
        Lanes lanes{};
        unsigned free = 0;  // lanes left without a ray
        auto fill = [&](unsigned lanesToFill) {  // the next rays into these lanes
            for (unsigned i = 0; i < 4; ++i) {
                Ray ray{};
                if (!(lanesToFill >> i & 1)) continue;
                if (nextRay(next, ray)) setLane(lanes, i, ray);
                else free |= 1u << i;
            }
        };
        fill(0xf);
        if (free == 0xf) return;  // no ray leaves the origin's voxel
        crossed_.insert(originCode_);  // every ray that leaves the origin's voxel starts there
        std::size_t rows = 0;
        const bool avx2 = gseg::detail::cpuHasAvx2();
        while (free == 0) {
            if (rows == kRows) crossed_.insertAll(path_.data(), 4 * rows), rows = 0;
            unsigned ended = 0;
#if defined(__GNUC__) && defined(__x86_64__)
            rows += avx2 ? stepLanesAvx2(lanes, path_.data() + 4 * rows, kRows - rows, ended)
                         : stepLanes(lanes, path_.data() + 4 * rows, kRows - rows, ended);
#else
            rows += stepLanes(lanes, path_.data() + 4 * rows, kRows - rows, ended);
#endif
            fill(ended);
        }
        crossed_.insertAll(path_.data(), 4 * rows);
        for (unsigned i = 0; i < 4; ++i)  // the rays still going, to their ends
            if (!(free >> i & 1)) walk(laneRay(lanes, i));
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

    /// The start of OcTree::computeRayKeys(origin, end) (OctoMap 1.9.7) as `ray`; false if the end
    /// lies in the origin's voxel (no ray).
    bool rayOf(const octomap::point3d& end, std::uint64_t endCode, Ray& ray) const {
        if (endCode == originCode_) return false;
        octomap::point3d direction = (end - origin_);
        const float length = float(direction.norm());
        direction /= length;
        const double resolution = geometry_->getResolution();
        for (int i = 0; i < 3; ++i) {
            const int step = direction(i) > 0.0 ? 1 : direction(i) < 0.0 ? -1 : 0;
            ray.flip[i] = step < 0 ? kAxisMask[i] : 0;
            if (step != 0) {
                double voxelBorder = geometry_->keyToCoord(originKey_[unsigned(i)]);
                voxelBorder += float(step * resolution * 0.5);
                ray.t[i] = (voxelBorder - origin_(i)) / direction(i);
                ray.delta[i] = resolution / std::fabs(direction(i));
            } else {
                ray.t[i] = ray.delta[i] = std::numeric_limits<double>::max();
            }
        }
        ray.length = double(length), ray.code = originCode_, ray.end = endCode;
        return true;
    }

    /// The next ray of the scan from endpoint `next` on (skipping ends in the origin's voxel);
    /// false when none is left.
    bool nextRay(std::size_t& next, Ray& ray) const {
        while (next < endPoints_.size()) {
            const std::size_t r = next++;
            if (rayOf(endPoints_[r], endCodes_[r], ray)) return true;
        }
        return false;
    }

    void setLane(Lanes& s, unsigned i, const Ray& r) const {
        s.t0[i] = r.t[0], s.t1[i] = r.t[1], s.t2[i] = r.t[2];
        s.d0[i] = r.delta[0], s.d1[i] = r.delta[1], s.d2[i] = r.delta[2];
        s.f0[i] = r.flip[0], s.f1[i] = r.flip[1], s.f2[i] = r.flip[2];
        s.length[i] = r.length, s.code[i] = r.code, s.end[i] = r.end, s.last[i] = originCode_;
    }

    static Ray laneRay(const Lanes& s, unsigned i) {
        return Ray{{s.t0[i], s.t1[i], s.t2[i]}, {s.d0[i], s.d1[i], s.d2[i]}, {s.f0[i], s.f1[i], s.f2[i]}, s.length[i], s.code[i], s.end[i]};
    }

    /// OctoMap's incremental loop from `ray`'s state to its end, kPath voxels at a time (walkRay()),
    /// each batch then marked in crossed_ brick by brick.
    void walk(Ray ray) {
        bool more = true;
        while (more) {
            std::size_t n = 0;
            more = walkRay(ray, path_.data(), kPath, n);
            crossed_.insertAll(path_.data(), n);
        }
    }

    static constexpr std::size_t kRows = 1024, kPath = 4 * kRows;
    std::array<std::uint64_t, kPath> path_;  ///< the voxels of the rays being cast (four lanes, or one ray)
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
