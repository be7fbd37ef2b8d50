// #35: TraversabilityMap::apply() splits a scan's voxels into shards of bricks updated on several
// threads; the maps (every file write() writes, and the counters) are the same bytes for any number
// of threads, and the same as inserting scan by scan. On the six sequence-00 scans as a drive
// (skipped with a message where ../shared/data is absent) and on a synthetic drive.
#include <gseg/io/kitti.hpp>
#include <gseg/map/scan_update.hpp>
#include <gseg/map/traversability_map.hpp>
#include <support/child.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

struct Scan {
    std::vector<float> ground, obstacles;
    Eigen::Vector3d origin;
};

/// Every file of the map written to `dir/m`, in write()'s order (the YAML names its PGM alike).
std::vector<std::string> filesOf(const gseg::map::TraversabilityMap& m, const fs::path& dir) {
    std::vector<std::string> bytes;
    for (const std::string& path : m.write((dir / "m").string())) bytes.push_back(gseg::test::readText(path));
    return bytes;
}

void expectSameMapsForAnyThreads(const std::vector<Scan>& scans, const gseg::map::TraversabilityOptions& o, const std::string& name) {
    std::vector<gseg::map::ScanUpdate> updates;
    std::size_t voxels = 0;
    for (const Scan& s : scans) {
        updates.push_back(gseg::map::castScan(gseg::PointCloudView(s.ground.data(), s.ground.size() / 3),
                                              gseg::PointCloudView(s.obstacles.data(), s.obstacles.size() / 3), s.origin, o));
        voxels = std::max(voxels, updates.back().free.voxels());
    }
    ASSERT_GT(voxels, 100000u) << "scans big enough to be split over threads";
    std::vector<std::string> reference;
    gseg::map::MapStats referenceStats;
    for (unsigned threads : {1u, 2u, 3u, 4u, 8u}) {
        SCOPED_TRACE(name + ", " + std::to_string(threads) + " thread(s)");
        gseg::map::TraversabilityMap m(o);
        m.setUpdateThreads(threads);
        for (const auto& u : updates) m.apply(u);
        const fs::path dir = gseg::test::freshDir("update_threads", name + std::to_string(threads));
        const std::vector<std::string> files = filesOf(m, dir);
        const gseg::map::MapStats s = m.stats();
        fs::remove_all(dir);
        if (threads == 1) {
            reference = files, referenceStats = s;
            // The same as inserting scan by scan (castScan() and apply() on one thread).
            gseg::map::TraversabilityMap inserted(o);
            for (const Scan& scan : scans)
                inserted.insertScan(gseg::PointCloudView(scan.ground.data(), scan.ground.size() / 3),
                                    gseg::PointCloudView(scan.obstacles.data(), scan.obstacles.size() / 3), scan.origin);
            const fs::path dir2 = gseg::test::freshDir("update_threads", name + "inserted");
            EXPECT_TRUE(filesOf(inserted, dir2) == files);
            fs::remove_all(dir2);
            EXPECT_GT(s.groundVoxels, 1000u);
            EXPECT_GT(s.obstacleVoxels, 100u);
            continue;
        }
        ASSERT_EQ(files.size(), reference.size());
        for (std::size_t i = 0; i < files.size(); ++i) EXPECT_TRUE(files[i] == reference[i]) << "file " << i;
        EXPECT_EQ(s.groundVoxels, referenceStats.groundVoxels);
        EXPECT_EQ(s.obstacleVoxels, referenceStats.obstacleVoxels);
        EXPECT_EQ(s.freeVoxels, referenceStats.freeVoxels);
        EXPECT_EQ(s.clearedObstacleVoxels, referenceStats.clearedObstacleVoxels);
        EXPECT_EQ(s.brickValueBlocks, referenceStats.brickValueBlocks);
    }
}

