#include <gseg/map/scan_update.hpp>

#include "voxel_keys.hpp"

#include <octomap/OcTree.h>

#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

namespace gseg::map {
namespace {

using detail::BrickSet;
using detail::mortonCode;

/// Ray casting of one scan against an empty tree of the map's geometry (OctoMap's own ray
/// traversal, so the voxels are exactly those OcTree::insertPointCloud would touch).
class Caster {
public:
    Caster(const TraversabilityOptions& o, const Eigen::Vector3d& sensorOrigin)
        : geometry_(o.resolution), maxRange_(o.maxRange), limit_(2 * o.extent()),
          origin_(float(sensorOrigin.x()), float(sensorOrigin.y()), float(sensorOrigin.z())) {
        octomap::OcTreeKey k;
        if (!keyOf(origin_, k)) {
            std::ostringstream s;
            s.precision(3);
            s << std::fixed << "sensor position (" << sensorOrigin.x() << ", " << sensorOrigin.y() << ", " << sensorOrigin.z()
              << ") m lies outside the map's extent of +-" << o.extent() << " m (" << o.resolution << " m voxels)";
            throw std::out_of_range(s.str());
        }
    }

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
            if (ends_.insert(code)) endPoints_.push_back(p);
        }
    }

    /// Every voxel from the origin's up to (not including) each ray end's.
    void castRays(BrickSet& crossed) {
        octomap::KeyRay ray;
        for (const auto& end : endPoints_) {
            geometry_.computeRayKeys(origin_, end, ray);
            for (const auto& k : ray) crossed.insert(mortonCode(k));
        }
    }
    std::size_t rays() const { return endPoints_.size(); }

private:
    octomap::OcTree geometry_;
    double maxRange_, limit_;
    octomap::point3d origin_;
    BrickSet ends_;
    std::vector<octomap::point3d> endPoints_;

    bool keyOf(const octomap::point3d& p, octomap::OcTreeKey& key) const {
        for (int a = 0; a < 3; ++a)  // far outside: rejected before OctoMap's int conversion can overflow
            if (!(std::abs(double(p(a))) < limit_)) return false;
        return geometry_.coordToKeyChecked(p, key);
    }
};

// ---- byte encoding ----

void putVarint(std::string& out, std::uint64_t v) {
    while (v >= 0x80) out.push_back(char(std::uint8_t(v) | 0x80)), v >>= 7;
    out.push_back(char(v));
}

void putRaw64(std::string& out, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) out.push_back(char(std::uint8_t(v >> (8 * i))));
}

class Reader {
public:
    Reader(const std::string& s, std::size_t start) : s_(s), pos_(start) {}
    std::uint64_t varint() {
        std::uint64_t v = 0;
        for (int shift = 0; shift < 64; shift += 7) {
            const std::uint8_t b = byte();
            v |= std::uint64_t(b & 0x7f) << shift;
            if (!(b & 0x80)) return v;
        }
        throw std::runtime_error("scan update: malformed number");
    }
    std::uint64_t raw64() {
        std::uint64_t v = 0;
        for (int i = 0; i < 8; ++i) v |= std::uint64_t(byte()) << (8 * i);
        return v;
    }
    std::vector<std::uint64_t> codes() {
        const std::uint64_t n = varint();
        if (n > s_.size() - pos_) throw std::runtime_error("scan update: list longer than the data");
        std::vector<std::uint64_t> out(n);
        std::uint64_t prev = 0;
        for (auto& c : out) prev = c = prev + varint();
        return out;
    }
    bool atEnd() const { return pos_ == s_.size(); }

private:
    const std::string& s_;
    std::size_t pos_;
    std::uint8_t byte() {
        if (pos_ >= s_.size()) throw std::runtime_error("scan update: truncated");
        return std::uint8_t(s_[pos_++]);
    }
};

const char kMagic[] = "GSU1";

}  // namespace

bool ScanUpdate::operator==(const ScanUpdate& o) const {
    return origin == o.origin && free == o.free && groundHits == o.groundHits && obstacleHits == o.obstacleHits &&
           groundPoints == o.groundPoints && obstaclePoints == o.obstaclePoints && rays == o.rays &&
           pointsSkipped == o.pointsSkipped;
}

ScanUpdate castScan(const PointCloudView& ground, const PointCloudView& obstacles, const Eigen::Vector3d& sensorOrigin,
                    const TraversabilityOptions& options) {
    options.validate();
    if (!sensorOrigin.allFinite()) throw std::invalid_argument("castScan: sensor origin is not finite");
    Caster caster(options, sensorOrigin);
    ScanUpdate u;
    u.origin = sensorOrigin;
    u.groundPoints = ground.size();
    u.obstaclePoints = obstacles.size();
    BrickSet groundHits, obstacleHits, crossed;
    caster.collect(ground, groundHits, u);
    caster.collect(obstacles, obstacleHits, u);
    caster.castRays(crossed);
    u.rays = caster.rays();
    u.free = crossed.sortedCodes({&groundHits, &obstacleHits});
    u.groundHits = groundHits.sortedCodes();
    u.obstacleHits = obstacleHits.sortedCodes();
    return u;
}

std::string serializeScanUpdate(const ScanUpdate& u) {
    std::string out(kMagic, 4);
    for (int a = 0; a < 3; ++a) {
        std::uint64_t bits = 0;
        std::memcpy(&bits, &u.origin[a], sizeof bits);
        putRaw64(out, bits);
    }
    for (std::uint64_t v : {u.groundPoints, u.obstaclePoints, u.rays, u.pointsSkipped}) putVarint(out, v);
    for (const auto* list : {&u.free, &u.groundHits, &u.obstacleHits}) {
        putVarint(out, list->size());
        std::uint64_t prev = 0;
        for (std::uint64_t c : *list) putVarint(out, c - prev), prev = c;
    }
    return out;
}

ScanUpdate deserializeScanUpdate(const std::string& bytes) {
    if (bytes.compare(0, 4, kMagic) != 0) throw std::runtime_error("scan update: not a gseg scan update (bad magic)");
    ScanUpdate u;
    Reader in(bytes, 4);
    for (int a = 0; a < 3; ++a) {
        const std::uint64_t bits = in.raw64();
        std::memcpy(&u.origin[a], &bits, sizeof bits);
    }
    u.groundPoints = in.varint(), u.obstaclePoints = in.varint(), u.rays = in.varint(), u.pointsSkipped = in.varint();
    u.free = in.codes();
    u.groundHits = in.codes();
    u.obstacleHits = in.codes();
    if (!in.atEnd()) throw std::runtime_error("scan update: trailing bytes");
    return u;
}

}  // namespace gseg::map
