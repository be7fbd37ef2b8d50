#include <gseg/io/kitti.hpp>  // regularFileSize
#include <gseg/map/poses.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace gseg::map {
namespace {

/// The numbers of a line (whitespace or comma separated), or the first token that is not a finite
/// number.
struct LineNumbers {
    std::vector<double> values;
    std::string bad;  ///< the first token that is not a finite number ("" when every one is)
    /// "'x' is not a number" or "'nan' is not a finite number" for `bad`.
    std::string badReason() const;
};

std::string LineNumbers::badReason() const {
    char* end = nullptr;
    const double v = std::strtod(bad.c_str(), &end);
    const bool parsed = end == bad.c_str() + bad.size();
    return "'" + bad + "' is not a " + (parsed && !std::isfinite(v) ? "finite number" : "number");
}

LineNumbers parseNumbers(const std::string& line) {
    LineNumbers out;
    const char* p = line.c_str();
    while (true) {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == ',') ++p;
        if (*p == '\0') break;
        const char* tokenEnd = p;
        while (*tokenEnd && !std::strchr(" \t\r,", *tokenEnd)) ++tokenEnd;
        char* end = nullptr;
        const double v = std::strtod(p, &end);
        if (end != tokenEnd || !std::isfinite(v)) {
            out.bad.assign(p, tokenEnd);
            return out;
        }
        out.values.push_back(v);
        p = end;
    }
    return out;
}

bool isSkipped(const std::string& line) {
    const auto first = line.find_first_not_of(" \t\r");
    return first == std::string::npos || line[first] == '#';
}

std::ifstream openText(const std::string& path) {
    gseg::io::regularFileSize(path);  // stat before open: a FIFO is refused, not waited on
    std::ifstream in(path);
    if (!in) throw std::runtime_error(path + ": cannot open (" + std::strerror(errno) + ")");
    return in;
}

std::runtime_error lineError(const std::string& path, std::size_t lineNo, const std::string& what) {
    return std::runtime_error(path + ":" + std::to_string(lineNo) + ": " + what);
}

/// The numbers of line `lineNo` of `path`; throws naming the line and the token if one is not a
/// finite number.
std::vector<double> numbersOf(const std::string& line, const std::string& path, std::size_t lineNo) {
    LineNumbers n = parseNumbers(line);
    if (!n.bad.empty()) throw lineError(path, lineNo, n.badReason());
    return std::move(n.values);
}

/// Calls f(lineNo, numbers) for each line that is not blank or a comment; throws naming the line
/// where a token is not a finite number.
template <class F>
void forEachDataLine(const std::string& path, F&& f) {
    std::ifstream in = openText(path);
    std::string line;
    for (std::size_t lineNo = 1; std::getline(in, line); ++lineNo)
        if (!isSkipped(line)) f(lineNo, numbersOf(line, path, lineNo));
}

/// [R | t] from 12 row-major numbers; throws naming the line if R is not a rotation.
Eigen::Isometry3d fromRowMajor3x4(const std::vector<double>& v, const std::string& path, std::size_t lineNo) {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = v[std::size_t(4 * r + c)];
    const Eigen::Matrix3d R = m.topLeftCorner<3, 3>();
    const double offOrtho = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), det = R.determinant();
    if (!(offOrtho <= kRotationTolerance && std::abs(det - 1) <= kRotationTolerance)) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "the 3x3 part is not a rotation (|R^T R - I| up to %.3g, det R = %.6g)", offOrtho, det);
        throw lineError(path, lineNo, buf);
    }
    return Eigen::Isometry3d(m);
}

}  // namespace

std::vector<StampedPose> readTumTrajectory(const std::string& path) {
    std::vector<StampedPose> out;
    forEachDataLine(path, [&](std::size_t lineNo, const std::vector<double>& v) {
        if (v.size() != 8)
            throw lineError(path, lineNo, "expected 8 numbers `t x y z qx qy qz qw`, found " + std::to_string(v.size()));
        const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
        if (q.norm() < 1e-9) throw lineError(path, lineNo, "zero quaternion");
        StampedPose sp;
        sp.t = v[0];
        sp.pose.linear() = q.normalized().toRotationMatrix();
        sp.pose.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
        if (!out.empty() && sp.t <= out.back().t)
            throw lineError(path, lineNo, "time stamp " + std::to_string(sp.t) + " is not after the previous one");
        out.push_back(sp);
    });
    if (out.empty()) throw std::runtime_error(path + ": no poses in the file");
    return out;
}

