#include <support/lidar_sim.hpp>

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

void Scene::addBox(double x0, double y0, double z0, double x1, double y1, double z1, Truth t) {
    Box b;
    b.lo[0] = x0, b.lo[1] = y0, b.lo[2] = z0, b.hi[0] = x1, b.hi[1] = y1, b.hi[2] = z1;
    b.truth = t;
    boxes.push_back(b);
}

SimScan simulate(const Scene& scene, const Lidar& lidar) {
    SimScan out;
    std::mt19937 rng(lidar.seed);
    std::normal_distribution<double> noise(0.0, lidar.noiseSigma);
    const int steps = int(std::lround(360.0 / lidar.azimuthStepDeg));
    for (int b = 0; b < lidar.beams; ++b) {
        const double el = (lidar.minElevationDeg +
                           (lidar.beams > 1 ? b * (lidar.maxElevationDeg - lidar.minElevationDeg) / (lidar.beams - 1) : 0)) *
                          kDeg;
        for (int s = 0; s < steps; ++s) {
            const double az = s * lidar.azimuthStepDeg * kDeg;
            const double d[3] = {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
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
            for (const Box& bx : scene.boxes) {
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
                if (t0 <= t1 && t0 > 0.1 && t0 < best) best = t0, truth = bx.truth, hit = true;
            }
            if (!hit) continue;
            const double r = best + noise(rng);
            out.xyz.insert(out.xyz.end(), {float(r * d[0]), float(r * d[1]), float(r * d[2])});
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

}  // namespace gseg::test
