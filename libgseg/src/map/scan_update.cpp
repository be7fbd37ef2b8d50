#include <gseg/map/scan_update.hpp>

#include <gseg/io/bytes.hpp>

#include "voxel_keys.hpp"
#include "../cpu_features.hpp"

#include <octomap/OcTree.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iomanip>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <algorithm>
#include <array>

namespace gseg::map {
namespace {

using detail::BrickSet;
using detail::mortonCode;

constexpr std::uint64_t kAxisMask[3] = {0x249249249249ULL, 0x249249249249ULL << 1, 0x249249249249ULL << 2};

/// Per-axis sum and difference of Morton codes: each axis's key added (subtracted) modulo 2^16,
/// the carries kept within the axis by filling (clearing) the other axes' bits.
inline std::uint64_t mortonAdd(std::uint64_t a, std::uint64_t b) {
    std::uint64_t out = 0;
    for (const std::uint64_t m : kAxisMask) out |= ((a | ~m) + (b & m)) & m;
    return out;
}
inline std::uint64_t mortonSub(std::uint64_t a, std::uint64_t b) {
    std::uint64_t out = 0;
    for (const std::uint64_t m : kAxisMask) out |= ((a & m) - (b & m)) & m;
    return out;
}

/// The voxels a scan's rays cross, one bit each in a cube of 2^kSideBits voxels per axis around
/// the sensor (where most ray steps are: every ray starts there), a BrickSet beyond it. The rays
/// are stepped in the cube's own codes: the Morton code of a voxel's key minus the cube's corner
/// (per axis, modulo 2^16), so a voxel lies in the cube exactly when its code is below
/// 2^(3 kSideBits) and marking it is one bit set at that position, with no brick to look up. The
/// corner is a multiple of 8 voxels per axis: the cube's bricks are the map's bricks.
class Window {
public:
    static constexpr unsigned kSideBits = 9;
    static constexpr std::uint64_t kVoxels = 1ULL << (3 * kSideBits);
    static constexpr unsigned kSide = 1u << kSideBits;

    /// Centres the cube on the voxel `originCode` (map code); the cube must be empty (moveTo()).
    void begin(std::uint64_t originCode) {
        const octomap::OcTreeKey k = detail::keyOfCode(originCode);
        octomap::OcTreeKey c;
        for (unsigned a = 0; a < 3; ++a) {
            cornerKey_[a] = (int(k[a]) - int(1u << (kSideBits - 1))) & ~7;  // may be negative at the extent's edge
            c[a] = std::uint16_t(cornerKey_[a] & 0xffff);
        }
        corner_ = detail::mortonCode(c);
        if (!words_ || dirty_) {  // first, or after a throw: zeroed pages, which take memory only once marked
            words_.reset(static_cast<std::uint64_t*>(std::calloc(kVoxels / 64, sizeof(std::uint64_t))));
            if (!words_) throw std::bad_alloc();
        }
        far_.clear();
        dirty_ = true;
    }
    /// The cube's code of a map code.
    std::uint64_t local(std::uint64_t code) const { return mortonSub(code, corner_); }

    /// Marks the voxels codes[0, n) (the cube's codes).
    void mark(const std::uint64_t* codes, std::size_t n) {
        std::uint64_t* const words = words_.get();
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint64_t c = codes[i];
            if (c < kVoxels) {
                words[c >> 6] |= 1ULL << (c & 63);
            } else {
                far_.insert(c);
            }
        }
    }