/// #35, MPI: the voxels shared by `ranks` maps as rawlog-octomap's ranks share them (rank 0 applies
/// every update less the other holders' free and ground voxels, each other holder its takeVoxels()
/// through the wire format), merged into rank 0's map: every file the same bytes as one map's.
void expectSameMapsForAnyRanks(const std::vector<Scan>& scans, const gseg::map::TraversabilityOptions& o, const std::string& name) {
    std::vector<gseg::map::ScanUpdate> updates;
    for (const Scan& s : scans)
        updates.push_back(gseg::map::castScan(gseg::PointCloudView(s.ground.data(), s.ground.size() / 3),
                                              gseg::PointCloudView(s.obstacles.data(), s.obstacles.size() / 3), s.origin, o));
    gseg::map::TraversabilityMap one(o);
    for (const auto& u : updates) one.apply(u);
    const fs::path oneDir = gseg::test::freshDir("update_ranks", name + "one");
    const std::vector<std::string> reference = filesOf(one, oneDir);
    fs::remove_all(oneDir);
    const gseg::map::MapStats referenceStats = one.stats();
    for (int ranks : {2, 3, 4, 5}) {
        SCOPED_TRACE(name + ", " + std::to_string(ranks) + " ranks");
        std::vector<gseg::map::TraversabilityMap> maps;
        for (int r = 0; r < ranks; ++r) {
            maps.emplace_back(o);
            maps.back().shareVoxels(r, ranks);
        }
        std::vector<std::size_t> held(std::size_t(ranks), 0);  // voxels of each holder's parts
        for (const auto& u : updates) {
            gseg::map::ScanUpdate mine = u;
            for (int r = 1; r < ranks; ++r) {
                const gseg::map::ScanUpdate part = gseg::map::takeVoxels(mine, r, ranks);
                const std::vector<std::uint64_t> partFree = part.free.codes();
                for (const auto* codes : {&partFree, &part.groundHits, &part.obstacleHits})
                    for (std::uint64_t c : *codes) ASSERT_EQ(gseg::map::voxelOwner(c, ranks), r);
                held[std::size_t(r)] += partFree.size() + part.groundHits.size() + part.obstacleHits.size();
                maps[std::size_t(r)].apply(gseg::map::deserializeScanUpdate(gseg::map::serializeScanUpdate(part)));
            }
            for (std::uint64_t c : mine.free.codes()) ASSERT_EQ(gseg::map::voxelOwner(c, ranks), 0);
            for (std::uint64_t c : mine.groundHits) ASSERT_EQ(gseg::map::voxelOwner(c, ranks), 0);
            EXPECT_EQ(mine.obstacleHits, u.obstacleHits) << "the obstacle hits stay whole";
            held[0] += mine.free.voxels();
            maps[0].apply(mine);
        }
        for (int r = 0; r < ranks; ++r) {
            if (r < gseg::map::kVoxelHolders) EXPECT_GT(held[std::size_t(r)], 10000u) << "rank " << r << " holds voxels";
            else EXPECT_EQ(held[std::size_t(r)], 0u) << "rank " << r << " holds none";
        }
        EXPECT_LT(maps[0].stats().freeVoxels, referenceStats.freeVoxels) << "rank 0 alone holds part of them";
        for (int r = 1; r < ranks; ++r) maps[0].mergeVoxels(maps[std::size_t(r)].voxelBytes());
        const fs::path dir = gseg::test::freshDir("update_ranks", name + std::to_string(ranks));
        const std::vector<std::string> files = filesOf(maps[0], dir);
        fs::remove_all(dir);
        ASSERT_EQ(files.size(), reference.size());
        for (std::size_t i = 0; i < files.size(); ++i) EXPECT_TRUE(files[i] == reference[i]) << "file " << i;
        const gseg::map::MapStats s = maps[0].stats();
        EXPECT_EQ(s.groundVoxels, referenceStats.groundVoxels);
        EXPECT_EQ(s.obstacleVoxels, referenceStats.obstacleVoxels);
        EXPECT_EQ(s.freeVoxels, referenceStats.freeVoxels);
        EXPECT_EQ(s.clearedObstacleVoxels, referenceStats.clearedObstacleVoxels);
        EXPECT_EQ(s.brickValueBlocks, referenceStats.brickValueBlocks);
        EXPECT_EQ(s.bricks, referenceStats.bricks);
        if (ranks == 2) {  // a brick held twice, or bytes that are not voxels: refused, saying so
            EXPECT_THROW(maps[0].mergeVoxels(maps[1].voxelBytes()), std::runtime_error);
            EXPECT_THROW(maps[1].mergeVoxels("GSB1"), std::runtime_error);
            EXPECT_THROW(maps[1].mergeVoxels("not voxels"), std::runtime_error);
            EXPECT_THROW(maps[1].shareVoxels(2, 2), std::invalid_argument);
        }
    }
}

