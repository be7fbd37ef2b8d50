// kitti2rawlog: a KITTI odometry sequence (velodyne/*.bin, times.txt, poses.txt + calib.txt) as an
// MRPT rawlog (observation-only layout) that rawlog-octomap and RawLogViewer read.
//
// Per frame, in this order, all with the frame's time stamp:
//   1. CObservationOdometry "KITTI_ODOMETRY" (only when poses are known): the same pose in 2D (x,
//      y, yaw), so that MRPT tools that follow odometry (RawLogViewer's travelled distance and
//      path) show the drive.
//   2. CObservationRobotPose "KITTI_POSE" (only when poses are known): the velodyne pose in the
//      world frame = the velodyne frame of the first converted scan (z up, road near z = -1.73 m),
//      i.e. V_first^-1 * V_k with V_k = Tr^-1 * P_k * Tr. It comes after the odometry, so that a
//      reader taking the last pose before a scan (rawlog-octomap) gets the full 3D pose.
//   3. CObservationPointCloud "VELODYNE": x, y, z, intensity (CPointsMapXYZI) in the velodyne frame;
//      sensorPose = identity (the velodyne is the vehicle frame here).
// Time stamps: a base date plus times.txt (seconds since the drive started); without times.txt,
// frame k is k * 0.1 s after the base (KITTI's 10 Hz). KITTI odometry does not say when each
// sequence was recorded (the raw recordings are from 2011-09-26 to 2011-10-03, matched to
// sequences only loosely), so the base is fixed and documented: 2011-09-26 00:00:00 UTC, the first
// recording day; --start-time sets another (time 0 is MRPT's "invalid time", shown as 1970).
// --simplemap also writes the same scans with their poses as a CSimpleMap, the input of MRPT's
// observations2map (MRPT builds a simplemap in memory: not for long drives).
// --repeat N writes the frames N times along a continuing synthetic trajectory (each round starts
// where the previous one ended, one frame step later): a long drive for benchmarks, streamed.
// Every write and the close are checked; outputs appear complete or not at all, never over an input.

#include "common/cli.hpp"

#include <gseg/eval/kitti_sequence.hpp>
#include <gseg/io/atomic_file.hpp>
#include <gseg/io/kitti.hpp>
#include <gseg/mrpt/gzip_stream.hpp>
#include <gseg/mrpt/observation_points.hpp>
#include <gseg/mrpt/rawlog_io.hpp>
#include <gseg/map/poses.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/progress.hpp>
#include <gseg/version.hpp>

#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRobotPose.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/datetime.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

/// The documented base of the time stamps: 2011-09-26 00:00:00 UTC (see the top of this file).
constexpr const char* kDefaultStart = "2011-09-26T00:00:00Z";

struct Cli {
    std::string sequence, output, poses, calib, simplemap;
    bool noPoses = false;
    bool overwrite = false;  ///< -w: replace outputs that exist
    long first = 0, last = -1, repeat = 1;
    double start = 0;  ///< [s since the UNIX epoch] time of the drive's t = 0
};

/// "YYYY-MM-DD", "YYYY-MM-DDTHH:MM:SS[.fff][Z]" or "YYYY-MM-DD HH:MM:SS[.fff]" (UTC) as seconds
/// since the UNIX epoch. Throws std::invalid_argument on anything else.
double parseStartTime(const std::string& text) {
    int y = 0, mo = 0, d = 0, h = 0, mi = 0, n = 0;
    double sec = 0;
    const char* s = text.c_str();
    bool ok = std::sscanf(s, "%4d-%2d-%2d%n", &y, &mo, &d, &n) == 3 && n == 10;
    if (ok && s[n] != '\0') {
        int m = 0;
        ok = (s[n] == 'T' || s[n] == ' ') && std::sscanf(s + n + 1, "%2d:%2d:%lf%n", &h, &mi, &sec, &m) == 3;
        const char* rest = s + n + 1 + m;
        ok = ok && (*rest == '\0' || (rest[0] == 'Z' && rest[1] == '\0'));
    }
    ok = ok && y >= 1971 && y <= 9999 && mo >= 1 && mo <= 12 && d >= 1 && d <= 31 && h >= 0 && h < 24 && mi >= 0 &&
         mi < 60 && sec >= 0 && sec < 61;
    if (!ok)
        throw std::invalid_argument("--start-time needs a UTC date YYYY-MM-DD or YYYY-MM-DDTHH:MM:SS (1971 to 9999), got '" +
                                    text + "'");
    std::tm tm{};
    tm.tm_year = y - 1900, tm.tm_mon = mo - 1, tm.tm_mday = d, tm.tm_hour = h, tm.tm_min = mi;
    return double(::timegm(&tm)) + sec;
}

