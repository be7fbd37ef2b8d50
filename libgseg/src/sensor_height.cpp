#include <gseg/grid.hpp>
#include <gseg/option_table.hpp>
#include <gseg/plane_fit.hpp>
#include <gseg/sensor_height.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace gseg {
namespace {

struct Vote {
    Eigen::Vector3d p;  // column centre (x, y) and its floor (z)
    double weight;      // nearer columns weigh more
};

/// Per column, the lowest run of minColumnPoints points within floorThickness: the mean of those
/// points (their own x, y: on a tilted ground the column centre would not lie on the plane).
std::vector<Vote> columnFloors(const PointCloudView& cloud, const SensorHeightOptions& o) {
    struct Keyed {
        std::uint64_t key;
        float z, x, y;
        bool operator<(const Keyed& b) const { return key != b.key ? key < b.key : z < b.z; }
    };
    std::vector<Keyed> keyed;
    keyed.reserve(cloud.size() / 2);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const float x = cloud.x(i), y = cloud.y(i), z = cloud.z(i);
        if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) continue;
        const double r = std::hypot(double(x), double(y));
        if (r < o.minRange || r > o.maxRange) continue;
        const std::uint64_t key = (std::uint64_t(std::uint32_t(cellCoord(x, o.columnSize))) << 32) |
                                  std::uint32_t(cellCoord(y, o.columnSize));
        keyed.push_back({key, z, x, y});
    }
    std::sort(keyed.begin(), keyed.end());
    std::vector<Vote> votes;
    const std::size_t m = std::size_t(std::max(1, o.minColumnPoints));
    for (std::size_t s = 0; s < keyed.size();) {
        std::size_t e = s;
        while (e < keyed.size() && keyed[e].key == keyed[s].key) ++e;
        for (std::size_t k = s; k + m <= e; ++k)
            if (keyed[k + m - 1].z - keyed[k].z <= o.floorThickness) {
                Eigen::Vector3d mean = Eigen::Vector3d::Zero();
                for (std::size_t j = k; j < k + m; ++j) mean += Eigen::Vector3d(keyed[j].x, keyed[j].y, keyed[j].z);
                mean /= double(m);
                votes.push_back({mean, 1.0 / std::max(3.0, mean.head<2>().norm())});
                break;
            }
        s = e;
    }
    return votes;
}

/// Weighted least-squares plane through the votes flagged in `use`; false if degenerate.
bool fitVotes(const std::vector<Vote>& votes, const std::vector<std::uint8_t>& use, Eigen::Vector3d& n, double& d) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    double w = 0;
    for (std::size_t i = 0; i < votes.size(); ++i)
        if (use[i]) mean += votes[i].weight * votes[i].p, w += votes[i].weight;
    if (w <= 0) return false;
    mean /= w;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < votes.size(); ++i)
        if (use[i]) {
            const Eigen::Vector3d q = votes[i].p - mean;
            cov += votes[i].weight * q * q.transpose();
        }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    if (!(eig.eigenvalues()(1) > 1e-9)) return false;  // votes on one line: no plane
    n = eig.eigenvectors().col(0).normalized();
    if (n.z() < 0) n = -n;
    d = -n.dot(mean);
    return true;
}

}  // namespace