TEST(MapUpdateThreads, TheSixSequence00ScansAsADriveGiveTheSameBytesOnAnyNumberOfThreads) {
    std::vector<Scan> scans;
    for (int k = 0; k < 6; ++k) {
        const std::string rel = "semantickitti/sequences/00/velodyne/00000" + std::to_string(k) + ".bin";
        const std::string bin = gseg::test::sharedData(rel);
        if (bin.empty()) GTEST_SKIP() << gseg::test::missingDataMessage(rel);
        const std::vector<float> raw = gseg::io::readKittiBin(bin);
        Scan s;
        s.origin = Eigen::Vector3d(1.5 * k, 0.2 * k, 1.73);
        for (std::size_t i = 0; i + 3 < raw.size(); i += 4) {  // points below 0.3 m above the road as ground
            const float p[3] = {raw[i] + float(s.origin.x()), raw[i + 1] + float(s.origin.y()), raw[i + 2] + 1.73f};
            (p[2] < 0.3f ? s.ground : s.obstacles).insert((p[2] < 0.3f ? s.ground : s.obstacles).end(), p, p + 3);
        }
        scans.push_back(std::move(s));
    }
    expectSameMapsForAnyThreads(scans, gseg::map::TraversabilityOptions(), "seq00_");
}

TEST(MapUpdateThreads, ASyntheticDriveAtNegativeCoordinatesGivesTheSameBytesOnAnyNumberOfThreads) {
    // A street with walls and random clutter, driven towards negative x and y (bricks on every side of 0).
    std::mt19937 rng(35);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    std::vector<Scan> scans;
    for (int k = 0; k < 5; ++k) {
        Scan s;
        s.origin = Eigen::Vector3d(-2.0 * k - 0.05, -0.7 * k + 0.03, 1.8);
        for (int i = 0; i < 60000; ++i) {
            const float az = 6.2831853f * u(rng), r = 2.f + 38.f * u(rng);
            const float x = float(s.origin.x()) + r * std::cos(az), y = float(s.origin.y()) + r * std::sin(az);
            if (i % 3 == 0) {
                s.obstacles.insert(s.obstacles.end(), {x, y, 0.2f + 3.f * u(rng)});
            } else {
                s.ground.insert(s.ground.end(), {x, y, 0.05f * std::sin(0.3f * x) + 0.02f * u(rng)});
            }
        }
        scans.push_back(std::move(s));
    }
    gseg::map::TraversabilityOptions o;
    o.resolution = 0.15, o.maxRange = 30;
    expectSameMapsForAnyThreads(scans, o, "synthetic_");
}

TEST(MapUpdateThreads, VoxelsSharedByTwoToFiveRanksAndMergedGiveTheSameBytesAsOneMap) {
    std::mt19937 rng(12);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    std::vector<Scan> scans;
    for (int k = 0; k < 4; ++k) {
        Scan s;
        s.origin = Eigen::Vector3d(-3.0 * k + 0.4, 1.1 * k - 0.02, 1.7);
        for (int i = 0; i < 30000; ++i) {
            const float az = 6.2831853f * u(rng), r = 2.f + 28.f * u(rng);
            const float x = float(s.origin.x()) + r * std::cos(az), y = float(s.origin.y()) + r * std::sin(az);
            if (i % 4 == 0) s.obstacles.insert(s.obstacles.end(), {x, y, 0.3f + 2.5f * u(rng)});
            else s.ground.insert(s.ground.end(), {x, y, 0.04f * std::cos(0.2f * y) + 0.02f * u(rng)});
        }
        scans.push_back(std::move(s));
    }
    gseg::map::TraversabilityOptions o;
    o.resolution = 0.2, o.maxRange = 25;
    expectSameMapsForAnyRanks(scans, o, "ranks_");
}

}  // namespace
