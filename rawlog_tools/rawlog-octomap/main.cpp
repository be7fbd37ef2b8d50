// rawlog-octomap: traversability OctoMaps (ground / obstacles) from a rawlog of 3D LiDAR scans.
//
// Two passes over the rawlog: the first lists the scans with their time stamps and the poses the
// rawlog holds, so every pose problem is reported before any work; the second segments each scan
// (or takes the `_ground` / `_obstacles` observations written by rawlog-gseg as they are), puts
// the points into the world frame and ray-casts them into the maps.
//
// Poses, in this order of preference:
//   --poses TUM file (`t x y z qx qy qz qw`): the vehicle pose, matched to scans by time stamp;
//   --poses KITTI file (3x4 per scan, camera-0) + calib.txt: the velodyne pose of scan k
//     (Tr^-1 * P_k * Tr), scans taken in order;
//   the rawlog's own: CObservationRobotPose (absolute, as kitti2rawlog writes), CObservationOdometry
//     (absolute 2D odometry), CActionRobotMovement2D/3D (increments, integrated from the origin).

#include <gseg/map/poses.hpp>
#include <gseg/map/progress.hpp>
#include <gseg/map/traversability_map.hpp>
#include <gseg/map/world_scan.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/observation_points.hpp>
#include <gseg/mrpt/rawlog_io.hpp>
#include <gseg/sensor_height.hpp>

#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CActionRobotMovement3D.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationRobotPose.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3D.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <filesystem>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using mrpt::poses::CPose3D;

namespace {

const char* kUsage =
    "usage: rawlog-octomap -i IN.rawlog -o PREFIX [--poses FILE] [--calib FILE] [--pose-tolerance 0.02]\n"
    "                      [--resolution 0.2] [--max-range 50] [--clearance 2] [-c FILE.yaml]\n"
    "  writes PREFIX_ground.bt, PREFIX_obstacles.bt, PREFIX_traversability.ot, PREFIX_traversability.png\n"
    "  --poses FILE    TUM trajectory (t x y z qx qy qz qw, vehicle pose, matched by time stamp) or KITTI\n"
    "                  poses (3x4 per scan, with calib.txt beside it or --calib); default: poses in the rawlog\n"
    "  --pose-tolerance S  [s] largest time difference between a scan and its TUM pose\n"
    "  --resolution M  [m] voxel edge      --max-range M  [m] ray length limit\n"
    "  --clearance M   [m] obstacles higher than this above the ground do not block a cell\n"
    "  -c FILE         gseg parameters (YAML or INI, see config/)\n";

struct Cli {
    std::string input, prefix, poses, calib, config;
    double poseTolerance = 0.02;
    gseg::map::TraversabilityOptions options;
};

double parseNumber(const std::string& flag, const std::string& v) {
    std::size_t used = 0;
    double d = 0;
    try {
        d = std::stod(v, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used != v.size() || !(d > 0)) throw std::invalid_argument(flag + " needs a number > 0, got '" + v + "'");
    return d;
}

Cli parseCli(int argc, char** argv) {
    Cli c;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
            return argv[++i];
        };
        if (a == "-i" || a == "--input") c.input = value();
        else if (a == "-o" || a == "--output") c.prefix = value();
        else if (a == "--poses") c.poses = value();
        else if (a == "--calib") c.calib = value();
        else if (a == "-c" || a == "--config") c.config = value();
        else if (a == "--pose-tolerance") c.poseTolerance = parseNumber(a, value());
        else if (a == "--resolution") c.options.resolution = parseNumber(a, value());
        else if (a == "--max-range") c.options.maxRange = parseNumber(a, value());
        else if (a == "--clearance") c.options.clearance = parseNumber(a, value());
        else if (a == "-h" || a == "--help") {
            std::cout << kUsage;
            std::exit(0);
        } else throw std::invalid_argument("unexpected argument '" + a + "'");
    }
    if (c.input.empty() || c.prefix.empty()) throw std::invalid_argument("needs -i IN.rawlog and -o PREFIX");
    c.options.validate();
    return c;
}

