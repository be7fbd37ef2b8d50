// rawlog-octomap --bench: the speed of rawlog-octomap against plain OctoMap on the same rawlog.
//
// The anchor is what a user of OctoMap (or octomap_server) does today: every point of every scan
// in the world frame, OcTree::insertPointCloud(cloud, sensor origin, maxRange, lazy = false,
// discretize = true), then OcTree::writeBinary(). Both read the same rawlog with the same poses.
// Rounds alternate which of the two runs first, so a machine that gets busier or quieter during
// the benchmark affects both alike.

#include "rawlog_octomap.hpp"

#include "common/cli.hpp"

#include <gseg/io/atomic_file.hpp>

#include <gseg/map/world_scan.hpp>
#include <gseg/text.hpp>
#include <gseg/ordered_pipeline.hpp>

#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <thread>

#include <fcntl.h>
#include <unistd.h>

namespace rawlog_octomap {
namespace {

using Clock = std::chrono::steady_clock;

/// OctoMap's writeBinary() prints " done." to stderr (its OCTOMAP_DEBUG is on in Debian's build);
/// the benchmark's table should not carry it. Restores stderr on every path.
class QuietStderr {
public:
    QuietStderr() : saved_(::dup(STDERR_FILENO)) {
        const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
        if (saved_ >= 0 && null >= 0) std::fflush(stderr), ::dup2(null, STDERR_FILENO);
        if (null >= 0) ::close(null);
    }
    ~QuietStderr() {
        if (saved_ < 0) return;
        std::fflush(stderr);
        ::dup2(saved_, STDERR_FILENO);
        ::close(saved_);
    }
    QuietStderr(const QuietStderr&) = delete;
    QuietStderr& operator=(const QuietStderr&) = delete;

private:
    int saved_;
};

struct AnchorTimes {
    double total = 0, insert = 0;
    std::size_t scans = 0, points = 0;
};

/// Plain OctoMap: one occupancy tree of all points, ray cast by OctoMap itself.
AnchorTimes plainOctomap(const Cli& cli, const std::string& bt) {
    const auto start = Clock::now();
    AnchorTimes a;
    ScanStream stream(cli.poses);
    octomap::OcTree tree(cli.options.resolution);
    tree.setProbHit(cli.options.probHit), tree.setProbMiss(cli.options.probMiss);
    tree.setClampingThresMin(cli.options.clampMin), tree.setClampingThresMax(cli.options.clampMax);
    ScanJob job;
    std::vector<float> xyz;
    while (stream.next(job)) {
        xyz.clear();
        Eigen::Vector3d origin = Eigen::Vector3d::Zero();
        for (const auto* part : {&job.raw, &job.ground, &job.obstacles})
            if (*part) origin = gseg::map::appendWorldPoints(**part, job.robotPose, xyz);
        octomap::Pointcloud cloud;
        cloud.reserve(xyz.size() / 3);
        for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) cloud.push_back(xyz[i], xyz[i + 1], xyz[i + 2]);
        const auto t0 = Clock::now();
        tree.insertPointCloud(cloud, octomap::point3d(float(origin.x()), float(origin.y()), float(origin.z())),
                              cli.options.maxRange, false, true);
        a.insert += gseg::secondsSince(t0);
        ++a.scans, a.points += cloud.size();
    }
    bool written = false;
    {
        const QuietStderr quiet;
        written = tree.writeBinary(bt);
    }
    if (!written) throw std::runtime_error(bt + ": cannot write");
    a.total = gseg::secondsSince(start);
    return a;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

void runBench(const Cli& cli) {
    Cli ours = cli;
    ours.prefix = cli.prefix + "_bench";
    ours.overwrite = true;  // every round writes them again (checked here, before the first)
    const std::string plainBt = cli.prefix + "_bench_plain.bt";
    std::vector<gseg::io::NamedPath> outputs = {{"-o", plainBt}};
    for (const std::string& path : gseg::map::TraversabilityMap::pathsToCheck(ours.prefix)) outputs.push_back({"-o", path});
    gseg::io::checkOutputs({{"input", cli.input}, {"--poses", cli.poses.poses}, {"--calib", cli.poses.calib}, {"-c", cli.config}},
                           outputs, {cli.overwrite, false});
#ifdef NDEBUG
    const char* build = "Release";
#else
    const char* build = "Debug (assertions on)";
#endif
    gseg::tools::say("rawlog-octomap --bench: %s, %d round(s), build %s, %u hardware thread(s) (%u usable), %u worker thread(s)\n",
                cli.input.c_str(), cli.benchRounds, build, std::thread::hardware_concurrency(),
                gseg::usableCores(), cli.threads);
    gseg::tools::say("%-6s %-16s %10s %12s\n", "round", "run", "wall [s]", "note");
    std::vector<double> plain, plainInsert, fast;
    RunReport last;
    for (int round = 0; round < cli.benchRounds; ++round) {
        for (int k = 0; k < 2; ++k) {
            if ((round % 2 == 0) == (k == 0)) {
                const AnchorTimes a = plainOctomap(cli, plainBt);
                plain.push_back(a.total), plainInsert.push_back(a.insert);
                gseg::tools::say("%-6d %-16s %10.3f   insertPointCloud %.3f s, %zu scans, %zu points\n", round + 1,
                            "plain OctoMap", a.total, a.insert, a.scans, a.points);
            } else {
                last = buildMaps(ours, true);
                fast.push_back(last.wallSeconds);
                gseg::tools::say("%-6d %-16s %10.3f   %zu scans\n", round + 1, "rawlog-octomap", last.wallSeconds,
                            last.stats.scans);
            }
            std::fflush(stdout);
        }
    }
    const double p = median(plain), pi = median(plainInsert), f = median(fast);
    gseg::tools::say("median: plain OctoMap %.3f s (insertPointCloud alone %.3f s), rawlog-octomap %.3f s: %.1fx faster "
                "(%.1fx against insertPointCloud alone)\n",
                p, pi, f, p / f, pi / f);
    const PhaseTimes& t = last.tally.times;
    gseg::tools::say("rawlog-octomap, last round [s]: read %.3f, segmentation %.3f, transform %.3f, ray casting %.3f "
                "(summed over %u worker thread(s)), map update %.3f, writing %.3f\n",
                t.read, t.segmentation, t.transform, t.rayCasting, cli.threads, t.mapUpdate, t.writing);
}

}  // namespace rawlog_octomap
