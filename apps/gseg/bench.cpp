// gseg bench: time the segmentation of scans, per phase and step.
#include "cli.hpp"
#include "commands.hpp"

#include <gseg/ground_segmenter.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/scan_source.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <sys/resource.h>
#include <thread>

namespace gseg::app {
namespace {

#ifdef NDEBUG
constexpr const char* kBuild = "optimised (NDEBUG)";
#else
constexpr const char* kBuild = "debug (assertions on)";
#endif

struct Stats {
    double median = 0, p90 = 0, min = 0;
};

Stats stats(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    if (v.empty()) return {};
    return {v[v.size() / 2], v[std::min(v.size() - 1, std::size_t(0.9 * double(v.size())))], v.front()};
}

struct Sample {
    double total = 0;
    StepTimes p1, p2;
};

int run(const std::vector<std::string>& scans, const std::string& config, int repeat, int threads) {
    Params params;
    if (!config.empty()) {
        const auto cfg = mrpt::loadConfig(config);
        if (cfg.distToGroundAuto) throw std::runtime_error(config + ": bench needs a numeric distToGround");
        params = cfg.params;
    }
    std::vector<mrpt::Scan> loaded;
    std::size_t points = 0;
    for (const auto& s : scans) {
        loaded.push_back(mrpt::loadScan(s));
        points += loaded.back().size();
    }
    std::printf("gseg bench: %zu scans, %zu points, %d repeats, %d thread(s); build %s; %u hardware threads\n",
                loaded.size(), points, repeat, threads, kBuild, std::thread::hardware_concurrency());

    // Each thread has its own segmenter and segments every scan `repeat` times after a warm-up.
    std::vector<std::vector<Sample>> samples(static_cast<std::size_t>(threads));
    const auto wallStart = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t)
        pool.emplace_back([&, t] {
            GroundSegmenter seg(params);
            for (const auto& s : loaded) seg.segment(PointCloudView(s.xyzi.data(), s.size(), 16), false);
            for (int r = 0; r < repeat; ++r)
                for (const auto& s : loaded) {
                    const Result res = seg.segment(PointCloudView(s.xyzi.data(), s.size(), 16), false);
                    samples[std::size_t(t)].push_back({res.totalMs, res.phase1.ms, res.phase2.ms});
                }
        });
    for (auto& th : pool) th.join();
    const double wallS = std::chrono::duration<double>(std::chrono::steady_clock::now() - wallStart).count();

    std::vector<Sample> all;
    for (const auto& v : samples) all.insert(all.end(), v.begin(), v.end());
    auto column = [&](auto get) {
        std::vector<double> v;
        for (const Sample& s : all) v.push_back(get(s));
        return stats(v);
    };
    const Stats total = column([](const Sample& s) { return s.total; });
    std::printf("per scan: median %.2f ms, p90 %.2f ms, min %.2f ms; %.2f M points/s per thread\n", total.median,
                total.p90, total.min, double(points) / double(loaded.size()) / total.median / 1000.0);
    const struct {
        const char* name;
        double StepTimes::*step;
    } steps[] = {{"grid", &StepTimes::grid},
                 {"classification", &StepTimes::classification},
                 {"plane fit", &StepTimes::planeFit},
                 {"expansion", &StepTimes::expansion},
                 {"refinement", &StepTimes::refinement}};
    std::printf("%-16s %12s %12s\n", "median ms", "phase I", "phase II");
    for (const auto& st : steps)
        std::printf("%-16s %12.3f %12.3f\n", st.name, column([&](const Sample& s) { return s.p1.*st.step; }).median,
                    column([&](const Sample& s) { return s.p2.*st.step; }).median);
    std::printf("%-16s %12.3f %12.3f\n", "phase total", column([](const Sample& s) { return s.p1.total(); }).median,
                column([](const Sample& s) { return s.p2.total(); }).median);
    std::printf("throughput: %.1f scans/s with %d thread(s)\n", double(all.size()) / wallS, threads);
    rusage ru{};
    ::getrusage(RUSAGE_SELF, &ru);
    std::printf("peak memory: %.1f MB\n", double(ru.ru_maxrss) / 1024.0);
    return 0;
}

}  // namespace

int runBench(int argc, char** argv) {
    std::vector<std::string> scans;
    std::string config;
    int repeat = 20, threads = 1;
    try {
        TCLAP::CmdLine cmd("Time GSeg3D on scans: warm-up, then median / p90 / min per scan, per phase and step.", ' ',
                           "0.1");
        TCLAP::UnlabeledMultiArg<std::string> scanArgs("scans", "KITTI .bin, PLY or rawlog files", true, "SCAN", cmd);
        TCLAP::ValueArg<std::string> cfg("c", "config", "YAML or INI parameter file", false, "", "FILE", cmd);
        TCLAP::ValueArg<int> rep("", "repeat", "timed passes over all scans (default 20)", false, 20, "N", cmd);
        TCLAP::ValueArg<int> thr("", "threads", "independent segmenters on N threads (default 1)", false, 1, "N", cmd);
        if (const int code = parseArgs(cmd, argc, argv); code >= 0) return code;
        scans = scanArgs.getValue(), config = cfg.getValue(), repeat = rep.getValue(), threads = thr.getValue();
    } catch (const TCLAP::ArgException& e) {
        std::fprintf(stderr, "gseg bench: %s (%s)\n", e.error().c_str(), e.argId().c_str());
        return 2;
    }
    if (repeat < 1 || threads < 1 || threads > 256) {
        std::fprintf(stderr, "gseg bench: --repeat must be >= 1 and --threads between 1 and 256\n");
        return 2;
    }
    try {
        return run(scans, config, repeat, threads);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "gseg bench: %s\n", e.what());
        return 1;
    }
}

}  // namespace gseg::app
