#pragma once
/// \file lidar_sim.hpp
/// A small deterministic LiDAR simulator for tests: rings of beams cast from a sensor onto a scene
/// of primitives, each with an exact ground truth.

#include <cstdint>
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

/// An axis-aligned box.
struct Box {
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    Truth truth = Truth::NonGround;
};

/// The scene: what the beams can hit.
struct Scene {
    std::vector<Plane> planes;
    std::vector<Box> boxes;

    /// Level ground at z = -height, everywhere.
    void addFlatGround(double height);
    /// Ground z = -height for x < x0, rising (or falling, negative angle) at `degrees` beyond x0.
    /// Truth of the sloped part: `slopeTruth`.
    void addRamp(double height, double x0, double degrees, Truth slopeTruth);
    void addBox(double x0, double y0, double z0, double x1, double y1, double z1, Truth t = Truth::NonGround);
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

    static Lidar hdl64() { return Lidar(); }
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

/// Ground precision and recall of `labels` (1 ground) against the truth; DontCare points ignored.
struct PR {
    double precision = 0, recall = 0;
    std::size_t truthGround = 0, predictedGround = 0;
};
PR groundPR(const SimScan& scan, const std::vector<std::uint8_t>& labels);

}  // namespace gseg::test