SensorHeightEstimate estimateSensorHeight(const PointCloudView& cloud, const SensorHeightOptions& o) {
    SensorHeightEstimate e;
    const std::vector<Vote> votes = columnFloors(cloud, o);
    e.columns = int(votes.size());
    if (e.columns < o.minColumns) {
        e.reason = "only " + std::to_string(e.columns) + " columns with a ground floor within " +
                   std::to_string(int(o.maxRange)) + " m (need " + std::to_string(o.minColumns) + ")";
        return e;
    }
    // RANSAC over the votes for the best-supported plane no steeper than maxTiltDegrees; nearer
    // votes weigh more. Deterministic: a fixed seed.
    const double minNz = std::cos(o.maxTiltDegrees * M_PI / 180.0);
    std::uint64_t state = 0x5eed;
    double bestScore = -1;
    Eigen::Vector3d bestN = Eigen::Vector3d::UnitZ();
    double bestD = 0;
    const std::size_t n = votes.size();
    for (int it = 0; it < 300; ++it) {
        const std::size_t a = splitmix64(state) % n, b = splitmix64(state) % n, c = splitmix64(state) % n;
        if (a == b || b == c || a == c) continue;
        Eigen::Vector3d nrm = (votes[b].p - votes[a].p).cross(votes[c].p - votes[a].p);
        if (nrm.norm() < 1e-6) continue;
        nrm.normalize();
        if (nrm.z() < 0) nrm = -nrm;
        if (nrm.z() < minNz) continue;
        const double d = -nrm.dot(votes[a].p);
        double score = 0;
        for (const Vote& v : votes)
            if (std::abs(nrm.dot(v.p) + d) <= o.planeTolerance) score += v.weight;
        if (score > bestScore) bestScore = score, bestN = nrm, bestD = d;
    }
    if (bestScore < 0) {
        e.reason = "no plane within " + std::to_string(int(o.maxTiltDegrees)) + " deg of level through the floors";
        return e;
    }
    std::vector<std::uint8_t> use(n);
    for (std::size_t i = 0; i < n; ++i) use[i] = std::abs(bestN.dot(votes[i].p) + bestD) <= o.planeTolerance;
    Eigen::Vector3d refN;
    double refD;
    if (fitVotes(votes, use, refN, refD) && refN.z() >= minNz) {
        bestN = refN, bestD = refD;
        for (std::size_t i = 0; i < n; ++i) use[i] = std::abs(bestN.dot(votes[i].p) + bestD) <= o.planeTolerance;
    }
    std::vector<double> residuals;
    for (std::size_t i = 0; i < n; ++i)
        if (use[i]) residuals.push_back(std::abs(bestN.dot(votes[i].p) + bestD));
    e.inliers = int(residuals.size());
    if (e.inliers < o.minColumns) {
        e.reason = "only " + std::to_string(e.inliers) + " column floors agree on one ground plane (need " +
                   std::to_string(o.minColumns) + ")";
        return e;
    }
    std::nth_element(residuals.begin(), residuals.begin() + long(residuals.size() / 2), residuals.end());
    e.spread = residuals[residuals.size() / 2];
    e.normal = bestN;
    e.height = bestD;  // n . 0 + d: the origin's signed distance above the plane
    e.tiltDegrees = std::acos(std::min(1.0, bestN.z())) * 180.0 / M_PI;
    e.valid = e.height > 0;
    if (!e.valid) e.reason = "the ground plane found lies above the sensor";
    return e;
}

std::string checkDistToGround(const PointCloudView& cloud, double distToGround, double tolerance,
                              const SensorHeightOptions& options) {
    const SensorHeightEstimate e = estimateSensorHeight(cloud, options);
    if (!e.valid) return "";
    const double under = e.heightUnderSensor();
    if (std::abs(under - distToGround) <= tolerance) return "";
    char line[320];
    std::snprintf(line, sizeof line,
                  "the ground lies %.2f m below the sensor in this scan (estimated from %d columns), but "
                  "distToGround is %.3f m, and a wrong height can cost most of the ground. Set "
                  "distToGround to the sensor's height, or to auto (config/auto_height.yaml)",
                  under, e.columns, distToGround);
    return line;
}

std::string HeightDecision::describe() const {
    char buf[160];
    const char* what = source == Source::Estimated ? "estimated" : source == Source::PreviousScan ? "previous scan's" : "fallback";
    std::snprintf(buf, sizeof buf, "%.2f m (%s%s", height, what, tiltDegrees > 0 ? ", levelled " : "");
    std::string s = buf;
    if (tiltDegrees > 0) {
        std::snprintf(buf, sizeof buf, "%.1f deg", tiltDegrees);
        s += buf;
    }
    if (source != Source::Estimated && !estimate.reason.empty()) s += "; no estimate: " + estimate.reason;
    return s + ")";
}

AutoHeightSegmenter::AutoHeightSegmenter(const Params& params, const SensorHeightOptions& options)
    : segmenter_(params), options_(options), fallback_(params.distToGround) {}

AutoHeightResult AutoHeightSegmenter::segment(const PointCloudView& cloud, bool keepCellDiagnostics,
                                              const SensorHeightEstimate* previous) {
    AutoHeightResult out;
    HeightDecision& d = out.decision;
    d.estimate = estimateSensorHeight(cloud, options_);
    if (d.estimate.valid) {
        d.source = HeightDecision::Source::Estimated;
        d.height = d.estimate.height;
        d.tiltDegrees = d.estimate.tiltDegrees;
    } else if (previous && previous->valid) {
        d.source = HeightDecision::Source::PreviousScan;
        d.height = previous->height, d.tiltDegrees = previous->tiltDegrees;
    } else {
        d.source = HeightDecision::Source::Fallback;
        d.height = fallback_;
    }
    // A tilt below a quarter of a degree is not worth a copy of the cloud.
    const Eigen::Vector3d normal = d.source == HeightDecision::Source::PreviousScan ? previous->normal : d.estimate.normal;
    if (d.tiltDegrees < options_.minLevelTiltDegrees || d.tiltDegrees > options_.maxLevelTiltDegrees) {
        // Level enough, or terrain rather than a mounting tilt: keep the frame and use the plane's
        // height straight under the sensor.
        d.height = d.height / std::max(0.1, normal.z());
        d.tiltDegrees = 0;
        out.result = segmenter_.segment(cloud, d.height, keepCellDiagnostics);
        return out;
    }
    const Eigen::Matrix3f R = Eigen::Quaterniond::FromTwoVectors(normal, Eigen::Vector3d::UnitZ()).toRotationMatrix().cast<float>();
    levelled_.resize(3 * cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const float* p = cloud.point(i);
        Eigen::Map<Eigen::Vector3f> out(&levelled_[3 * i]);
        out = R * Eigen::Vector3f(p[0], p[1], p[2]);
    }
    out.result = segmenter_.segment(PointCloudView(levelled_.data(), cloud.size()), d.height, keepCellDiagnostics);
    return out;
}