/// Exit codes.
using gseg::tools::kBadInput;  // the exit codes of every tool (common/cli.hpp)
using gseg::tools::kBadUsage;
using gseg::tools::kDone;

/// Parses the command line into `c`; returns -1 to go on, or the exit code (0 after --help /
/// --version, 2 on bad usage, with the message printed).
int parseCli(int argc, char** argv, Cli& c) {
    gseg::tools::CommandLine line(
        "kitti2rawlog",
        "Convert a KITTI odometry sequence (velodyne/NNNNNN.bin, optional times.txt, poses.txt, calib.txt) into an "
        "MRPT rawlog: per frame a CObservationOdometry and a CObservationRobotPose (when poses are known) and the "
        "scan as a CObservationPointCloud (x, y, z, intensity). Time stamps: --start-time plus times.txt (10 Hz "
        "without it). The old form `kitti2rawlog SEQUENCE_DIR -o OUT` still works. An output that exists is refused "
        "unless -w. Exit code: 0 done, 1 bad input (nothing written), 2 bad usage.",
        true);
    TCLAP::CmdLine& cmd = line.cmd();
    try {
        TCLAP::ValueArg<std::string> input("i", "input", "the KITTI sequence folder (e.g. sequences/00)", false, "",
                                           "SEQUENCE_DIR", cmd);
        TCLAP::UnlabeledValueArg<std::string> positional("sequence", "the sequence folder, old form (same as -i)", false,
                                                         "", "SEQUENCE_DIR", cmd);
        TCLAP::ValueArg<std::string> output("o", "output", "output rawlog (gzip)", true, "", "OUT.rawlog", cmd);
        TCLAP::ValueArg<std::string> poses("", "poses", "KITTI poses (3x4 per frame, camera 0; default "
                                           "SEQUENCE_DIR/poses.txt if present)", false, "", "FILE", cmd);
        TCLAP::ValueArg<std::string> calib("", "calib", "calib.txt with Tr, velodyne to camera 0 (default "
                                           "SEQUENCE_DIR/calib.txt)", false, "", "FILE", cmd);
        TCLAP::SwitchArg noPoses("", "no-poses", "write the scans only, even if poses.txt is present", cmd);
        TCLAP::ValueArg<long> first("", "first", "first frame to convert (frame number, default 0)", false, 0, "N", cmd);
        TCLAP::ValueArg<long> last("", "last", "last frame to convert (inclusive; default the last one)", false, -1, "M", cmd);
        TCLAP::ValueArg<std::string> simplemap("", "simplemap", "also write scans + poses as a CSimpleMap (the input of "
                                               "MRPT's observations2map; held in memory: short drives only)", false, "",
                                               "OUT.simplemap", cmd);
        TCLAP::ValueArg<long> repeat("", "repeat", "the frames N times along a continuing trajectory (a long drive for "
                                     "benchmarks; needs poses)", false, 1, "N", cmd);
        TCLAP::ValueArg<std::string> start("", "start-time", std::string("UTC date and time of the drive's t = 0 of "
                                           "times.txt (default ") + kDefaultStart + ", the first KITTI recording day; "
                                           "KITTI odometry does not say when each sequence was recorded)",
                                           false, kDefaultStart, "YYYY-MM-DD[THH:MM:SS]", cmd);
        if (const int code = line.parse(argc, argv); code >= 0) return code;
        c.overwrite = line.overwrite();
        if (!input.getValue().empty() && !positional.getValue().empty())
            throw std::invalid_argument("give the sequence folder once: -i SEQUENCE_DIR (or the old positional form)");
        c.sequence = input.getValue().empty() ? positional.getValue() : input.getValue();
        if (c.sequence.empty()) throw std::invalid_argument("needs the sequence folder: -i SEQUENCE_DIR");
        c.output = output.getValue(), c.poses = poses.getValue(), c.calib = calib.getValue();
        c.simplemap = simplemap.getValue(), c.noPoses = noPoses.getValue();
        c.first = first.getValue(), c.last = last.getValue(), c.repeat = repeat.getValue();
        if (c.first < 0) throw std::invalid_argument("--first needs a frame number >= 0");
        if (c.last < -1) throw std::invalid_argument("--last needs a frame number >= 0");
        if (c.last >= 0 && c.last < c.first) throw std::invalid_argument("--last is before --first");
        if (c.repeat < 1) throw std::invalid_argument("--repeat needs a count >= 1");
        c.start = parseStartTime(start.getValue());
    } catch (const std::invalid_argument& e) {
        return line.usageError(e.what());
    }
    return -1;
}

