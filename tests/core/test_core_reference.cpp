// The core's search steps checked against brute force on seeded random inputs (#17 item 7): the
// region growing's KD-tree neighbour search and breadth-first expansion against an O(n^2) search,
// and the RANSAC plane fit against an exhaustive search over every triple of a small input.
#include <gseg/params.hpp>
#include <gseg/plane_fit.hpp>
#include <gseg/region_growing.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <random>
#include <set>
#include <tuple>
#include <vector>

namespace {

std::vector<Eigen::Vector3f> randomCentroids(std::mt19937& rng, std::size_t n) {
    std::uniform_real_distribution<float> xy(-20.f, 20.f), z(-1.95f, -1.5f);
    std::vector<Eigen::Vector3f> c(n);
    for (auto& p : c) p = {xy(rng), xy(rng), z(rng)};
    return c;
}

float distanceSq(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    const Eigen::Vector3f d = a - b;
    return d.x() * d.x() + d.y() * d.y() + d.z() * d.z();
}

// The rule under test, the same for both: accept two candidates in three (by index).
bool acceptRule(std::uint32_t c) { return c % 3 != 0; }

}  // namespace

// Three ways (#21): as it is; with a centroid absurdly far away (the sparse column search); with
// the neighbours of odd candidates searched only once they are accepted (needsNeighbours).
/// (mode, seed): mode 0 plain, 1 far centroid, 2 lazy.
class RegionGrowingReference : public ::testing::TestWithParam<std::tuple<int, std::uint32_t>> {};

TEST_P(RegionGrowingReference, NeighboursAndReachedCellsEqualAnExhaustiveSearch) {
    const int mode = std::get<0>(GetParam());
    const std::uint32_t seed = std::get<1>(GetParam());
    {
        std::mt19937 rng(seed);
        std::vector<Eigen::Vector3f> c = randomCentroids(rng, 300 + 20 * seed);
        if (mode == 1) c.emplace_back(1e7f, -1e7f, -1.73f);
        gseg::ExpansionSettings s;
        if (mode == 2) s.needsNeighbours = [](std::uint32_t i) { return i % 2 == 0; };
        s.seed = {0.f, 0.f, -1.73f};
        s.seedRadius = 7.7;
        s.radius = 4.0;
        s.heightGate = seed % 2 ? 0.3 : std::numeric_limits<double>::infinity();
        s.seedGate = 0.3;
        std::map<std::uint32_t, std::vector<std::uint32_t>> seen;  // what expandRegion passed to accept
        const auto state = gseg::expandRegion(c, s, [&](std::uint32_t i, const std::vector<std::uint32_t>& nb) {
            seen[i] = nb;
            return acceptRule(i);
        });
        // Brute force: every pair.
        auto neighbours = [&](std::uint32_t i) {
            std::vector<std::uint32_t> out;
            for (std::uint32_t j = 0; j < c.size(); ++j)
                if (j != i && distanceSq(c[i], c[j]) < float(s.radius * s.radius) && std::abs(c[j].z() - c[i].z()) <= s.heightGate)
                    out.push_back(j);
            return out;
        };
        std::vector<std::uint8_t> expected(c.size(), 0);
        std::deque<std::uint32_t> queue;
        for (std::uint32_t j = 0; j < c.size(); ++j)
            if (distanceSq(c[j], s.seed) < float(s.seedRadius * s.seedRadius) && std::abs(c[j].z() - s.seed.z()) <= s.seedGate)
                expected[j] = 1, queue.push_back(j);
        ASSERT_FALSE(queue.empty()) << "seed " << seed;
        while (!queue.empty()) {
            const std::uint32_t i = queue.front();
            queue.pop_front();
            if (!acceptRule(i)) continue;
            expected[i] = 2;
            for (std::uint32_t j : neighbours(i))
                if (expected[j] == 0) expected[j] = 1, queue.push_back(j);
        }
        EXPECT_EQ(state, expected) << "seed " << seed;
        std::size_t accepted = 0;
        for (const auto& [i, nb] : seen) {
            accepted += acceptRule(i);
            if (mode == 2 && i % 2) {
                EXPECT_TRUE(nb.empty()) << "a candidate that needs no neighbours got some";
                continue;
            }
            const std::set<std::uint32_t> got(nb.begin(), nb.end());
            const std::vector<std::uint32_t> ref = neighbours(i);
            EXPECT_EQ(got, std::set<std::uint32_t>(ref.begin(), ref.end())) << "seed " << seed << ", candidate " << i;
            EXPECT_EQ(got.size(), nb.size()) << "a neighbour listed twice";
        }
        EXPECT_EQ(seen.size(), std::size_t(std::count_if(expected.begin(), expected.end(), [](std::uint8_t v) { return v > 0; })))
            << "every reached candidate is decided exactly once";
        EXPECT_GT(accepted, 10u) << "seed " << seed << ": the expansion went nowhere (a vacuous test)";
    }
}