using gseg::map::ScanPart;

/// One observation of a scan: top-level entry, index inside a CSensoryFrame (0 otherwise), part.
struct Member {
    std::size_t entry = 0, sub = 0;
    ScanPart part = ScanPart::Raw;
};

/// A scan: one raw LiDAR observation, or the `_ground` + `_obstacles` pair rawlog-gseg wrote.
struct PlannedScan {
    std::vector<Member> members;
    double t = 0;           ///< [s] time stamp (MRPT clock as seconds)
    std::string label;      ///< sensor label (without the part suffix)
    CPose3D sensorPose;     ///< mounting on the vehicle
    std::optional<CPose3D> rawlogPose;  ///< vehicle pose from the rawlog at this scan
    CPose3D robotPose;      ///< the pose used
};

struct Plan {
    std::vector<PlannedScan> scans;
    bool rawlogHasPoses = false;
};

std::string baseLabel(const std::string& label, ScanPart part) {
    const std::size_t cut = part == ScanPart::Ground ? 7 : part == ScanPart::Obstacles ? 10 : 0;
    return label.substr(0, label.size() - cut);
}

/// Calls f(sub, observation) for each observation of a top-level object; integrates actions.
class PlanBuilder {
public:
    Plan plan;

    void visit(std::size_t entry, const mrpt::serialization::CSerializable::Ptr& obj) {
        if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(obj)) {
            if (!pose_) pose_ = CPose3D();  // sensory-frame layout: odometry starts at the origin
            for (std::size_t i = 0; i < sf->size(); ++i) observation(entry, i, *sf->getObservationByIndex(i));
        } else if (auto acts = std::dynamic_pointer_cast<mrpt::obs::CActionCollection>(obj)) {
            if (!pose_) pose_ = CPose3D();
            actions(*acts);
        } else if (auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj)) {
            observation(entry, 0, *obs);
        }
    }

private:
    std::optional<CPose3D> pose_;

    void actions(const mrpt::obs::CActionCollection& acts) {
        for (std::size_t i = 0; i < acts.size(); ++i) {
            const mrpt::obs::CAction* a = &acts.get(i);
            if (auto m3 = dynamic_cast<const mrpt::obs::CActionRobotMovement3D*>(a)) {
                pose_ = *pose_ + m3->poseChange.mean;
                plan.rawlogHasPoses = true;
            } else if (auto m2 = dynamic_cast<const mrpt::obs::CActionRobotMovement2D*>(a)) {
                pose_ = *pose_ + CPose3D(m2->poseChange->getMeanVal());
                plan.rawlogHasPoses = true;
            }
        }
    }

    void observation(std::size_t entry, std::size_t sub, const mrpt::obs::CObservation& obs) {
        if (auto rp = dynamic_cast<const mrpt::obs::CObservationRobotPose*>(&obs)) {
            pose_ = rp->pose.mean;
            plan.rawlogHasPoses = true;
            return;
        }
        if (auto odo = dynamic_cast<const mrpt::obs::CObservationOdometry*>(&obs)) {
            pose_ = CPose3D(odo->odometry);
            plan.rawlogHasPoses = true;
            return;
        }
        const ScanPart part = gseg::map::scanPartOf(obs);
        if (part == ScanPart::Raw && !gseg::mrpt::isLidarObservation(obs)) return;
        const double t = mrpt::Clock::toDouble(obs.timestamp);
        const std::string label = baseLabel(obs.sensorLabel, part);
        if (part != ScanPart::Raw && !plan.scans.empty()) {
            PlannedScan& last = plan.scans.back();
            const bool samePair = last.members.size() == 1 && last.members[0].part != ScanPart::Raw &&
                                  last.members[0].part != part && last.label == label && last.t == t;
            if (samePair) {
                last.members.push_back({entry, sub, part});
                return;
            }
        }
        PlannedScan s;
        s.members.push_back({entry, sub, part});
        s.t = t;
        s.label = label;
        obs.getSensorPose(s.sensorPose);
        s.rawlogPose = pose_;
        plan.scans.push_back(s);
    }
};

