#pragma once
/// \file lidar_sim.hpp
/// A small deterministic LiDAR simulator for tests: rings of beams cast from a sensor onto a scene
/// of primitives, each with an exact ground truth.

#include <cstdint>
#include <functional>
#include <vector>

namespace gseg::test {

/// Truth of a primitive's points.
enum class Truth : std::uint8_t { NonGround = 0, Ground = 1, DontCare = 2 };

/// A bounded plane n . p = offset, kept where lo <= p <= hi (axis-aligned bounds).
struct Plane {
    double n[3] = {0, 0, 1};
    double offset = 0;
    double lo[3] = {-1e9, -1e9, -1e9}, hi[3] = {1e9, 1e9, 1e9};
    Truth truth = Truth::Ground;
};

/// An axis-aligned box. With `scatter` > 0 a hit lands up to that far behind the box's surface
/// along the beam (uniformly, inside the box): foliage, hedges, bushes.
struct Box {
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    Truth truth = Truth::NonGround;
    double scatter = 0;  ///< [m]
};

/// Ground given as a height field z = height(x, y), hit by marching along the beam.
struct Terrain {
    std::function<double(double, double)> height;
    Truth truth = Truth::Ground;
};

/// The scene: what the beams can hit.
struct Scene {
    std::vector<Plane> planes;
    std::vector<Box> boxes;
    std::vector<Terrain> terrains;

    /// Level ground at z = -height, everywhere.
    void addFlatGround(double height);
    /// Ground z = -height for x < x0, rising (or falling, negative angle) at `degrees` beyond x0.
    /// Truth of the sloped part: `slopeTruth`.
    void addRamp(double height, double x0, double degrees, Truth slopeTruth);
    void addBox(double x0, double y0, double z0, double x1, double y1, double z1, Truth t = Truth::NonGround);
    /// A car standing on the ground at z = ground: lower body from 0.3 to 1.0 m over [x0, x0 + 4.4] x
    /// [y0, y0 + 1.8], cabin from 1.0 to 1.5 m over the middle 2.4 m, four wheels under the body.
    void addCar(double x0, double y0, double ground);
};

/// The sensor: `beams` rings evenly spread over [minElevation, maxElevation] degrees, one shot
/// every `azimuthStep` degrees, at the origin (the scene is built around it), range noise sigma.
struct Lidar {
    int beams = 64;
    double minElevationDeg = -24.9, maxElevationDeg = 2.0;
    double azimuthStepDeg = 0.4;
    double maxRange = 80.0;
    double noiseSigma = 0.01;  ///< [m] Gaussian range noise
    std::uint32_t seed = 7;
    double rollDeg = 0, pitchDeg = 0;  ///< mounting tilt: rays and points are in the tilted sensor frame
    double fieldOfViewDeg = 360;       ///< horizontal field of view, centred on x (forward-looking sensors: less)

    static Lidar hdl64() { return Lidar(); }
    /// A 32-beam spinning sensor (-25..+15 deg).
    static Lidar hdl32() {
        Lidar l;
        l.beams = 32, l.minElevationDeg = -25, l.maxElevationDeg = 15, l.azimuthStepDeg = 0.2;
        return l;
    }
    /// A forward-looking solid-state sensor: 120 x 25 deg, 64 rows.
    static Lidar solidState() {
        Lidar l;
        l.beams = 64, l.minElevationDeg = -12.5, l.maxElevationDeg = 12.5, l.azimuthStepDeg = 0.2;
        l.fieldOfViewDeg = 120;
        return l;
    }
    static Lidar vlp16() {
        Lidar l;
        l.beams = 16, l.minElevationDeg = -15, l.maxElevationDeg = 15, l.azimuthStepDeg = 0.2;
        return l;
    }
};

/// One simulated scan: x, y, z per point (3 floats) and its truth.
struct SimScan {
    std::vector<float> xyz;
    std::vector<Truth> truth;
    std::size_t size() const { return truth.size(); }
};

/// Casts every beam; rays that hit nothing within maxRange give no point.
SimScan simulate(const Scene& scene, const Lidar& lidar);

/// A world in world coordinates (metres, z up): ground height z(x, y) and obstacle boxes, some of
/// them only in some scans (moving things). For simulated drives.
struct World {
    std::function<double(double, double)> ground = [](double, double) { return 0.0; };
    std::vector<Box> boxes;                                 ///< in every scan
    std::function<std::vector<Box>(int scan)> boxesOfScan;  ///< more boxes in scan k
};

/// Scan `scan` of a drive through `world` from the sensor at world position (x, y, z): the points
/// in the world frame (the sensor's axes are the world's), with their truth.
SimScan simulateInWorld(const World& world, int scan, double x, double y, double z, const Lidar& lidar);

/// Ground precision and recall of `labels` (1 ground) against the truth; DontCare points ignored.
struct PR {
    double precision = 0, recall = 0;
    std::size_t truthGround = 0, predictedGround = 0;
};
PR groundPR(const SimScan& scan, const std::vector<std::uint8_t>& labels);

}  // namespace gseg::test
