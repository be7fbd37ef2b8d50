// The voxel store of the maps (brick_map.hpp, private to the map layer): every voxel keeps the
// value that OctoMap's updateNode() gives it, whether a word's voxels are updated eight at a time
// (AVX2) or one at a time. Against a plain per-voxel reference, on seeded random scans over a few
// bricks: new voxels, voxels at both clamping bounds, occupied ground that misses leave alone,
// words that collapse to one value and open again.
#include "brick_map.hpp"
#include "../cpu_features.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <vector>

namespace {

using namespace gseg::map::detail;

float logOdds(double p) { return float(std::log(p / (1 - p))); }  // octomap::logodds()

LogOdds kittiLogOdds() {
    LogOdds l;
    l.hit = logOdds(0.7), l.miss = logOdds(0.4), l.clampMin = logOdds(0.12), l.clampMax = logOdds(0.97), l.occupied = logOdds(0.5);
    return l;
}

/// One value per voxel and map, updated as OccupancyOcTreeBase::updateNode() does.
struct Reference {
    LogOdds l;
    std::map<std::uint64_t, float> maps[2];
    void update(int m, std::uint64_t code, float delta, bool skipOccupied) {
        auto it = maps[m].find(code);
        const bool exists = it != maps[m].end();
        const float old = exists ? it->second : 0.f;
        if (skipOccupied && exists && old >= l.occupied) return;
        float v = old + delta;
        if (v < l.clampMin) v = l.clampMin;
        else if (v > l.clampMax) v = l.clampMax;
        maps[m][code] = v;
    }
};

TEST(BrickMap, WordsUpdatedEightAtOnceOrOneAtATimeKeepOctomapsValues) {
    if (!gseg::detail::cpuHasAvx2()) GTEST_SKIP() << "this CPU has no AVX2: only the one-at-a-time update runs (tested by every map test)";
    const LogOdds l = kittiLogOdds();
    BrickMap eight(l), one(l);
    eight.setEightAtOnce(true), one.setEightAtOnce(false);
    Reference ref{l, {}};
    const std::uint64_t bricks[] = {0x12345, 0x12346, 0x22345, 0x40000};  // Morton codes >> 9
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    for (int scan = 0; scan < 80; ++scan) {
        std::vector<std::uint64_t> free, groundHits, obstacleHits;
        for (std::uint64_t b : bricks) {
            // Per brick and scan: all its voxels free (words reach the lower bound and collapse),
            // a random share free, or mostly hits (words reach the upper bound).
            const double pick = u(rng), pFree = pick < 0.3 ? 1.0 : pick < 0.8 ? 0.5 : 0.1, pHit = pick < 0.8 ? 0.05 : 0.6;
            for (std::uint64_t v = 0; v < 512; ++v) {
                const std::uint64_t code = (b << 9) | v;
                if (u(rng) < pFree) free.push_back(code);
                else {  // hits are never in a scan's free list
                    if (u(rng) < pHit) groundHits.push_back(code);
                    if (u(rng) < pHit) obstacleHits.push_back(code);
                }
            }
        }
        eight.applyScan(gseg::map::VoxelBricks::fromCodes(free), groundHits, obstacleHits);
        one.applyScan(gseg::map::VoxelBricks::fromCodes(free), groundHits, obstacleHits);
        for (std::uint64_t c : free) ref.update(kGround, c, l.miss, true), ref.update(kObstacles, c, l.miss, false);
        for (std::uint64_t c : groundHits) ref.update(kGround, c, l.hit, false);
        for (std::uint64_t c : obstacleHits) ref.update(kObstacles, c, l.hit, false);
    }
    std::size_t atMin = 0, atMax = 0, occupiedGround = 0;
    for (int m : {kGround, kObstacles}) {
        for (std::uint64_t b : bricks)
            for (std::uint64_t v = 0; v < 512; ++v) {
                const std::uint64_t code = (b << 9) | v;
                const auto it = ref.maps[m].find(code);
                float a = 0, c = 0;
                const bool inEight = eight.value(MapIndex(m), code, a), inOne = one.value(MapIndex(m), code, c);
                ASSERT_EQ(inEight, it != ref.maps[m].end()) << "map " << m << " voxel " << code;
                ASSERT_EQ(inOne, inEight) << "map " << m << " voxel " << code;
                if (!inEight) continue;
                ASSERT_EQ(a, it->second) << "eight at once: map " << m << " voxel " << code;
                ASSERT_EQ(c, it->second) << "one at a time: map " << m << " voxel " << code;
                atMin += a == l.clampMin, atMax += a == l.clampMax;
                occupiedGround += m == kGround && a >= l.occupied;
            }
        for (bool occupied : {false, true}) EXPECT_EQ(eight.count(MapIndex(m), occupied), one.count(MapIndex(m), occupied));
    }
    // The scans reached what the test is about.
    EXPECT_GT(atMin, 500u);
    EXPECT_GT(atMax, 100u);
    EXPECT_GT(occupiedGround, 100u);
    EXPECT_EQ(eight.blocksInUse(), one.blocksInUse()) << "a word gets its block of values where a voxel changes, either way";
    EXPECT_LT(eight.blocksInUse(), 2u * 4u * 8u) << "some words hold one value for all";
}

}  // namespace