    /// Every marked voxel into `out` (map codes), the cube emptied for the next scan. `lo` and
    /// `hi`: per axis, the least and greatest key of the origin's and the ray ends' voxels. A ray
    /// crosses only voxels within them but for rounding at a voxel border (one voxel beyond the
    /// end's on one axis), so a margin of two voxels bounds every marked voxel.
    void moveTo(BrickSet& out, const int lo[3], const int hi[3]) {
        int from[3], to[3];  // the cube's bricks within the box, per axis
        for (unsigned a = 0; a < 3; ++a) {
            from[a] = std::max(0, lo[a] - 2 - cornerKey_[a]) >> 3;
            to[a] = std::min(int(kSide) - 1, hi[a] + 2 - cornerKey_[a]) >> 3;
        }
        for (int z = from[2]; z <= to[2]; ++z)
            for (int y = from[1]; y <= to[1]; ++y)
                for (int x = from[0]; x <= to[0]; ++x) {
                    const std::uint64_t brick = detail::spreadBits(unsigned(x)) | (detail::spreadBits(unsigned(y)) << 1) | (detail::spreadBits(unsigned(z)) << 2);
                    std::uint64_t* w = &words_[brick << 3];
                    if ((w[0] | w[1] | w[2] | w[3] | w[4] | w[5] | w[6] | w[7]) == 0) continue;
                    out.insertBrick(mapBrick(brick), w);
                    std::fill(w, w + 8, 0);
                }
        far_.forEachBrick([&](std::uint64_t brick, const std::uint64_t* w) { out.insertBrick(mapBrick(brick), w); });
        dirty_ = false;
    }

private:
    std::uint64_t corner_ = 0;            ///< Morton code of the cube's corner (map code)
    int cornerKey_[3] = {0, 0, 0};        ///< the corner's key per axis
    struct Free {
        void operator()(std::uint64_t* p) const { std::free(p); }
    };
    std::unique_ptr<std::uint64_t[], Free> words_;  ///< one bit per voxel of the cube, in its codes' order
    BrickSet far_;                        ///< the voxels beyond the cube (the cube's codes)
    bool dirty_ = false;                  ///< begun and not emptied by moveTo()

    std::uint64_t mapBrick(std::uint64_t brick) const { return mortonAdd(brick << 9, corner_) >> 9; }
};

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
        const double inside = o.maxRange * (1 - 1e-9);
        insideSq_ = inside * inside;
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
        window_.begin(originCode_);
        originLocal_ = window_.local(originCode_);
        for (unsigned a = 0; a < 3; ++a) boxLo_[a] = boxHi_[a] = int(originKey_[a]);
        for (BrickSet* b : {&ends_, &groundHits_, &obstacleHits_, &crossed_}) b->clear();
        endPoints_.clear();
        endCodes_.clear();
    }

    BrickSet& groundHits() { return groundHits_; }

    /// Per-cell sums of the ground points within maxRange (sorted by cell).
    std::vector<GroundCellSample> groundCells(const PointCloudView& pts) {
        cells_.clear();
        std::vector<GroundCellSample> out;
        std::size_t last = SIZE_MAX;  // the last point's cell in out: the next point mostly shares it
        for (std::size_t i = 0; i < pts.size(); ++i) {
            const octomap::point3d p(pts.x(i), pts.y(i), pts.z(i));
            octomap::OcTreeKey key;
            if (!withinRange((p - origin_).norm_sq()) || !keyOf(p, key)) continue;
            const std::uint32_t cell = (std::uint32_t(key[0]) << 16) | key[1];
            const double z = pts.z(i);
            if (last == SIZE_MAX || out[last].cell != cell) {
                bool added = false;
                last = cells_.insert(cell, added);
                if (added) {
                    out.emplace_back();
                    out.back().cell = cell, out.back().minZ = out.back().maxZ = float(z);
                }
            }
            GroundCellSample& c = out[last];
            ++c.count, c.sumZ += z, c.sumZ2 += z * z, c.sumX += pts.x(i), c.sumY += pts.y(i);
            c.minZ = std::min(c.minZ, float(z)), c.maxZ = std::max(c.maxZ, float(z));
        }
        std::sort(out.begin(), out.end(), [](const GroundCellSample& a, const GroundCellSample& b) { return a.cell < b.cell; });
        return out;
    }
    BrickSet& obstacleHits() { return obstacleHits_; }

    /// Hits and ray ends of a point set (the first point of each endpoint voxel ends a ray).
    void collect(const PointCloudView& pts, BrickSet& hits, ScanUpdate& u) {
        for (std::size_t i = 0; i < pts.size(); ++i) {
            octomap::point3d p(pts.x(i), pts.y(i), pts.z(i));
            const octomap::point3d d = p - origin_;
            const double squared = d.norm_sq();
            const bool hit = withinRange(squared);
            const double range = hit ? 0 : std::sqrt(squared);  // only a ray cut at maxRange needs it
            if (!hit) p = origin_ + d * float(maxRange_ / range);
            octomap::OcTreeKey key;
            if (!std::isfinite(range) || !keyOf(p, key)) {
                ++u.pointsSkipped;
                continue;
            }
            const std::uint64_t code = mortonCode(key);
            if (hit) hits.insert(code);
            if (ends_.insert(code)) {
                endPoints_.push_back(p), endCodes_.push_back(code);
                for (unsigned a = 0; a < 3; ++a) boxLo_[a] = std::min(boxLo_[a], int(key[a])), boxHi_[a] = std::max(boxHi_[a], int(key[a]));
            }
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
        if (free == 0xf) return window_.moveTo(crossed_, boxLo_, boxHi_);  // no ray leaves the origin's voxel
        window_.mark(&originLocal_, 1);  // every ray that leaves the origin's voxel starts there
        std::size_t rows = 0;
        const bool avx2 = gseg::detail::cpuHasAvx2();
        while (free == 0) {
            if (rows == kRows) window_.mark(path_.data(), 4 * rows), rows = 0;
            unsigned ended = 0;
#if defined(__GNUC__) && defined(__x86_64__)
            rows += avx2 ? stepLanesAvx2(lanes, path_.data() + 4 * rows, kRows - rows, ended)
                         : stepLanes(lanes, path_.data() + 4 * rows, kRows - rows, ended);
#else
            rows += stepLanes(lanes, path_.data() + 4 * rows, kRows - rows, ended);
#endif
            fill(ended);
        }
        window_.mark(path_.data(), 4 * rows);
        for (unsigned i = 0; i < 4; ++i)  // the rays still going, to their ends
            if (!(free >> i & 1)) walk(laneRay(lanes, i));
        window_.moveTo(crossed_, boxLo_, boxHi_);
    }
    std::size_t rays() const { return endPoints_.size(); }
    const BrickSet& crossed() const { return crossed_; }

private:
    std::unique_ptr<octomap::OcTree> geometry_;  ///< an empty tree: key arithmetic only
    double maxRange_ = 0, limit_ = 0;
    double insideSq_ = 0;  ///< below this squared range a point is within maxRange_ without taking the root

    /// Whether a point at this squared distance (octomap's norm_sq()) lies within maxRange_, as
    /// octomap's norm() <= maxRange_ says, the root taken only near the limit.
    bool withinRange(double squared) const { return squared <= insideSq_ || std::sqrt(squared) <= maxRange_; }
    octomap::point3d origin_;
    octomap::OcTreeKey originKey_;
    std::uint64_t originCode_ = 0, originLocal_ = 0;  ///< the origin's voxel: map code, window_'s code
    Window window_;  ///< the voxels the rays cross, until castRays() ends
    int boxLo_[3] = {0, 0, 0}, boxHi_[3] = {0, 0, 0};  ///< the keys of the origin and the ray ends: the least and greatest per axis
    BrickSet ends_, groundHits_, obstacleHits_, crossed_;
    std::vector<octomap::point3d> endPoints_;
    std::vector<std::uint64_t> endCodes_;
    detail::CodeIndex cells_;  ///< groundCells(): a cell -> its place in the list

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
        ray.length = double(length), ray.code = originLocal_, ray.end = window_.local(endCode);
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
        s.length[i] = r.length, s.code[i] = r.code, s.end[i] = r.end, s.last[i] = originLocal_;
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
            window_.mark(path_.data(), n);
        }
    }

    static constexpr std::size_t kRows = 1024, kPath = 4 * kRows;
    std::array<std::uint64_t, kPath> path_;  ///< the voxels of the rays being cast (four lanes, or one ray)
};

