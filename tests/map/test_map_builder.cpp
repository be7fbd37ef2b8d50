// The map builder's parts, without the tool: ScanStream (scans with their poses, pairs taken as
// they are), ScanWorker (the per-scan work, independent of the map, of other scans and of the
// order), MapBuilder (ordered integration: the same maps with any number of workers, local or
// remote, and through insert(), the plugin's route). On a simulated drive (tests/support/lidar_sim).
#include <gseg/map/map_builder.hpp>
#include <gseg/map/scan_message.hpp>

#include <support/child.hpp>
#include <support/sim_drive.hpp>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using gseg::map::BuildOptions;
using gseg::map::MapBuilder;
using gseg::map::ScanJob;
using gseg::map::ScanResult;
using gseg::map::ScanStream;
using gseg::map::ScanWorker;

constexpr int kScans = 6;

/// Options of a drive of kScans scans (tests/support/sim_drive.hpp).
struct Drive {
    bool pairs = false;     ///< each scan also as its LIDAR_ground / LIDAR_obstacles pair (rawlog-gseg without --replace)
    int tinyScan = -1;      ///< this scan sees only the floor within 1.2 m: no height estimate
    int emptyScan = -1;     ///< this scan has no points
};

std::string writeDrive(const std::string& name, const Drive& d = {}) {
    const std::string path = (gseg::test::freshDir("map_builder", name) / "drive.rawlog").string();
    gseg::test::Drive sim;
    sim.layout = d.pairs ? gseg::test::Drive::RawAndPair : gseg::test::Drive::Raw;
    sim.tinyScan = d.tinyScan, sim.emptyScan = d.emptyScan;
    sim.scans = kScans, sim.azimuthStepDeg = 1.0;  // small scans: quick
    gseg::test::writeDrive(path, sim);
    return path;
}

gseg::map::PoseConfig poses(const std::string& rawlog) {
    gseg::map::PoseConfig c;
    c.input = rawlog;
    return c;
}

std::vector<ScanJob> readAll(ScanStream& stream) {
    std::vector<ScanJob> jobs;
    for (ScanJob job; stream.next(job);) jobs.push_back(job);
    return jobs;
}

gseg::mrpt::LoadedConfig fixedHeight() {
    gseg::mrpt::LoadedConfig c;
    c.params.distToGround = 1.8;
    return c;
}

gseg::mrpt::LoadedConfig autoHeight() {
    gseg::mrpt::LoadedConfig c;
    c.params.distToGround = 1.8;  // the fallback
    c.distToGroundAuto = true;
    return c;
}

/// The maps as bytes: both OcTrees as OctoMap writes them, and the counters.
std::string mapBytes(const gseg::map::TraversabilityMap& map) {
    std::ostringstream out;
    map.groundTree().writeBinaryConst(out);
    map.obstacleTree().writeBinaryConst(out);
    const gseg::map::MapStats s = map.stats();
    out << s.scans << ' ' << s.groundPoints << ' ' << s.obstaclePoints << ' ' << s.rays << ' ' << s.groundVoxels << ' '
        << s.obstacleVoxels << ' ' << s.freeVoxels;
    for (const auto& p : map.path()) out << ' ' << p.transpose();
    return out.str();
}

std::string buildWith(const std::string& rawlog, const gseg::mrpt::LoadedConfig& cfg, BuildOptions how,
                      MapBuilder** keep = nullptr) {
    ScanStream stream(poses(rawlog));
    static std::unique_ptr<MapBuilder> last;
    last = std::make_unique<MapBuilder>(cfg, gseg::map::TraversabilityOptions());
    last->run(stream, how);
    if (keep) *keep = last.get();
    return mapBytes(last->map());
}

