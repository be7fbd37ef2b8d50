#pragma once
/// \file sim_observations.hpp
/// Simulated scans as MRPT observations, for the filter's and rawlog-gseg's tests. Header-only.

#include <support/lidar_sim.hpp>

#include <mrpt/maps/CPointsMapXYZI.h>
#include <mrpt/obs/CObservationPointCloud.h>

namespace gseg::test {

/// A simulated level scan as a CObservationPointCloud labelled "SIM".
inline ::mrpt::obs::CObservationPointCloud simulatedCloud(const SimScan& scan) {
    auto pc = ::mrpt::maps::CPointsMapXYZI::Create();
    for (std::size_t i = 0; i < scan.size(); ++i) pc->insertPoint(scan.xyz[3 * i], scan.xyz[3 * i + 1], scan.xyz[3 * i + 2]);
    ::mrpt::obs::CObservationPointCloud obs;
    obs.pointcloud = pc;
    obs.sensorLabel = "SIM";
    return obs;
}

/// An HDL-64 scan of flat ground 1.73 m below the sensor with a 2 x 2 m box 6-8 m ahead.
inline SimScan streetScan() {
    Scene s;
    s.addFlatGround(1.73);
    s.addBox(6, -1, -1.73, 8, 1, 0);
    return simulate(s, Lidar::hdl64());
}

}  // namespace gseg::test
