#include <support/lidar_sim.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace gseg::test {
namespace {
constexpr double kDeg = M_PI / 180.0;
bool inside(const double* p, const double* lo, const double* hi, double eps = 1e-9) {
    for (int a = 0; a < 3; ++a)
        if (p[a] < lo[a] - eps || p[a] > hi[a] + eps) return false;
    return true;
}
}  // namespace

void Scene::addFlatGround(double height) {
    Plane p;
    p.offset = -height;
    planes.push_back(p);
}

void Scene::addRamp(double height, double x0, double degrees, Truth slopeTruth) {
    Plane flat;
    flat.offset = -height;
    flat.hi[0] = x0;
    planes.push_back(flat);
    // z = -height + tan(a) (x - x0)  <=>  -sin(a) x + cos(a) z = cos(a) (-height) - sin(a) x0
    const double a = degrees * kDeg;
    Plane ramp;
    ramp.n[0] = -std::sin(a), ramp.n[1] = 0, ramp.n[2] = std::cos(a);
    ramp.offset = -height * std::cos(a) - std::sin(a) * x0;
    ramp.lo[0] = x0;
    ramp.truth = slopeTruth;
    planes.push_back(ramp);
}

void Scene::addCar(double x0, double y0, double ground) {
    addBox(x0, y0, ground + 0.3, x0 + 4.4, y0 + 1.8, ground + 1.0);
    addBox(x0 + 1.0, y0 + 0.1, ground + 1.0, x0 + 3.4, y0 + 1.7, ground + 1.5);
    for (double x : {x0 + 0.5, x0 + 3.3})
        for (double y : {y0 + 0.05, y0 + 1.5}) addBox(x, y, ground, x + 0.6, y + 0.25, ground + 0.3);
}

void Scene::addBox(double x0, double y0, double z0, double x1, double y1, double z1, Truth t) {
    Box b;
    b.lo[0] = x0, b.lo[1] = y0, b.lo[2] = z0, b.hi[0] = x1, b.hi[1] = y1, b.hi[2] = z1;
    b.truth = t;
    boxes.push_back(b);
}

namespace {

// First crossing of a height field along the beam d within (0.1, best): marches with a step that
// grows with range, then bisects.
bool hitTerrain(const Terrain& t, const double* d, double best, double& at) {
    auto above = [&](double r) { return r * d[2] > t.height(r * d[0], r * d[1]); };
    double r0 = 0.1;
    if (!above(r0)) return false;
    while (r0 < best) {
        const double r1 = std::min(best, r0 + std::max(0.05, 0.01 * r0));
        if (!above(r1)) {
            double a = r0, b = r1;
            for (int i = 0; i < 30; ++i) {
                const double m = 0.5 * (a + b);
                (above(m) ? a : b) = m;
            }
            at = 0.5 * (a + b);
            return true;
        }
        r0 = r1;
    }
    return false;
}

/// The boxes a beam can hit, by the beam's azimuth: seen from the sensor (the origin) a box's
/// footprint spans an azimuth interval under half a turn, unless the origin is in or at the
/// footprint (then every bin holds it). Each box is listed in the bins its interval overlaps and
/// one more each side, so rounding never leaves out a box a beam hits, and in scene order: a beam
/// meets the same boxes in the same order as when it is tested against every box (the same hits,
/// the same draws of the scatter's random numbers), in a fraction of the time for scenes of
/// thousands of boxes (a hedge of leaf clusters).
class BoxBins {
public:
    explicit BoxBins(const std::vector<Box>& boxes) : bins_(kBins) {
        for (std::size_t i = 0; i < boxes.size(); ++i) {
            all_.push_back(i);
            const Box& b = boxes[i];
            constexpr double eps = 1e-6;
            if (b.lo[0] - eps <= 0 && 0 <= b.hi[0] + eps && b.lo[1] - eps <= 0 && 0 <= b.hi[1] + eps) {
                for (auto& bin : bins_) bin.push_back(i);
                continue;
            }
            const double corners[4][2] = {{b.lo[0], b.lo[1]}, {b.hi[0], b.lo[1]}, {b.lo[0], b.hi[1]}, {b.hi[0], b.hi[1]}};
            const double a0 = std::atan2(corners[0][1], corners[0][0]);
            double lo = a0, hi = a0;
            for (const auto& c : corners) {
                const double a = a0 + std::remainder(std::atan2(c[1], c[0]) - a0, 2 * M_PI);
                lo = std::min(lo, a), hi = std::max(hi, a);
            }
            const long first = long(std::floor(lo / kWidth)) - 1, last = long(std::floor(hi / kWidth)) + 1;
            for (long k = first; k <= std::min(last, first + kBins - 1); ++k) bins_[binOf(k)].push_back(i);
        }
    }
    /// The boxes, ascending, that the beam of direction `d` may hit.
    const std::vector<std::size_t>& of(const double* d) const {
        if (std::abs(d[0]) < 1e-9 && std::abs(d[1]) < 1e-9) return all_;  // straight up or down
        return bins_[binOf(long(std::floor(std::atan2(d[1], d[0]) / kWidth)))];
    }

private:
    static constexpr long kBins = 720;
    static constexpr double kWidth = 2 * M_PI / kBins;
    static std::size_t binOf(long k) { return std::size_t(((k % kBins) + kBins) % kBins); }
    std::vector<std::vector<std::size_t>> bins_;
    std::vector<std::size_t> all_;
};

}  // namespace