/// Frame number and path of every velodyne/NNNNNN.bin in [first, last], sorted.
std::vector<std::pair<long, std::string>> listScans(const Cli& c) {
    const fs::path dir = fs::path(c.sequence) / "velodyne";
    if (!fs::is_directory(dir)) throw std::runtime_error(dir.string() + ": no such folder (a KITTI sequence has velodyne/*.bin)");
    std::vector<std::pair<long, std::string>> out;
    for (const gseg::eval::KittiScan& s : gseg::eval::listKittiScans(c.sequence)) {
        const std::optional<std::size_t> number = gseg::eval::kittiFrameNumber(s.name);  // other names: skipped
        if (!number) continue;
        const long k = long(*number);
        if (k >= c.first && (c.last < 0 || k <= c.last)) out.emplace_back(k, s.scan);
    }
    std::sort(out.begin(), out.end());
    if (out.empty()) throw std::runtime_error(dir.string() + ": no scan NNNNNN.bin in the requested frame range");
    return out;
}

/// times.txt as seconds, or empty if absent.
std::vector<double> readTimes(const std::string& sequence) {
    const fs::path p = fs::path(sequence) / "times.txt";
    return fs::exists(p) ? gseg::map::readKittiTimes(p.string()) : std::vector<double>();
}

/// Velodyne poses of the frames, world = first converted frame; nullopt without poses.
std::optional<std::vector<Eigen::Isometry3d>> framePoses(const Cli& c, const std::vector<std::pair<long, std::string>>& scans) {
    if (c.noPoses) return std::nullopt;
    std::string posesPath = c.poses;
    if (posesPath.empty()) {
        const fs::path p = fs::path(c.sequence) / "poses.txt";
        if (!fs::exists(p)) return std::nullopt;
        posesPath = p.string();
    }
    const std::string calibPath = c.calib.empty() ? (fs::path(c.sequence) / "calib.txt").string() : c.calib;
    const auto camera = gseg::map::readKittiPoses(posesPath);
    if (std::size_t(scans.back().first) >= camera.size())
        throw std::runtime_error(posesPath + ": " + std::to_string(camera.size()) + " poses, but frame " +
                                 std::to_string(scans.back().first) + " needs one (fewer poses than scans)");
    const auto velodyne = gseg::map::kittiToVelodyneFrame(camera, gseg::map::readKittiCalibTr(calibPath));
    const Eigen::Isometry3d firstInv = velodyne[std::size_t(scans.front().first)].inverse();
    std::vector<Eigen::Isometry3d> out;
    for (const auto& s : scans) out.push_back(firstInv * velodyne[std::size_t(s.first)]);
    return out;
}

