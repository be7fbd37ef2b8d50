#include <support/scenes.hpp>

#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <random>
#include <stdexcept>

namespace gseg::test {
namespace {

constexpr double kH = 1.73;  // KITTI-like mounting height

Scene flat(double h = kH) {
    Scene s;
    s.addFlatGround(h);
    return s;
}

// Rolling terrain: sum of two sines, amplitude `a` metres, wavelengths 40 and 55 m (slopes up to
// about atan(2 pi a / 40)). The sensor stands on it at z = -h (the terrain is shifted so).
Scene hills(double a, double h = kH) {
    Scene s;
    Terrain t;
    const auto f = [a](double x, double y) { return a * std::sin(2 * M_PI * x / 40.0) + 0.6 * a * std::sin(2 * M_PI * y / 55.0 + 1.0); };
    const double z0 = f(0, 0);
    t.height = [f, z0, h](double x, double y) { return -h + f(x, y) - z0; };
    s.terrains.push_back(t);
    return s;
}

// Roughness: value noise on a square lattice of `spacing` metres whose node heights are uniform
// with standard deviation `sigma` metres, bilinearly interpolated (deterministic in x, y and seed).
double roughness(double x, double y, double sigma, double spacing, std::uint32_t seed) {
    const auto node = [&](std::int64_t i, std::int64_t j) {
        std::uint64_t h = std::uint64_t(i) * 0x9E3779B97F4A7C15ull ^ (std::uint64_t(j) + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
        h ^= std::uint64_t(seed) * 0x165667B19E3779F9ull;
        h ^= h >> 29, h *= 0xBF58476D1CE4E5B9ull, h ^= h >> 32;
        return (double(h >> 11) / double(1ull << 53) - 0.5) * std::sqrt(12.0) * sigma;  // uniform, std sigma
    };
    const double u = x / spacing, v = y / spacing;
    const double fu = std::floor(u), fv = std::floor(v);
    const auto i = std::int64_t(fu), j = std::int64_t(fv);
    const double a = u - fu, b = v - fv;
    return (1 - a) * (1 - b) * node(i, j) + a * (1 - b) * node(i + 1, j) + (1 - a) * b * node(i, j + 1) +
           a * b * node(i + 1, j + 1);
}

// A straight road along x (|y| < halfWidth, flat at z = -h) between verges that lie `left` and
// `right` metres above it, rough (4 cm, the grass of issue #20), and that slope up at `leftDeg`
// degrees beyond `leftFoot` metres on the left (an embankment; 0: flat).
Scene roadBetweenVerges(double h, double halfWidth, double left, double right, double leftDeg = 0,
                        double leftFoot = 1e9) {
    Scene s;
    Terrain t;
    const double tanLeft = std::tan(leftDeg * M_PI / 180.0);
    t.height = [=](double x, double y) {
        if (std::abs(y) < halfWidth) return -h;
        const double r = roughness(x, y, 0.04, 0.3, 5);
        if (y < 0) return -h + right + r;
        return -h + left + r + (y > leftFoot ? (y - leftFoot) * tanLeft : 0.0);
    };
    s.terrains.push_back(t);
    return s;
}

using Builder = std::function<NamedScan()>;

NamedScan make(const std::string& name, const Scene& s, double h = kH, const Lidar& l = Lidar::hdl64(),
               double radius = 5.0) {
    return {name, simulate(s, l), h, radius};
}

const std::map<std::string, Builder>& builders() {
    static const std::map<std::string, Builder> b = {
        {"flat", [] { return make("flat", flat()); }},
        {"ramp_up_10", [] { Scene s; s.addRamp(kH, 6, 10, Truth::Ground); return make("ramp_up_10", s); }},
        {"ramp_up_20", [] { Scene s; s.addRamp(kH, 6, 20, Truth::Ground); return make("ramp_up_20", s); }},
        {"ramp_down_10", [] { Scene s; s.addRamp(kH, 6, -10, Truth::Ground); return make("ramp_down_10", s); }},
        {"ramp_up_45", [] { Scene s; s.addRamp(kH, 6, 45, Truth::NonGround); return make("ramp_up_45", s); }},
        {"hills_gentle", [] { return make("hills_gentle", hills(1.0)); }},
        {"hills_steep", [] { return make("hills_steep", hills(2.5)); }},
        {"car_beside",
         [] {
             // A car parked 1.6 m to the right of the sensor, another 2.2 m to the left, slightly ahead.
             Scene s = flat();
             s.addCar(-2.0, -3.4, -kH);
             s.addCar(0.5, 2.2, -kH);
             return make("car_beside", s);
         }},
        {"traffic_jam",
         [] {
             // Cars bumper to bumper in three lanes all around the sensor, 3 to 8 m away: the road
             // shows only in the gaps.
             Scene s = flat();
             for (double x = -22; x <= 22; x += 5.4) {
                 if (std::abs(x) > 3) s.addCar(x - 2.2, -0.9, -kH);  // own lane, ahead and behind
                 s.addCar(x - 1.0, 2.6, -kH);                        // left lane
                 s.addCar(x + 1.3, -4.4, -kH);                       // right lane
             }
             return make("traffic_jam", s);
         }},
        {"flatbed_truck",
         [] {
             // A flat-bed truck beside the sensor: bed 1.2 m up, 2.5 m wide, 7 m long; cab 3 m tall.
             Scene s = flat();
             s.addBox(-3, 2.0, -kH + 0.5, 4, 4.5, -kH + 1.2);
             s.addBox(4, 2.0, -kH + 0.5, 6, 4.5, -kH + 3.0);
             for (double x : {-2.5, 2.5, 4.5})
                 for (double y : {2.0, 4.1}) s.addBox(x, y, -kH, x + 1.0, y + 0.4, -kH + 0.5);
             return make("flatbed_truck", s);
         }},
        {"wall_ledge",
         [] {
             // A wall 4 m to the left with a 0.6 m deep ledge 1 m up, then the wall goes on to 3 m.
             Scene s = flat();
             s.addBox(-15, 4.0, -kH, 15, 4.6, -kH + 1.0);
             s.addBox(-15, 4.6, -kH, 15, 5.5, -kH + 3.0);
             return make("wall_ledge", s);
         }},
        {"hedge",
         [] {
             // A 1.4 m hedge 3.5 m to the right along the road, and a bush ahead-left.
             Scene s = flat();
             Box hedge;
             hedge.lo[0] = -20, hedge.lo[1] = -5.0, hedge.lo[2] = -kH;
             hedge.hi[0] = 20, hedge.hi[1] = -3.5, hedge.hi[2] = -kH + 1.4;
             hedge.scatter = 0.4;
             s.boxes.push_back(hedge);
             Box bush = hedge;
             bush.lo[0] = 8, bush.lo[1] = 3, bush.hi[0] = 10, bush.hi[1] = 5, bush.hi[2] = -kH + 1.0;
             s.boxes.push_back(bush);
             return make("hedge", s);
         }},
        {"curb_near",
         [] {
             // A 0.15 m curb 2.5 m to the left of the sensor, sidewalk beyond; the curb face is don't-care.
             Scene s;
             Plane road, walk, face;
             road.offset = -kH, road.hi[1] = 2.5;
             walk.offset = -kH + 0.15, walk.lo[1] = 2.5;
             face.n[0] = 0, face.n[1] = 1, face.n[2] = 0, face.offset = 2.5;
             face.lo[2] = -kH, face.hi[2] = -kH + 0.15, face.truth = Truth::DontCare;
             s.planes = {road, walk, face};
             return make("curb_near", s);
         }},
        {"vlp16_low",
         [] {
             // A VLP-16 0.5 m above flat ground with a box ahead: rings far apart, big search radius.
             Scene s = flat(0.5);
             s.addBox(5, -1, -0.5, 6, 1, 0.5);
             return make("vlp16_low", s, 0.5, Lidar::vlp16(), 10.0);
         }},
        {"tilted_5deg",
         [] {
             // An HDL-64 pitched 5 deg forward and rolled 2 deg, over flat ground with a car ahead.
             Scene s = flat();
             s.addCar(7, -1, -kH);
             Lidar l = Lidar::hdl64();
             l.pitchDeg = 5, l.rollDeg = 2;
             return make("tilted_5deg", s, kH, l);
         }},
        {"hdl32_street",
         [] {
             // A 32-beam sensor 1.84 m up in a street: parked cars on both sides, a hedge, a wall.
             Scene s = flat(1.84);
             for (double x = -18; x <= 18; x += 6) s.addCar(x, 3.0, -1.84), s.addCar(x + 2, -4.8, -1.84);
             Box hedge;
             hedge.lo[0] = -25, hedge.lo[1] = 6.0, hedge.lo[2] = -1.84, hedge.hi[0] = 25, hedge.hi[1] = 7.0;
             hedge.hi[2] = -0.6, hedge.scatter = 0.4;
             s.boxes.push_back(hedge);
             s.addBox(-25, -9, -1.84, 25, -8.5, 2.0);
             return make("hdl32_street", s, 1.84, Lidar::hdl32(), 5.0);
         }},
        {"solid_state_hills",
         [] {
             // A forward-looking solid-state sensor 1 m up on rolling vegetated ground: bushes ahead.
             Scene s = hills(0.8, 1.0);
             for (int i = 0; i < 8; ++i) {
                 const double x = 6 + 3.5 * i, y = ((i * 37) % 11) - 5.0;
                 const double z = s.terrains[0].height(x + 0.5, y + 0.5);
                 Box bush;
                 bush.lo[0] = x, bush.lo[1] = y, bush.lo[2] = z - 0.1, bush.hi[0] = x + 1.2, bush.hi[1] = y + 1.2;
                 bush.hi[2] = z + 0.9, bush.scatter = 0.5;
                 s.boxes.push_back(bush);
             }
             return make("solid_state_hills", s, 1.0, Lidar::solidState(), 5.0);
         }},
        // --- issue #20: the ground beside the road, rough terrain, sparse sensors ---
        {"grass_verge_5cm",
         [] {
             // An 8 m road between grass verges 5 cm above it (4 cm roughness); a parked car on the
             // road, a 1.4 m hedge along the left verge 9 m out.
             Scene s = roadBetweenVerges(kH, 4.0, 0.05, 0.05);
             s.addCar(6, -3.5, -kH);
             Box hedge;
             hedge.lo[0] = -25, hedge.lo[1] = 9.0, hedge.lo[2] = -kH, hedge.hi[0] = 25, hedge.hi[1] = 10.5;
             hedge.hi[2] = -kH + 1.4, hedge.scatter = 0.4;
             s.boxes.push_back(hedge);
             return make("grass_verge_5cm", s);
         }},
        {"grass_verge_15cm",
         [] {
             // The same with verges 15 cm above the road (a curb-high grass shoulder).
             Scene s = roadBetweenVerges(kH, 4.0, 0.15, 0.15);
             s.addCar(6, -3.5, -kH);
             Box hedge;
             hedge.lo[0] = -25, hedge.lo[1] = 9.0, hedge.lo[2] = -kH, hedge.hi[0] = 25, hedge.hi[1] = 10.5;
             hedge.hi[2] = -kH + 1.4, hedge.scatter = 0.4;
             s.boxes.push_back(hedge);
             return make("grass_verge_15cm", s);
         }},
        {"embankment_12",
         [] {
             // A flat road; on the left a 5 cm verge that rises at 12 deg from 6 m out (an
             // embankment, 4 cm roughness); on the right a flat verge and a wall 12 m out.
             Scene s = roadBetweenVerges(kH, 4.0, 0.05, 0.05, 12.0, 6.0);
             s.addBox(-25, -12.5, -kH, 25, -12.0, -kH + 2.5);
             return make("embankment_12", s);
         }},
        {"gravel_road",
         [] {
             // Gravel everywhere: 3 cm roughness on a 10 cm lattice plus 2 cm on a 0.5 m one; two cars.
             Scene s;
             Terrain t;
             t.height = [](double x, double y) { return -kH + roughness(x, y, 0.03, 0.1, 9) + roughness(x, y, 0.02, 0.5, 10); };
             s.terrains.push_back(t);
             s.addCar(5, 2.0, -kH);
             s.addCar(-12, -3.5, -kH);
             return make("gravel_road", s);
         }},
        {"hdl32_road_terrain",
         [] {
             // An HDL-32E 1.84 m up over an 8 m road; terrain on both sides 8 cm above it, rolling by
             // 0.3 m over 25 m with 4 cm roughness, out to the end of the range; cars on the road.
             Scene s;
             Terrain t;
             t.height = [](double x, double y) {
                 if (std::abs(y) < 4.0) return -1.84;
                 const double dy = std::abs(y) - 4.0;
                 return -1.84 + 0.08 + 0.3 * std::sin(2 * M_PI * x / 25.0) * std::min(1.0, dy / 6.0) +
                        roughness(x, y, 0.04, 0.3, 13);
             };
             s.terrains.push_back(t);
             s.addCar(8, -3.2, -1.84);
             s.addCar(-15, 1.4, -1.84);
             return make("hdl32_road_terrain", s, 1.84, Lidar::hdl32(), 5.0);
         }},
        {"vlp16_rolling_grass",
         [] {
             // A VLP-16 1.2 m up on rolling grass (the hills of hills_gentle at 0.5 m, 3 cm roughness)
             // with two bushes.
             Scene s = hills(0.5, 1.2);
             const auto base = s.terrains[0].height;
             s.terrains[0].height = [base](double x, double y) { return base(x, y) + roughness(x, y, 0.03, 0.3, 17); };
             for (const double x : {7.0, -9.0}) {
                 const double z = base(x + 0.6, 3.6);
                 Box bush;
                 bush.lo[0] = x, bush.lo[1] = 3.0, bush.lo[2] = z - 0.1, bush.hi[0] = x + 1.2, bush.hi[1] = 4.2;
                 bush.hi[2] = z + 0.9, bush.scatter = 0.5;
                 s.boxes.push_back(bush);
             }
             return make("vlp16_rolling_grass", s, 1.2, Lidar::vlp16(), 10.0);
         }},
        {"reflections",
         [] {
             NamedScan n = make("reflections", flat());
             addReflections(n.scan, kH, 2000, 1.0, 3.0, 30.0, 11);
             return n;
         }},
    };
    return b;
}

}  // namespace

void addReflections(SimScan& scan, double height, std::size_t count, double minDepth, double maxDepth,
                    double range, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (std::size_t i = 0; i < count; ++i) {
        const double r = 3.0 + (range - 3.0) * u(rng), a = 2 * M_PI * u(rng);
        const double z = -height - (minDepth + (maxDepth - minDepth) * u(rng));
        scan.xyz.insert(scan.xyz.end(), {float(r * std::cos(a)), float(r * std::sin(a)), float(z)});
        scan.truth.push_back(Truth::NonGround);
    }
}

std::vector<NamedScan> allScenes() {
    std::vector<NamedScan> out;
    for (const auto& [name, build] : builders()) out.push_back(build());
    return out;
}

NamedScan scene(const std::string& name) {
    const auto it = builders().find(name);
    if (it == builders().end()) throw std::invalid_argument("no scene named " + name);
    return it->second();
}

}  // namespace gseg::test