Plan planScans(const std::string& path) {
    if (!std::ifstream(path)) throw std::runtime_error(path + ": cannot open the rawlog (" + std::strerror(errno) + ")");
    PlanBuilder b;
    gseg::mrpt::forEachRawlogEntry(path, [&](std::size_t entry, const auto& obj) {
        b.visit(entry, obj);
        return true;
    });
    if (b.plan.scans.empty())
        throw std::runtime_error(path + ": no 3D LiDAR scan in the rawlog (CObservationPointCloud, "
                                        "CObservationVelodyneScan, CObservation3DRangeScan)");
    return b.plan;
}

CPose3D toPose(const Eigen::Isometry3d& p) {
    mrpt::math::CMatrixDouble44 m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = p.matrix()(r, c);
    return CPose3D(m);
}

std::string describe(const PlannedScan& s, std::size_t k) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "scan %zu ('%s' at rawlog entry %zu, t = %.6f s)", k, s.label.c_str(),
                  s.members[0].entry, s.t);
    return buf;
}

void assignPoses(const Cli& c, Plan& plan) {
    if (c.poses.empty()) {
        if (!plan.rawlogHasPoses)
            throw std::runtime_error(c.input + ": no poses (no CObservationRobotPose, CObservationOdometry or "
                                               "odometry action in the rawlog): give --poses with a TUM or KITTI file");
        for (std::size_t k = 0; k < plan.scans.size(); ++k) {
            auto& s = plan.scans[k];
            if (!s.rawlogPose) throw std::runtime_error(c.input + ": " + describe(s, k) + " comes before the first pose in the rawlog");
            s.robotPose = *s.rawlogPose;
        }
        return;
    }
    if (gseg::map::detectPoseFileFormat(c.poses) == gseg::map::PoseFileFormat::Tum) {
        const auto traj = gseg::map::readTumTrajectory(c.poses);
        for (std::size_t k = 0; k < plan.scans.size(); ++k) {
            auto& s = plan.scans[k];
            const auto i = gseg::map::nearestPose(traj, s.t, c.poseTolerance);
            if (!i)
                throw std::runtime_error(c.poses + ": no pose within " + std::to_string(c.poseTolerance) + " s of " +
                                         describe(s, k));
            s.robotPose = toPose(traj[*i].pose);
        }
        return;
    }
    const std::string calib = c.calib.empty() ? (fs::path(c.poses).parent_path() / "calib.txt").string() : c.calib;
    const auto velodyne = gseg::map::kittiToVelodyneFrame(gseg::map::readKittiPoses(c.poses), gseg::map::readKittiCalibTr(calib));
    if (velodyne.size() < plan.scans.size())
        throw std::runtime_error(c.poses + ": " + std::to_string(velodyne.size()) + " poses for " +
                                 std::to_string(plan.scans.size()) + " scans (one KITTI pose per scan, in order)");
    for (std::size_t k = 0; k < plan.scans.size(); ++k) {  // KITTI poses are the velodyne's: remove the mounting
        CPose3D mountingInv = plan.scans[k].sensorPose;
        mountingInv.inverse();
        plan.scans[k].robotPose = toPose(velodyne[k]) + mountingInv;
    }
}