INSTANTIATE_TEST_SUITE_P(ModesAndSeeds, RegionGrowingReference,
                         ::testing::Combine(::testing::Values(0, 1, 2), ::testing::Range(std::uint32_t(1), std::uint32_t(21))));

class PlaneFitReference : public ::testing::TestWithParam<std::uint64_t> {};

TEST_P(PlaneFitReference, TheInliersAreThoseOfTheBestPlaneThroughAnyThreePoints) {
    gseg::Params params;
    params.ransacMaxIterations = 1000;
    const double threshold = params.groundInlierThreshold;
    const std::uint64_t seed = GetParam();
    {
        std::mt19937 rng{std::uint32_t(seed)};
        std::uniform_real_distribution<float> u(-1.f, 1.f), noise(-0.03f, 0.03f), tilt(-0.08f, 0.08f);
        const float a = tilt(rng), b = tilt(rng), c0 = -1.7f;  // z = a x + b y + c0 (up to 6.5 deg)
        std::vector<Eigen::Vector3f> pts;
        const int onPlane = 7 + int(seed % 5), off = 2 + int(seed % 4);
        for (int i = 0; i < onPlane; ++i) {
            const float x = 2 * u(rng), y = 2 * u(rng);
            pts.emplace_back(x, y, a * x + b * y + c0 + noise(rng));
        }
        for (int i = 0; i < off; ++i) {  // clutter 0.6 to 1.6 m above the plane
            const float x = 2 * u(rng), y = 2 * u(rng);
            pts.emplace_back(x, y, a * x + b * y + c0 + 0.6f + std::abs(u(rng)));
        }
        // Exhaustive: the plane through each triple, and its inliers; the largest set wins.
        std::size_t best = 0;
        std::vector<std::uint8_t> bestSet;
        for (std::size_t i = 0; i < pts.size(); ++i)
            for (std::size_t j = i + 1; j < pts.size(); ++j)
                for (std::size_t k = j + 1; k < pts.size(); ++k) {
                    Eigen::Vector3f n = (pts[j] - pts[i]).cross(pts[k] - pts[i]);
                    if (n.norm() < 1e-6f) continue;
                    n.normalize();
                    std::vector<std::uint8_t> in(pts.size(), 0);
                    std::size_t count = 0;
                    for (std::size_t m = 0; m < pts.size(); ++m)
                        count += in[m] = std::abs(n.dot(pts[m] - pts[i])) <= threshold;
                    if (count > best) best = count, bestSet = in;
                }
        std::vector<std::uint8_t> inlier;
        const gseg::PlaneFitResult r = gseg::fitPlane(pts.data(), pts.size(), params, seed, inlier);
        ASSERT_TRUE(r.valid) << "seed " << seed;
        EXPECT_EQ(std::size_t(onPlane), best) << "seed " << seed << ": the scene has one dominant plane";
        EXPECT_EQ(r.numInliers, best) << "seed " << seed;
        EXPECT_EQ(inlier, bestSet) << "seed " << seed;
        EXPECT_LT(gseg::planeSlopeDegrees(r.normal), 10.0) << "seed " << seed;
    }
}

INSTANTIATE_TEST_SUITE_P(Seeds, PlaneFitReference, ::testing::Range(std::uint64_t(1), std::uint64_t(61)));
