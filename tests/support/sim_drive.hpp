#pragma once
// A simulated drive as a rawlog (MRPT tests only: header-only, so that the support library stays
// free of MRPT): a road with a box and a wall, the sensor mounted 1.8 m above the vehicle origin,
// a CObservationRobotPose before each scan (as kitti2rawlog writes), and optionally each scan's
// LIDAR_ground / LIDAR_obstacles pair split by the simulator's exact truth.
#include <support/lidar_sim.hpp>

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRobotPose.h>
#include <mrpt/serialization/CArchive.h>

#include <Eigen/Core>

#include <string>

namespace gseg::test {

inline constexpr double kRoadZ = 0.1;                                        ///< [m] the road in the world
inline const ::mrpt::poses::CPose3D kMount(0.5, 0.0, 1.8, 0, 0, 0);            ///< sensor 1.8 m above the vehicle origin

/// Vehicle at x = 3k on the road (z = kRoadZ), plus `offset` (e.g. UTM).
inline ::mrpt::poses::CPose3D vehiclePose(int k, const Eigen::Vector3d& offset = Eigen::Vector3d::Zero()) {
    return ::mrpt::poses::CPose3D(3.0 * k + offset.x(), offset.y(), kRoadZ + offset.z(), 0, 0, 0);
}

/// How writeDrive() lays the scans out.
struct Drive {
    bool poses = true;                  ///< a CObservationRobotPose before each scan
    enum Layout { Raw, Pair, RawAndPair } layout = Raw;  ///< Pair: as rawlog-gseg --replace writes; RawAndPair: without
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();    ///< added to every pose
    int emptyScan = -1;                 ///< this scan has no points
    int tinyScan = -1;                  ///< this scan sees only a floor disc within 1.2 m (no height estimate)
    int scans = 8;
    double azimuthStepDeg = 0.5;        ///< of the 32-beam sensor
};

/// Writes the drive (gzip rawlog) to `path`.
inline void writeDrive(const std::string& path, const Drive& d = {}) {
    ::mrpt::io::CFileGZOutputStream f(path);
    auto out = ::mrpt::serialization::archiveFrom(f);
    Lidar lidar;
    lidar.beams = 32, lidar.minElevationDeg = -25, lidar.maxElevationDeg = 5, lidar.azimuthStepDeg = d.azimuthStepDeg, lidar.maxRange = 40;
    for (int k = 0; k < d.scans; ++k) {
        const auto sensor = vehiclePose(k) + kMount;
        Scene s;
        s.addFlatGround(sensor.z() - kRoadZ);
        auto box = [&](double x0, double y0, double z0, double x1, double y1, double z1) {
            s.addBox(x0 - sensor.x(), y0 - sensor.y(), z0 - sensor.z(), x1 - sensor.x(), y1 - sensor.y(), z1 - sensor.z());
        };
        box(10, -4, kRoadZ, 11, -3, kRoadZ + 1.5);
        box(0, -8.2, kRoadZ, 40, -8, kRoadZ + 3);
        const auto scan = simulate(s, lidar);
        const auto t = ::mrpt::Clock::fromDouble(100.0 + 0.1 * k);
        if (d.poses) {
            ::mrpt::obs::CObservationRobotPose p;
            p.pose.mean = vehiclePose(k, d.offset);
            p.timestamp = t;
            out << p;
        }
        auto write = [&](const std::string& label, int want) {  // want: -1 all, 1 ground, 0 obstacles
            auto pc = ::mrpt::maps::CSimplePointsMap::Create();
            for (std::size_t i = 0; i < scan.size() && k != d.emptyScan; ++i) {
                const float x = scan.xyz[3 * i], y = scan.xyz[3 * i + 1], z = scan.xyz[3 * i + 2];
                if (k == d.tinyScan && x * x + y * y > 1.2f * 1.2f) continue;
                if (want < 0 || (scan.truth[i] == Truth::Ground) == (want == 1)) pc->insertPoint(x, y, z);
            }
            if (k == d.tinyScan && want != 0)  // a floor disc under the sensor
                for (int i = -4; i <= 4; ++i)
                    for (int j = -4; j <= 4; ++j) pc->insertPoint(0.12f * i, 0.12f * j, float(kRoadZ - sensor.z()));
            ::mrpt::obs::CObservationPointCloud obs;
            obs.pointcloud = pc;
            obs.sensorPose = kMount;
            obs.sensorLabel = label;
            obs.timestamp = t;
            out << obs;
        };
        if (d.layout != Drive::Pair) write("LIDAR", -1);
        if (d.layout != Drive::Raw) write("LIDAR_ground", 1), write("LIDAR_obstacles", 0);
    }
}

}  // namespace gseg::test