TEST(MapBuilderStream, ScansComeInOrderWithTheirPosesAndPairsReplaceTheRawScan) {
    const std::string rawlog = writeDrive("stream", {true});
    ScanStream stream(poses(rawlog));
    const std::vector<ScanJob> jobs = readAll(stream);
    ASSERT_EQ(jobs.size(), std::size_t(kScans));
    for (int k = 0; k < kScans; ++k) {
        const ScanJob& j = jobs[std::size_t(k)];
        EXPECT_EQ(j.index, std::size_t(k));
        EXPECT_EQ(j.label, "LIDAR");
        EXPECT_NEAR(j.t, 100.0 + 0.1 * k, 1e-6);
        EXPECT_NEAR(j.robotPose.x(), 3.0 * k, 1e-9);
        EXPECT_TRUE(j.presegmented()) << j.describe();
        EXPECT_FALSE(j.raw) << "the pair is used, the raw scan is not segmented again";
        ASSERT_TRUE(j.ground && j.obstacles);
        EXPECT_EQ(j.ground->sensorLabel, "LIDAR_ground");
    }
    EXPECT_EQ(stream.rawScansSeenWithTheirPair(), std::size_t(kScans));
    EXPECT_NEAR(jobs.back().fraction, 1.0, 1e-9);
    EXPECT_NE(jobs[2].describe().find("scan 2 ('LIDAR' at rawlog entry"), std::string::npos) << jobs[2].describe();
}

TEST(MapBuilderWorker, ResultsDependOnTheScanAloneNotOnTheWorkerOrTheOrder) {
    const std::string rawlog = writeDrive("order", {false, 2});
    ScanStream stream(poses(rawlog));
    const std::vector<ScanJob> jobs = readAll(stream);
    for (const auto& cfg : {fixedHeight(), autoHeight()}) {
        ScanWorker forward(cfg, {}), backward(cfg, {});
        std::vector<ScanResult> a, b(jobs.size());
        for (const ScanJob& j : jobs) a.push_back(forward(j));
        for (std::size_t i = jobs.size(); i-- > 0;) b[i] = backward(jobs[i]);
        for (std::size_t i = 0; i < jobs.size(); ++i) {
            EXPECT_TRUE(a[i].skipped.empty()) << a[i].skipped;
            EXPECT_FALSE(a[i].update.groundHits.empty()) << jobs[i].describe();
            EXPECT_TRUE(a[i].update == b[i].update) << jobs[i].describe() << " differs in reverse order";
            EXPECT_EQ(a[i].notes.heightNote, b[i].notes.heightNote);
        }
        if (cfg.distToGroundAuto) {
            // The one height rule: scan 2 has no estimate and gets the configured height, not scan 1's estimate.
            EXPECT_NE(a[2].notes.heightNote.find("1.80 m (fallback"), std::string::npos) << a[2].notes.heightNote;
            EXPECT_TRUE(a[1].notes.heightNote.empty()) << a[1].notes.heightNote;
            EXPECT_TRUE(a[3].notes.heightNote.empty()) << a[3].notes.heightNote;
        } else {
            EXPECT_TRUE(a[2].notes.heightNote.empty()) << "a fixed height has no fallback";
        }
    }
}

TEST(MapBuilderWorker, AScanWithoutPointsComesBackSkippedWithItsReason) {
    const std::string rawlog = writeDrive("empty", {false, -1, 3});
    ScanStream stream(poses(rawlog));
    const std::vector<ScanJob> jobs = readAll(stream);
    ScanWorker worker(fixedHeight(), {});
    const ScanResult r = worker(jobs[3]);
    EXPECT_NE(r.skipped.find("has no points"), std::string::npos) << r.skipped;
    EXPECT_EQ(r.describe, jobs[3].describe());
    EXPECT_TRUE(worker(jobs[4]).skipped.empty()) << "the worker goes on after a skipped scan";
}

TEST(MapBuilderWorker, AFixedHeightIsCheckedOnTheFirstScanOnly) {
    const std::string rawlog = writeDrive("check");
    ScanStream stream(poses(rawlog));
    const std::vector<ScanJob> jobs = readAll(stream);
    gseg::mrpt::LoadedConfig wrong;
    wrong.params.distToGround = 0.6;  // the sensor is 1.8 m up
    ScanWorker worker(wrong, {});
    EXPECT_TRUE(worker(jobs[1]).notes.heightWarning.empty()) << "only scan 0 is checked (any worker may get it)";
    EXPECT_NE(worker(jobs[0]).notes.heightWarning.find("distToGround is 0.600 m"), std::string::npos);
}

