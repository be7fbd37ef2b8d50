// kitti2rawlog: a KITTI odometry sequence (velodyne/*.bin, times.txt, poses.txt + calib.txt) as an
// MRPT rawlog (observation-only layout) that rawlog-octomap and RawLogViewer read.
//
// Per frame, in this order, both with the frame's time stamp:
//   1. CObservationRobotPose "KITTI_POSE" (only when poses are known): the velodyne pose in the
//      world frame = the velodyne frame of the first converted scan (z up, road near z = -1.73 m),
//      i.e. V_first^-1 * V_k with V_k = Tr^-1 * P_k * Tr.
//   2. CObservationPointCloud "VELODYNE": x, y, z, intensity (CPointsMapXYZI) in the velodyne frame;
//      sensorPose = identity (the velodyne is the vehicle frame here).
// Time stamps: times.txt (seconds since the drive started) taken as seconds since the UNIX epoch;
// without times.txt, frame k is at k * 0.1 s (KITTI's 10 Hz).
// --simplemap also writes the same scans with their poses as a CSimpleMap, the input of MRPT's
// observations2map (MRPT builds a simplemap in memory: not for long drives).
// --repeat N writes the frames N times along a continuing synthetic trajectory (each round starts
// where the previous one ended, one frame step later): a long drive for benchmarks, streamed.
// Every write and the close are checked; outputs appear complete or not at all, never over an input.

#include <gseg/io/kitti.hpp>
#include <gseg/map/gz_output.hpp>
#include <gseg/map/output_files.hpp>
#include <gseg/map/poses.hpp>
#include <gseg/map/progress.hpp>

#include <mrpt/maps/CPointsMapXYZI.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRobotPose.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

const char* kUsage =
    "usage: kitti2rawlog SEQUENCE_DIR -o OUT.rawlog [--poses FILE] [--calib FILE] [--no-poses]\n"
    "                    [--first N] [--last M] [--simplemap OUT.simplemap] [--repeat N]\n"
    "  SEQUENCE_DIR  a KITTI odometry sequence: velodyne/NNNNNN.bin, optional times.txt, poses.txt, calib.txt\n"
    "  --poses FILE  KITTI poses (3x4 per frame, camera-0); default SEQUENCE_DIR/poses.txt if present\n"
    "  --calib FILE  calib.txt with Tr (velodyne to camera-0); default SEQUENCE_DIR/calib.txt\n"
    "  --no-poses    write scans only, even if poses.txt is present\n"
    "  --first N, --last M  convert frames N..M (frame numbers, inclusive)\n"
    "  --simplemap F also write scans + poses as a CSimpleMap (input of observations2map; held in memory)\n"
    "  --repeat N    the frames N times along a continuing trajectory (a long drive for benchmarks; needs poses)\n";

struct Cli {
    std::string sequence, output, poses, calib, simplemap;
    bool noPoses = false;
    long first = 0, last = -1, repeat = 1;
};

long parseIndex(const std::string& flag, const std::string& v) {
    std::size_t used = 0;
    long n = -1;
    try {
        n = std::stol(v, &used);
    } catch (const std::exception&) {
    }
    if (used != v.size() || n < 0) throw std::invalid_argument(flag + " needs a frame number >= 0, got '" + v + "'");
    return n;
}

Cli parseCli(int argc, char** argv) {
    Cli c;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
            return argv[++i];
        };
        if (a == "-o" || a == "--output") c.output = value();
        else if (a == "--poses") c.poses = value();
        else if (a == "--calib") c.calib = value();
        else if (a == "--simplemap") c.simplemap = value();
        else if (a == "--no-poses") c.noPoses = true;
        else if (a == "--first") c.first = parseIndex(a, value());
        else if (a == "--last") c.last = parseIndex(a, value());
        else if (a == "--repeat") c.repeat = std::max(1L, parseIndex(a, value()));
        else if (a == "-h" || a == "--help") {
            std::cout << kUsage;
            std::exit(0);
        } else if (!a.empty() && a[0] == '-') throw std::invalid_argument("unknown option " + a);
        else if (c.sequence.empty()) c.sequence = a;
        else throw std::invalid_argument("unexpected argument '" + a + "'");
    }
    if (c.sequence.empty() || c.output.empty()) throw std::invalid_argument("needs SEQUENCE_DIR and -o OUT.rawlog");
    if (c.last >= 0 && c.last < c.first) throw std::invalid_argument("--last is before --first");
    return c;
}

