#pragma once
/// \file scenes.hpp
/// Simulated scenes with exact labels that stand for what real drives contain (slopes, hills,
/// traffic, raised surfaces, curbs, other sensors and mounts, reflections). Shared by the scene
/// tests and by tools that measure the segmenter on all of them.

#include <support/lidar_sim.hpp>

#include <string>
#include <vector>

namespace gseg::test {

/// One simulated scan and what the segmenter must be told about it.
struct NamedScan {
    std::string name;
    SimScan scan;
    double sensorHeight = 1.73;   ///< [m] true height of the sensor above the ground under it
    double searchRadius = 5.0;    ///< [m] centroidSearchRadius this sensor needs (sparse sensors: more)
};

/// Every scene, simulated (deterministic). Names are stable; see scenes.cpp for each layout.
std::vector<NamedScan> allScenes();

/// One scene by name (throws std::invalid_argument if unknown).
NamedScan scene(const std::string& name);

/// Appends `count` points between `minDepth` and `maxDepth` metres below flat ground at
/// z = -height, within `range` metres of the sensor (mirror reflections, multipath); truth NonGround.
void addReflections(SimScan& scan, double height, std::size_t count, double minDepth, double maxDepth,
                    double range, std::uint32_t seed);

}  // namespace gseg::test