TEST(MapBuilder, TheSameMapsWithAnyNumberOfWorkers) {
    const std::string rawlog = writeDrive("threads", {false, 2});
    for (const auto& cfg : {fixedHeight(), autoHeight()}) {
        BuildOptions serial;
        const std::string one = buildWith(rawlog, cfg, serial);
        EXPECT_GT(one.size(), 1000u);
        for (unsigned threads : {1u, 3u}) {
            BuildOptions how;
            how.threads = threads;
            EXPECT_TRUE(buildWith(rawlog, cfg, how) == one) << threads << " worker thread(s)";
        }
    }
}

TEST(MapBuilder, RemoteWorkersShareTheScansAndGiveTheSameMaps) {
    const std::string rawlog = writeDrive("remote");
    const std::string local = buildWith(rawlog, fixedHeight(), BuildOptions());
    ScanWorker elsewhere(fixedHeight(), {});  // stands for a worker thread of MPI rank 1
    BuildOptions how;
    how.threads = 0;  // rank 0 only maps (--rank0-maps-only)
    how.remoteWorkers = 1;
    how.ranks = 2;
    how.remoteWork = [&](unsigned slot, const ScanJob& job) {
        EXPECT_EQ(slot, 0u);
        ScanResult r = elsewhere(job);
        r.rank = 1;
        return r;
    };
    std::vector<std::size_t> order;
    how.onScan = [&](std::size_t k, const ScanResult&) { order.push_back(k); };
    MapBuilder* builder = nullptr;
    EXPECT_TRUE(buildWith(rawlog, fixedHeight(), how, &builder) == local);
    EXPECT_EQ(builder->tally().scansByRank, (std::vector<std::size_t>{0, std::size_t(kScans)}));
    EXPECT_EQ(order, (std::vector<std::size_t>{0, 1, 2, 3, 4, 5}));
}

TEST(MapBuilder, ScansAndResultsThroughTheWireFormatGiveTheSameMaps) {
    // What rawlog-octomap's MPI ranks send (gseg/map/scan_message.hpp): a scan to a worker, its
    // result back, each as bytes; the maps are those of one process, byte for byte.
    const std::string rawlog = writeDrive("wire", {true});
    const std::string local = buildWith(rawlog, autoHeight(), BuildOptions());
    ScanWorker elsewhere(autoHeight(), {});
    BuildOptions how;
    how.threads = 0, how.remoteWorkers = 1, how.ranks = 2;
    how.remoteWork = [&](unsigned, const ScanJob& job) {
        const ScanJob there = gseg::map::decodeScanJob(gseg::map::encodeScanJob(job));
        EXPECT_EQ(there.describe(), job.describe());
        EXPECT_EQ(there.presegmented(), job.presegmented());
        ScanResult r = elsewhere(there);
        r.rank = 1;
        const ScanResult back = gseg::map::decodeScanResult(gseg::map::encodeScanResult(r));
        EXPECT_TRUE(back.update == r.update);
        EXPECT_EQ(back.notes.heightNote, r.notes.heightNote);
        EXPECT_EQ(back.rank, 1);
        return back;
    };
    EXPECT_TRUE(buildWith(rawlog, autoHeight(), how) == local);
}

TEST(MapBuilder, AScanErrorOrAGarbledMessageThroughTheWireFormatThrows) {
    try {
        gseg::map::decodeScanResult(gseg::map::encodeScanError("scan 3: no points"));
        ADD_FAILURE() << "an error reply must throw";
    } catch (const std::runtime_error& e) {
        EXPECT_STREQ(e.what(), "scan 3: no points");
    }
    EXPECT_THROW(gseg::map::decodeScanResult(std::string(8, '\x07')), std::runtime_error);
    const std::string job = gseg::map::encodeScanJob(ScanJob());
    EXPECT_THROW(gseg::map::decodeScanJob(job.substr(0, job.size() - 1)), std::runtime_error);
}