std::vector<Eigen::Isometry3d> readKittiPoses(const std::string& path) {
    std::vector<Eigen::Isometry3d> out;
    forEachDataLine(path, [&](std::size_t lineNo, const std::vector<double>& v) {
        if (v.size() != 12)
            throw lineError(path, lineNo, "expected 12 numbers (row-major 3x4 KITTI pose), found " + std::to_string(v.size()));
        out.push_back(fromRowMajor3x4(v, path, lineNo));
    });
    if (out.empty()) throw std::runtime_error(path + ": no poses in the file");
    return out;
}

Eigen::Isometry3d readKittiCalibTr(const std::string& path) {
    std::ifstream in = openText(path);
    std::string line;
    for (std::size_t lineNo = 1; std::getline(in, line); ++lineNo) {
        if (line.rfind("Tr:", 0) != 0) continue;
        const std::vector<double> v = numbersOf(line.substr(3), path, lineNo);
        if (v.size() != 12) throw lineError(path, lineNo, "`Tr:` needs 12 numbers (velodyne to camera-0, 3x4)");
        return fromRowMajor3x4(v, path, lineNo);
    }
    throw std::runtime_error(path + ": no `Tr:` line (velodyne-to-camera calibration)");
}

std::vector<double> readKittiTimes(const std::string& path) {
    std::vector<double> out;
    forEachDataLine(path, [&](std::size_t lineNo, const std::vector<double>& v) {
        if (v.size() != 1) throw lineError(path, lineNo, "expected one time in seconds, found " + std::to_string(v.size()) + " numbers");
        const double t = v.front();
        if (!(t >= 0 && t <= kMaxKittiTime)) {
            char buf[160];
            std::snprintf(buf, sizeof buf, "time %.17g s is outside 0 to %.0f s (seconds since the drive started)", t,
                          kMaxKittiTime);
            throw lineError(path, lineNo, buf);
        }
        if (!out.empty() && t < out.back())
            throw lineError(path, lineNo, "time " + std::to_string(t) + " s is before the previous one");
        out.push_back(t);
    });
    return out;
}

std::vector<Eigen::Isometry3d> kittiToVelodyneFrame(const std::vector<Eigen::Isometry3d>& cameraPoses,
                                                    const Eigen::Isometry3d& tr) {
    const Eigen::Isometry3d trInv = tr.inverse();
    std::vector<Eigen::Isometry3d> out;
    out.reserve(cameraPoses.size());
    for (const auto& p : cameraPoses) out.push_back(trInv * p * tr);
    return out;
}

PoseFileFormat detectPoseFileFormat(const std::string& path) {
    std::ifstream in = openText(path);
    std::string line;
    for (std::size_t lineNo = 1; std::getline(in, line); ++lineNo) {
        if (isSkipped(line)) continue;
        const std::vector<double> v = numbersOf(line, path, lineNo);
        if (v.size() == 8) return PoseFileFormat::Tum;
        if (v.size() == 12) return PoseFileFormat::Kitti;
        throw lineError(path, lineNo,
                        "neither a TUM trajectory (8 numbers `t x y z qx qy qz qw`) nor KITTI poses (12 numbers)");
    }
    throw std::runtime_error(path + ": no poses in the file");
}

std::optional<std::size_t> nearestPose(const std::vector<StampedPose>& trajectory, double t, double tolerance) {
    const auto after = std::lower_bound(trajectory.begin(), trajectory.end(), t,
                                        [](const StampedPose& p, double v) { return p.t < v; });
    std::optional<std::size_t> best;
    double bestDt = tolerance;
    for (auto it : {after, after == trajectory.begin() ? trajectory.end() : after - 1}) {
        if (it == trajectory.end()) continue;
        const double dt = std::abs(it->t - t);
        if (dt <= bestDt) bestDt = dt, best = std::size_t(it - trajectory.begin());
    }
    return best;
}

}  // namespace gseg::map