SimScan simulate(const Scene& scene, const Lidar& lidar) {
    SimScan out;
    std::mt19937 rng(lidar.seed);
    std::normal_distribution<double> noise(0.0, lidar.noiseSigma);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    // Sensor-to-world rotation of the mounting tilt: roll about x, then pitch about y.
    const double cr = std::cos(lidar.rollDeg * kDeg), sr = std::sin(lidar.rollDeg * kDeg);
    const double cp = std::cos(lidar.pitchDeg * kDeg), sp = std::sin(lidar.pitchDeg * kDeg);
    const double R[3][3] = {{cp, sp * sr, sp * cr}, {0, cr, -sr}, {-sp, cp * sr, cp * cr}};
    const int steps = int(std::lround(360.0 / lidar.azimuthStepDeg));
    const BoxBins boxBins(scene.boxes);
    for (int b = 0; b < lidar.beams; ++b) {
        const double el = (lidar.minElevationDeg +
                           (lidar.beams > 1 ? b * (lidar.maxElevationDeg - lidar.minElevationDeg) / (lidar.beams - 1) : 0)) *
                          kDeg;
        for (int s = 0; s < steps; ++s) {
            const double az = s * lidar.azimuthStepDeg * kDeg;
            const double fromForward = std::remainder(az, 2 * M_PI);
            if (std::abs(fromForward) > 0.5 * lidar.fieldOfViewDeg * kDeg + 1e-9) continue;
            const double ds[3] = {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
            double d[3];
            for (int a = 0; a < 3; ++a) d[a] = R[a][0] * ds[0] + R[a][1] * ds[1] + R[a][2] * ds[2];
            double best = lidar.maxRange;
            Truth truth = Truth::DontCare;
            bool hit = false;
            for (const Plane& p : scene.planes) {
                const double denom = p.n[0] * d[0] + p.n[1] * d[1] + p.n[2] * d[2];
                if (std::abs(denom) < 1e-12) continue;
                const double t = p.offset / denom;
                const double q[3] = {t * d[0], t * d[1], t * d[2]};
                if (t > 0.1 && t < best && inside(q, p.lo, p.hi)) best = t, truth = p.truth, hit = true;
            }
            for (const Terrain& tr : scene.terrains) {
                double t = 0;
                if (hitTerrain(tr, d, best, t)) best = t, truth = tr.truth, hit = true;
            }
            for (std::size_t i : boxBins.of(d)) {
                const Box& bx = scene.boxes[i];
                double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
                for (int a = 0; a < 3 && t0 <= t1; ++a) {
                    if (std::abs(d[a]) < 1e-12) {
                        if (0.0 < bx.lo[a] || 0.0 > bx.hi[a]) t0 = 1, t1 = 0;
                        continue;
                    }
                    double ta = bx.lo[a] / d[a], tb = bx.hi[a] / d[a];
                    if (ta > tb) std::swap(ta, tb);
                    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
                }
                if (t0 <= t1 && t0 > 0.1 && t0 < best) {
                    const double behind = bx.scatter > 0 ? std::min({t1, best, t0 + bx.scatter * uniform(rng)}) : t0;
                    best = behind, truth = bx.truth, hit = true;
                }
            }
            if (!hit) continue;
            const double r = best + noise(rng);
            // Back into the sensor frame (transpose of R).
            const double w[3] = {r * d[0], r * d[1], r * d[2]};
            out.xyz.insert(out.xyz.end(), {float(R[0][0] * w[0] + R[1][0] * w[1] + R[2][0] * w[2]),
                                           float(R[0][1] * w[0] + R[1][1] * w[1] + R[2][1] * w[2]),
                                           float(R[0][2] * w[0] + R[1][2] * w[1] + R[2][2] * w[2])});
            out.truth.push_back(truth);
        }
    }
    return out;
}

PR groundPR(const SimScan& scan, const std::vector<std::uint8_t>& labels) {
    PR pr;
    std::size_t tp = 0;
    for (std::size_t i = 0; i < scan.size(); ++i) {
        if (scan.truth[i] == Truth::DontCare) continue;
        const bool g = scan.truth[i] == Truth::Ground;
        pr.truthGround += g;
        pr.predictedGround += labels[i];
        tp += g && labels[i];
    }
    pr.precision = pr.predictedGround ? double(tp) / double(pr.predictedGround) : 1.0;
    pr.recall = pr.truthGround ? double(tp) / double(pr.truthGround) : 1.0;
    return pr;
}

SimScan simulateInWorld(const World& world, int scan, double x, double y, double z, const Lidar& lidar) {
    Scene scene;
    scene.terrains.push_back({[g = world.ground, x, y, z](double px, double py) { return g(px + x, py + y) - z; }, Truth::Ground});
    std::vector<Box> boxes = world.boxes;
    if (world.boxesOfScan)
        for (const Box& b : world.boxesOfScan(scan)) boxes.push_back(b);
    const double at[3] = {x, y, z};
    for (Box b : boxes) {
        for (int a = 0; a < 3; ++a) b.lo[a] -= at[a], b.hi[a] -= at[a];
        scene.boxes.push_back(b);
    }
    SimScan out = simulate(scene, lidar);
    for (std::size_t i = 0; i < out.size(); ++i)
        for (int a = 0; a < 3; ++a) out.xyz[3 * i + std::size_t(a)] += float(at[a]);
    return out;
}

}  // namespace gseg::test
