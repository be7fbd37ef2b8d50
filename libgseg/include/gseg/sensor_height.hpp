#pragma once
/// \file sensor_height.hpp
/// Estimation of the sensor's height above the ground from one scan (`distToGround: auto`).

#include <gseg/point_cloud.hpp>

namespace gseg {

/// Options of estimateSensorHeight().
struct SensorHeightOptions {
    double minRange = 2.0;     ///< [m] ignore points closer than this horizontally (the vehicle itself)
    double maxRange = 30.0;    ///< [m] and farther than this
    double columnSize = 2.0;   ///< [m] side of the square columns
    int minColumnPoints = 5;   ///< [points] columns with fewer points are ignored
    int minColumns = 8;        ///< [columns] fewer usable columns: no estimate
};

/// Result of estimateSensorHeight().
struct SensorHeightEstimate {
    bool valid = false;
    double height = 0;      ///< [m] estimated height of the sensor above the ground (> 0: ground below)
    int columns = 0;        ///< columns that voted
    double spread = 0;      ///< [m] median absolute deviation of the column votes (small: one clear ground level)
};

/// The lowest dense surface around the sensor: in each occupied column (levelled frame, sensor at
/// the origin) the lowest point is a vote for the ground level, and the median vote wins, so
/// columns holding only a wall or a car roof do not move it. The cloud must be levelled (z up).
SensorHeightEstimate estimateSensorHeight(const PointCloudView& cloud,
                                          const SensorHeightOptions& options = SensorHeightOptions());

}  // namespace gseg