/// Frame number and path of every velodyne/NNNNNN.bin in [first, last], sorted.
std::vector<std::pair<long, std::string>> listScans(const Cli& c) {
    const fs::path dir = fs::path(c.sequence) / "velodyne";
    if (!fs::is_directory(dir)) throw std::runtime_error(dir.string() + ": no such folder (a KITTI sequence has velodyne/*.bin)");
    std::vector<std::pair<long, std::string>> out;
    for (const auto& e : fs::directory_iterator(dir)) {
        if (e.path().extension() != ".bin") continue;
        const std::string stem = e.path().stem().string();
        if (stem.empty() || stem.find_first_not_of("0123456789") != std::string::npos) continue;
        const long k = std::stol(stem);
        if (k >= c.first && (c.last < 0 || k <= c.last)) out.emplace_back(k, e.path().string());
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
    auto pc = mrpt::maps::CPointsMapXYZI::Create();
    const std::size_t n = xyzi.size() / 4;
    pc->reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
        pc->insertPointFast(xyzi[4 * i], xyzi[4 * i + 1], xyzi[4 * i + 2]);
        pc->setPointIntensity(i, xyzi[4 * i + 3]);
    }
    auto obs = mrpt::obs::CObservationPointCloud::Create();
    obs->pointcloud = pc;
    obs->sensorLabel = "VELODYNE";
    obs->timestamp = t;
    obs->sensorPose = mrpt::poses::CPose3D();
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
    gseg::map::checkOutputs(outputs, inputsOf(c, scans));  // before anything is written
    std::cerr << "kitti2rawlog: " << scans.size() << " scans (frames " << scans.front().first << ".." << scans.back().first
              << "), " << (poses ? "with poses" : "no poses") << ", "
              << (times.empty() ? "no times.txt: 10 Hz time stamps" : "times from times.txt")
              << (c.repeat > 1 ? ", " + std::to_string(c.repeat) + " rounds" : std::string()) << "\n";

    std::vector<double> frameTimes;
    for (const auto& s : scans) frameTimes.push_back(times.empty() ? 0.1 * double(s.first) : times[std::size_t(s.first)]);
    const Repeater repeater(poses ? &*poses : nullptr, frameTimes);
    gseg::map::AtomicFiles files(outputs);
    mrpt::maps::CSimpleMap simplemap;
    gseg::map::CheckedGzOutput file(files.temporary(0), c.output);
    auto out = mrpt::serialization::archiveFrom(file);
    gseg::map::Progress progress(stderr, "kitti2rawlog", "scans");
    const std::size_t total = scans.size() * std::size_t(c.repeat);
    Eigen::Isometry3d roundStart = Eigen::Isometry3d::Identity();
    for (std::size_t n = 0; n < total; ++n) {
        const std::size_t i = n % scans.size(), r = n / scans.size();
        if (i == 0 && r > 0) roundStart = roundStart * repeater.round;
        const auto t = mrpt::Clock::fromDouble(frameTimes[i] + double(r) * repeater.period);
        const auto scan = makeScan(scans[i].second, t);
        if (poses) out << *makePose(roundStart * (*poses)[i], t);
        out << *scan;
        if (!c.simplemap.empty()) {
            auto sf = mrpt::obs::CSensoryFrame::Create();
            sf->insert(scan);
            simplemap.insert(mrpt::poses::CPose3DPDFGaussian::Create(toPose(roundStart * (*poses)[i])), sf);
        }
        progress.update(n + 1, double(n + 1) / double(total));
    }
    file.close();
    if (!c.simplemap.empty()) {
        gseg::map::CheckedGzOutput map(files.temporary(1), c.simplemap);
        mrpt::serialization::archiveFrom(map) << simplemap;
        map.close();
    }
    files.commit();
    progress.finish(total);
    std::cerr << "kitti2rawlog: wrote " << c.output << (c.simplemap.empty() ? "" : " and " + c.simplemap) << "\n";
}

}  // namespace

int main(int argc, char** argv) {
    try {
        run(parseCli(argc, argv));
        return 0;
    } catch (const std::invalid_argument& e) {
        std::cerr << "kitti2rawlog: " << e.what() << "\n" << kUsage;
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "kitti2rawlog: " << gseg::map::reasonOf(e) << "\n";
        return 1;
    }
}