mrpt::poses::CPose3D toPose(const Eigen::Isometry3d& p) {
    mrpt::math::CMatrixDouble44 m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = p.matrix()(r, c);
    return mrpt::poses::CPose3D(m);
}

mrpt::obs::CObservationPointCloud::Ptr makeScan(const std::string& binPath, mrpt::Clock::time_point t) {
    const std::vector<float> xyzi = gseg::io::readKittiBin(binPath);
    return gseg::mrpt::pointCloudObservation(xyzi.data(), xyzi.size() / 4, mrpt::poses::CPose3D(), "VELODYNE", t);
}

mrpt::obs::CObservationOdometry::Ptr makeOdometry(const Eigen::Isometry3d& p, mrpt::Clock::time_point t) {
    auto obs = mrpt::obs::CObservationOdometry::Create();
    const mrpt::poses::CPose3D pose = toPose(p);
    obs->odometry = mrpt::poses::CPose2D(pose.x(), pose.y(), pose.yaw());
    obs->sensorLabel = "KITTI_ODOMETRY";
    obs->timestamp = t;
    return obs;
}

mrpt::obs::CObservationRobotPose::Ptr makePose(const Eigen::Isometry3d& p, mrpt::Clock::time_point t) {
    auto obs = mrpt::obs::CObservationRobotPose::Create();
    obs->pose.mean = toPose(p);
    obs->sensorLabel = "KITTI_POSE";
    obs->timestamp = t;
    return obs;
}

/// Every file the conversion reads (an output must be none of them).
std::vector<std::string> inputsOf(const Cli& c, const std::vector<std::pair<long, std::string>>& scans) {
    std::vector<std::string> in = {c.poses, c.calib};
    for (const char* f : {"poses.txt", "calib.txt", "times.txt"}) in.push_back((fs::path(c.sequence) / f).string());
    for (const auto& s : scans) in.push_back(s.second);
    return in;
}

/// Frame i of round r of --repeat: the trajectory continues from the end of round r - 1.
struct Repeater {
    Eigen::Isometry3d round = Eigen::Isometry3d::Identity();  ///< first pose of the next round, relative to the first
    double period = 0;                                        ///< [s] time of one round

    Repeater(const std::vector<Eigen::Isometry3d>* poses, const std::vector<double>& t) {
        if (!poses || poses->empty()) return;
        const auto& p = *poses;
        const Eigen::Isometry3d step = p.size() > 1 ? p[0].inverse() * p[1] : Eigen::Isometry3d::Identity();
        round = p.back() * step * p[0].inverse();
        const double dt = t.size() > 1 ? t[1] - t[0] : 0.1;
        period = (t.empty() ? 0.1 * double(p.size() - 1) : t.back() - t.front()) + dt;
    }
};

/// The last frame's time stamp (--start-time plus `lastTime` seconds) must be a date MRPT's time
/// stamps hold and print (up to 9999-12-31): beyond, they wrap to 1970 without a word.
void checkLastTimeStamp(const Cli& c, double lastTime, bool fromTimesTxt) {
    constexpr double kLastSecond = 253402300799.0;  // 9999-12-31T23:59:59Z since the UNIX epoch
    if (c.start + lastTime <= kLastSecond) return;
    char buf[256];
    std::snprintf(buf, sizeof buf, "the last frame's time stamp (--start-time + %.17g s%s) is after 9999-12-31, the last date a time stamp holds",
                  lastTime, c.repeat > 1 ? ", with --repeat" : "");
    throw std::runtime_error((fromTimesTxt ? (fs::path(c.sequence) / "times.txt").string() + ": " : std::string()) + buf);
}