TEST(MapBuilder, AnErrorOfOneScanIsRethrownAndTheScansBeforeItAreIntegrated) {
    const std::string rawlog = writeDrive("error");
    BuildOptions how;
    how.threads = 0;
    how.remoteWorkers = 2;
    ScanWorker w0(fixedHeight(), {}), w1(fixedHeight(), {});
    how.remoteWork = [&](unsigned slot, const ScanJob& job) {
        if (job.index == 3) throw std::runtime_error(job.describe() + ": lost on rank 1");
        return slot == 0 ? w0(job) : w1(job);
    };
    ScanStream stream(poses(rawlog));
    MapBuilder builder(fixedHeight(), gseg::map::TraversabilityOptions());
    try {
        builder.run(stream, how);
        FAIL() << "no error";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("scan 3 ("), std::string::npos) << e.what();
    }
    EXPECT_EQ(builder.map().path().size(), 3u) << "scans 0-2 were integrated, nothing after the error";
}

TEST(MapBuilder, SkippedScansAreCountedAndTheOthersMapped) {
    const std::string rawlog = writeDrive("skipped", {false, -1, 3});
    MapBuilder* builder = nullptr;
    BuildOptions how;
    how.threads = 2;
    buildWith(rawlog, fixedHeight(), how, &builder);
    ASSERT_EQ(builder->tally().skipped.size(), 1u);
    EXPECT_NE(builder->tally().skipped[0].find("scan 3 ("), std::string::npos) << builder->tally().skipped[0];
    EXPECT_EQ(builder->map().path().size(), std::size_t(kScans - 1));
}

TEST(MapBuilder, InsertingObservationsOneByOneGivesTheMapsOfTheStream) {
    // The plugin's route (observations2map gives one observation and its robot pose at a time)
    // and the tool's are the same builder: the same maps, fixed or automatic height.
    const std::string rawlog = writeDrive("insert", {false, 2});
    for (const auto& cfg : {fixedHeight(), autoHeight()}) {
        const std::string streamed = buildWith(rawlog, cfg, BuildOptions());
        ScanStream stream(poses(rawlog));
        MapBuilder one(cfg, gseg::map::TraversabilityOptions());
        for (const ScanJob& job : readAll(stream)) EXPECT_TRUE(one.insert(*job.raw, job.robotPose)) << job.describe();
        EXPECT_TRUE(mapBytes(one.map()) == streamed) << (cfg.distToGroundAuto ? "auto" : "fixed");
        EXPECT_EQ(one.tally().heightFallbacks.size(), cfg.distToGroundAuto ? 1u : 0u);
        one.clear();
        EXPECT_TRUE(one.map().empty());
        EXPECT_TRUE(one.tally().heightFallbacks.empty());
    }
}

TEST(MapBuilder, InsertTakesPairPartsAsTheyAreAndRefusesWhatIsNoScan) {
    const std::string rawlog = writeDrive("parts", {true});
    ScanStream stream(poses(rawlog));
    MapBuilder builder(fixedHeight(), gseg::map::TraversabilityOptions());
    const std::vector<ScanJob> jobs = readAll(stream);
    EXPECT_TRUE(builder.insert(*jobs[0].ground, jobs[0].robotPose));
    EXPECT_TRUE(builder.insert(*jobs[0].obstacles, jobs[0].robotPose));
    EXPECT_EQ(builder.tally().presegmented, 2u);
    EXPECT_GT(builder.map().stats().groundVoxels, 100u);
    mrpt::obs::CObservationRobotPose notAScan;
    EXPECT_FALSE(builder.insert(notAScan, mrpt::poses::CPose3D()));
    EXPECT_EQ(builder.map().path().size(), 2u);
}

}  // namespace