/// Second pass: segment / collect each scan and insert it.
void buildMap(const Cli& c, const Plan& plan, gseg::map::TraversabilityMap& map, const gseg::Params& params,
              bool autoHeight) {
    gseg::GroundSegmenter segmenter(params);
    // distToGround: auto: the sensor height is estimated from each scan before it is segmented.
    auto adaptHeight = [&](const mrpt::obs::CObservation& obs) {
        const std::vector<float> pts = gseg::mrpt::levelledPoints(obs);
        const auto h = gseg::estimateSensorHeight(gseg::PointCloudView(pts.data(), pts.size() / 4, 16));
        if (!h.valid) throw std::invalid_argument("'" + obs.sensorLabel + "': distToGround: auto found no ground level");
        gseg::Params p = params;
        p.distToGround = h.height;
        segmenter = gseg::GroundSegmenter(p);
    };
    gseg::map::Progress progress(stderr, "rawlog-octomap", plan.scans.size());
    std::size_t k = 0, m = 0;
    gseg::map::WorldScan pending;
    auto take = [&](std::size_t entry, std::size_t sub, const mrpt::obs::CObservation& obs) {
        if (k >= plan.scans.size()) return;
        const PlannedScan& s = plan.scans[k];
        const Member& want = s.members[m];
        if (want.entry != entry || want.sub != sub) return;
        if (want.part == ScanPart::Raw && autoHeight) adaptHeight(obs);
        if (want.part == ScanPart::Raw) pending = gseg::map::segmentToWorld(obs, s.robotPose, segmenter);
        else pending.sensorOrigin = gseg::map::appendWorldPoints(obs, s.robotPose,
                                                                 want.part == ScanPart::Ground ? pending.ground : pending.obstacles);
        if (++m < s.members.size()) return;
        map.insertScan(pending.groundView(), pending.obstaclesView(), pending.sensorOrigin);
        progress.update(k + 1, std::to_string(pending.ground.size() / 3) + " ground, " +
                                   std::to_string(pending.obstacles.size() / 3) + " obstacle points");
        pending = gseg::map::WorldScan();
        ++k, m = 0;
    };
    gseg::mrpt::forEachRawlogEntry(c.input, [&](std::size_t entry, const auto& obj) {
        if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(obj)) {
            for (std::size_t i = 0; i < sf->size(); ++i) take(entry, i, *sf->getObservationByIndex(i));
        } else if (auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj)) {
            take(entry, 0, *obs);
        }
        return k < plan.scans.size();
    });
    if (k < plan.scans.size()) throw std::runtime_error(c.input + ": the rawlog changed while it was read");
}

void printStats(const gseg::map::TraversabilityMap& map, const std::vector<std::string>& written) {
    const gseg::map::MapStats s = map.stats();
    const double res = map.options().resolution, cellArea = res * res;
    std::printf("rawlog-octomap: %zu scans, sensor path %.2f m; points: %zu ground, %zu obstacle; %zu rays\n", s.scans,
                s.pathLength, s.groundPoints, s.obstaclePoints, s.rays);
    std::printf("voxels (%.2f m): %zu ground, %zu obstacle, %zu free; %zu obstacle voxels cleared (seen through), "
                "%zu ground voxels under obstacles\n",
                res, s.groundVoxels, s.obstacleVoxels, s.freeVoxels, s.clearedObstacleVoxels, s.groundUnderObstacle);
    std::printf("top-down grid: %zu traversable (%.1f m^2), %zu obstacle (%.1f m^2), %zu unknown cells\n",
                s.cellsTraversable, double(s.cellsTraversable) * cellArea, s.cellsObstacle,
                double(s.cellsObstacle) * cellArea, s.cellsUnknown);
    for (const auto& p : written) std::printf("wrote %s\n", p.c_str());
}

void run(const Cli& c) {
    const gseg::mrpt::LoadedConfig cfg = c.config.empty() ? gseg::mrpt::LoadedConfig() : gseg::mrpt::loadConfig(c.config);
    Plan plan = planScans(c.input);
    assignPoses(c, plan);
    std::cerr << "rawlog-octomap: " << plan.scans.size() << " scans, poses from "
              << (c.poses.empty() ? "the rawlog" : c.poses) << "\n";
    gseg::map::TraversabilityMap map(c.options);
    buildMap(c, plan, map, cfg.params, cfg.distToGroundAuto);
    printStats(map, map.write(c.prefix));
}

}  // namespace

int main(int argc, char** argv) {
    try {
        run(parseCli(argc, argv));
        return 0;
    } catch (const std::invalid_argument& e) {
        std::cerr << "rawlog-octomap: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::string what = e.what();
        std::cerr << "rawlog-octomap: " << what.substr(0, what.find('\n')) << "\n";
        return 1;
    }
}