namespace {

const OptionTable<SensorHeightOptions>& heightTable() {
    using O = SensorHeightOptions;
    static const OptionTable<O> t(
        "sensorHeight option",
        {
            {"minRange", &O::minRange, "m", "ignore points closer than this horizontally (the vehicle itself)"},
            {"maxRange", &O::maxRange, "m", "and farther than this"},
            {"columnSize", &O::columnSize, "m", "side of the square columns that each vote for the ground level"},
            {"minColumnPoints", &O::minColumnPoints, "points",
             "a column's floor is the lowest run of this many points within floorThickness"},
            {"floorThickness", &O::floorThickness, "m", "thickness of that run (sparse points below it are skipped)"},
            {"minColumns", &O::minColumns, "columns", "fewer columns with a floor: no estimate"},
            {"maxTiltDegrees", &O::maxTiltDegrees, "deg", "steepest ground plane (sensor tilt plus slope) considered"},
            {"planeTolerance", &O::planeTolerance, "m", "a column floor within this of the plane supports it"},
            {"minLevelTiltDegrees", &O::minLevelTiltDegrees, "deg", "distToGround auto levels out tilts from this ..."},
            {"maxLevelTiltDegrees", &O::maxLevelTiltDegrees, "deg",
             "... up to this; beyond, it keeps the frame and uses the ground's height under the sensor"},
        });
    return t;
}

void requireHeightOption(bool ok, const char* key, double value, const char* what) {
    requireOption(ok, "sensorHeight option", key, value, what);
}

}  // namespace

void SensorHeightOptions::validate() const {
    const auto finite = [](double v) { return std::isfinite(v); };
    requireHeightOption(finite(minRange) && minRange >= 0 && minRange <= 1000, "minRange", minRange, "must be between 0 and 1000 m");
    requireHeightOption(finite(maxRange) && maxRange > minRange && maxRange <= 1000, "maxRange", maxRange,
                        "must be above minRange and at most 1000 m");
    requireHeightOption(finite(columnSize) && columnSize >= 0.05 && columnSize <= 100, "columnSize", columnSize,
                        "must be between 0.05 and 100 m");
    requireHeightOption(minColumnPoints >= 1 && minColumnPoints <= 1000000, "minColumnPoints", minColumnPoints,
                        "must be between 1 and 10^6 points");
    requireHeightOption(finite(floorThickness) && floorThickness > 0, "floorThickness", floorThickness, "must be > 0 m");
    requireHeightOption(minColumns >= 3 && minColumns <= 1000000, "minColumns", minColumns,
                        "must be between 3 (a plane) and 10^6 columns");
    requireHeightOption(finite(maxTiltDegrees) && maxTiltDegrees >= 0 && maxTiltDegrees < 90, "maxTiltDegrees",
                        maxTiltDegrees, "must be in [0, 90) degrees");
    requireHeightOption(finite(planeTolerance) && planeTolerance > 0, "planeTolerance", planeTolerance, "must be > 0 m");
    requireHeightOption(finite(minLevelTiltDegrees) && minLevelTiltDegrees >= 0 && minLevelTiltDegrees < 90,
                        "minLevelTiltDegrees", minLevelTiltDegrees, "must be in [0, 90) degrees");
    requireHeightOption(finite(maxLevelTiltDegrees) && maxLevelTiltDegrees >= minLevelTiltDegrees && maxLevelTiltDegrees < 90,
                        "maxLevelTiltDegrees", maxLevelTiltDegrees, "must be in [minLevelTiltDegrees, 90) degrees");
}

const std::vector<std::string>& SensorHeightOptions::keys() { return heightTable().names(); }

void SensorHeightOptions::set(const std::string& key, const std::string& value) { heightTable().set(*this, key, value); }

std::string SensorHeightOptions::get(const std::string& key) const { return heightTable().get(*this, key); }

std::pair<std::string, std::string> SensorHeightOptions::describe(const std::string& key) {
    return heightTable().describe(key);
}

}  // namespace gseg