// ---- byte encoding (gseg/io/bytes.hpp) ----

/// Morton codes of 16-bit keys hold 48 bits; brick codes their upper 39.
constexpr std::uint64_t kCodeLimit = 1ULL << 48, kBrickLimit = kCodeLimit >> 9;

/// Reads the lists of a scan update; errors say "scan update: ...".
class Reader {
public:
    Reader(const std::string& s, std::size_t start) : in_(s, "scan update", start) {}
    std::uint64_t varint() { return in_.varint(); }
    std::uint8_t byte() { return in_.u8(); }
    std::uint64_t raw64() { return in_.u64(); }
    double real64() { return in_.f64(); }
    float real32() { return in_.f32(); }
    bool atEnd() const { return in_.done(); }
    std::vector<std::uint64_t> codes() {
        const std::uint64_t n = varint();
        if (n > in_.remaining()) throw std::runtime_error("scan update: list longer than the data");
        std::vector<std::uint64_t> out(n);
        std::uint64_t prev = 0;
        for (auto& c : out) {
            const std::uint64_t delta = varint();
            if (delta >= kCodeLimit - prev) throw std::runtime_error("scan update: voxel out of range");
            prev = c = prev + delta;
        }
        return out;
    }
    /// writeBricks()'s set: bricks increasing, none empty, within the Morton codes' range.
    VoxelBricks bricks() {
        const std::uint64_t n = varint();
        if (n > in_.remaining() / 10) throw std::runtime_error("scan update: list longer than the data");
        VoxelBricks v;
        v.bricks.resize(n), v.words.assign(8 * n, 0);
        std::uint64_t prev = 0;
        for (std::uint64_t b = 0; b < n; ++b) {
            const std::uint64_t delta = varint();
            if (b > 0 && delta == 0) throw std::runtime_error("scan update: bricks out of order");
            if (delta >= kBrickLimit - prev) throw std::runtime_error("scan update: brick out of range");
            prev = v.bricks[b] = prev + delta;
            const unsigned present = byte();
            if (present == 0) throw std::runtime_error("scan update: empty brick");
            for (unsigned k = 0; k < 8; ++k)
                if (present >> k & 1) {
                    v.words[8 * b + k] = raw64();
                    if (v.words[8 * b + k] == 0) throw std::runtime_error("scan update: empty word");
                }
        }
        return v;
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

const char kMagic[] = "GSU4", kMagicV3[] = "GSU3", kMagicV2[] = "GSU2", kMagicV1[] = "GSU1";

void writeBricks(io::ByteWriter& out, const VoxelBricks& v) {
    out.varint(v.bricks.size());
    std::uint64_t prev = 0;
    for (std::size_t b = 0; b < v.bricks.size(); ++b) {
        out.varint(v.bricks[b] - prev), prev = v.bricks[b];
        const std::uint64_t* w = &v.words[8 * b];
        unsigned present = 0;
        for (unsigned k = 0; k < 8; ++k) present |= unsigned(w[k] != 0) << k;
        out.u8(std::uint8_t(present));
        for (unsigned k = 0; k < 8; ++k)
            if (w[k]) out.u64(w[k]);
    }
}

}  // namespace

std::size_t VoxelBricks::voxels() const {
    std::size_t n = 0;
    for (std::uint64_t w : words) n += std::size_t(__builtin_popcountll(w));
    return n;
}

std::vector<std::uint64_t> VoxelBricks::codes() const {
    std::vector<std::uint64_t> out;
    out.reserve(voxels());
    for (std::size_t b = 0; b < bricks.size(); ++b)
        for (std::uint64_t w = 0; w < 8; ++w)
            for (std::uint64_t bits = words[8 * b + w]; bits; bits &= bits - 1)
                out.push_back((bricks[b] << 9) | (w << 6) | std::uint64_t(__builtin_ctzll(bits)));
    return out;
}

VoxelBricks VoxelBricks::fromCodes(const std::vector<std::uint64_t>& codes) {
    VoxelBricks v;
    for (std::uint64_t c : codes) {
        if (v.bricks.empty() || v.bricks.back() != c >> 9) v.bricks.push_back(c >> 9), v.words.resize(v.words.size() + 8, 0);
        v.words[v.words.size() - 8 + ((c >> 6) & 7)] |= 1ULL << (c & 63);
    }
    return v;
}

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
    caster.crossed().sortedBricks(u.free.bricks, u.free.words, {&caster.groundHits(), &caster.obstacleHits()});
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
    writeBricks(out, u.free);
    for (const auto* list : {&u.groundHits, &u.obstacleHits}) {
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
    const bool v1 = bytes.compare(0, 4, kMagicV1) == 0, v2 = bytes.compare(0, 4, kMagicV2) == 0, v3 = bytes.compare(0, 4, kMagicV3) == 0;
    if (!v1 && !v2 && !v3 && bytes.compare(0, 4, kMagic) != 0) throw std::runtime_error("scan update: not a gseg scan update (bad magic)");
    ScanUpdate u;
    Reader in(bytes, 4);
    for (int a = 0; a < 3; ++a) u.origin[a] = in.real64();
    u.groundPoints = in.varint(), u.obstaclePoints = in.varint(), u.rays = in.varint(), u.pointsSkipped = in.varint();
    u.free = v1 || v2 || v3 ? VoxelBricks::fromCodes(in.codes()) : in.bricks();
    u.groundHits = in.codes();
    u.obstacleHits = in.codes();
    if (!v1) u.groundCells = in.groundCells();
    if (!v1 && !v2) u.terrain = in.terrainSamples();
    if (!in.atEnd()) throw std::runtime_error("scan update: trailing bytes");
    return u;
}

}  // namespace gseg::map