void run(const Cli& c) {
    const auto scans = listScans(c);
    const std::vector<double> times = readTimes(c.sequence);
    if (!times.empty() && std::size_t(scans.back().first) >= times.size())
        throw std::runtime_error((fs::path(c.sequence) / "times.txt").string() + ": " + std::to_string(times.size()) +
                                 " times, but frame " + std::to_string(scans.back().first) + " needs one");
    const auto poses = framePoses(c, scans);
    if (!c.simplemap.empty() && !poses)
        throw std::invalid_argument("--simplemap needs poses (poses.txt in the sequence or --poses)");
    if (c.repeat > 1 && !poses) throw std::invalid_argument("--repeat needs poses (poses.txt in the sequence or --poses)");
    std::vector<std::string> outputs = {c.output};
    if (!c.simplemap.empty()) outputs.push_back(c.simplemap);
    std::vector<gseg::io::NamedPath> ins;
    for (const std::string& in : inputsOf(c, scans)) ins.push_back({"input", in});
    gseg::io::checkOutputs(ins, {{"-o", c.output}, {"--simplemap", c.simplemap}}, {c.overwrite, false});  // before any work
    gseg::tools::note("kitti2rawlog: %zu scans (frames %ld..%ld), %s, %s after %s UTC%s\n", scans.size(), scans.front().first,
                      scans.back().first, poses ? "with poses" : "no poses",
                      times.empty() ? "no times.txt: 10 Hz time stamps" : "times from times.txt",
                      mrpt::system::dateTimeToString(mrpt::Clock::fromDouble(c.start)).c_str(),
                      c.repeat > 1 ? (", " + std::to_string(c.repeat) + " rounds").c_str() : "");

    std::vector<double> frameTimes;
    for (const auto& s : scans) frameTimes.push_back(times.empty() ? 0.1 * double(s.first) : times[std::size_t(s.first)]);
    const Repeater repeater(poses ? &*poses : nullptr, frameTimes);
    checkLastTimeStamp(c, frameTimes.back() + double(c.repeat - 1) * repeater.period, !times.empty());
    gseg::io::AtomicFileSet files(outputs);  // the rawlog and the simple map appear together or not at all
    mrpt::maps::CSimpleMap simplemap;
    gseg::mrpt::RawlogWriter out(files[0]);
    gseg::Progress progress(gseg::tools::progressOut(), "kitti2rawlog", "scans");
    const std::size_t total = scans.size() * std::size_t(c.repeat);
    Eigen::Isometry3d roundStart = Eigen::Isometry3d::Identity();
    for (std::size_t n = 0; n < total; ++n) {
        const std::size_t i = n % scans.size(), r = n / scans.size();
        if (i == 0 && r > 0) roundStart = roundStart * repeater.round;
        const auto t = mrpt::Clock::fromDouble(c.start + frameTimes[i] + double(r) * repeater.period);
        const auto scan = makeScan(scans[i].second, t);
        if (poses) {
            out.write(*makeOdometry(roundStart * (*poses)[i], t));
            out.write(*makePose(roundStart * (*poses)[i], t));
        }
        out.write(*scan);
        if (!c.simplemap.empty()) {
            auto sf = mrpt::obs::CSensoryFrame::Create();
            sf->insert(scan);
            simplemap.insert(mrpt::poses::CPose3DPDFGaussian::Create(toPose(roundStart * (*poses)[i])), sf);
        }
        progress.update(n + 1, double(n + 1) / double(total));
        gseg::tools::detail("kitti2rawlog: frame %ld (%s)%s\n", scans[i].first, scans[i].second.c_str(),
                            r > 0 ? (", round " + std::to_string(r + 1)).c_str() : "");
    }
    out.finish();
    if (!c.simplemap.empty()) gseg::mrpt::writeGzipObject(files[1], simplemap);
    files.commit();
    progress.finish(total);
    gseg::tools::note("kitti2rawlog: wrote %s%s\n", c.output.c_str(), c.simplemap.empty() ? "" : (" and " + c.simplemap).c_str());
}

}  // namespace

int main(int argc, char** argv) {
    Cli cli;
    if (const int code = parseCli(argc, argv, cli); code >= 0) return code;
    gseg::io::installTemporaryCleanup("kitti2rawlog");  // an interrupted run leaves no temporary
    try {
        run(cli);
        return kDone;
    } catch (...) {
        return gseg::tools::reportError("kitti2rawlog", gseg::tools::InvalidArgument::BadUsage);
    }
}
