// gseg bench: time the segmentation of scans, per scan, phase and step.
#include "commands.hpp"
#include "common/cli.hpp"

#include <gseg/ground_segmenter.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/scan_source.hpp>
#include <gseg/mrpt/segment_scan.hpp>
#include <gseg/ordered_pipeline.hpp>
#include <gseg/text.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <sys/resource.h>
#include <thread>

namespace gseg::app {
namespace {

// The build the numbers come from. GSEG_BUILD_TYPE (e.g. the CMake build type) if the build
// defines it, else what the compiler knows: optimisation on/off and NDEBUG.
#if defined(GSEG_BUILD_TYPE)
constexpr const char* kBuild = GSEG_BUILD_TYPE;
#elif defined(__OPTIMIZE__) && defined(NDEBUG)
constexpr const char* kBuild = "optimised, NDEBUG (Release-like)";
#elif defined(__OPTIMIZE__)
constexpr const char* kBuild = "optimised, assertions on";
#else
constexpr const char* kBuild = "unoptimised, assertions on (Debug): times are not representative";
#endif

struct Stats {
    double median = 0, p90 = 0, min = 0;
};

Stats stats(std::vector<double> v) {
    if (v.empty()) return {};
    std::sort(v.begin(), v.end());
    const auto at = [&](double q) { return v[std::min(v.size() - 1, std::size_t(q * double(v.size() - 1) + 0.5))]; };
    return {at(0.5), at(0.9), v.front()};
}

struct Sample {
    double total = 0;  ///< [ms] Result::totalMs
    StepTimes p1, p2;  ///< [ms] per step of phase I and II
};

struct Input {
    std::string name;
    ::gseg::mrpt::Scan scan;
    Params params;  ///< with the scan's own distToGround when the config says auto
};

/// The scans to time, with their parameters (with `distToGround: auto` the height estimated for the
/// scan, outside the timing; points with NaN or infinite coordinates are labelled non-ground by
/// the segmenter, uncounted in its work). A scan with no point cannot be timed and is listed in
/// `skipped`.
std::vector<Input> loadInputs(const std::vector<std::string>& paths, const std::string& config,
                              std::vector<std::string>& skipped) {
    const ::gseg::mrpt::LoadedConfig cfg = ::gseg::mrpt::loadConfigOrDefault(config);  // the one default without -c
    tools::noteWarnings("gseg bench", cfg.warnings);
    tools::detail("parameters (%s):\n%s", config.empty() ? "the default" : config.c_str(),
                  ::gseg::mrpt::toYaml(cfg).c_str());
    tools::say("%s\n", ::gseg::mrpt::heightSummary(cfg, config).c_str());
    std::vector<Input> inputs;
    for (const auto& path : paths) {
        Input in{std::filesystem::path(path).filename().string(), ::gseg::mrpt::loadScan(path), cfg.params};
        std::size_t nonFinite = 0;
        for (std::size_t i = 0; i < in.scan.size(); ++i)
            nonFinite += !std::isfinite(in.scan.xyzi[4 * i]) || !std::isfinite(in.scan.xyzi[4 * i + 1]) ||
                         !std::isfinite(in.scan.xyzi[4 * i + 2]);
        if (nonFinite == in.scan.size()) {
            skipped.push_back(in.name + ": no finite point to segment");
            tools::say("%s: skipped: no finite point to segment\n", in.name.c_str());
            continue;
        }
        if (nonFinite)
            tools::say("%s: %zu non-finite point(s) left out (labelled non-ground, not segmented)\n", in.name.c_str(),
                        nonFinite);
        if (cfg.distToGroundAuto) {
            const HeightDecision height = ::gseg::mrpt::ScanSegmenter(cfg)
                                              .segment(PointCloudView(in.scan.xyzi.data(), in.scan.size(), 16))
                                              .height;
            in.params.distToGround = height.height;
            tools::say("%s: distToGround auto %s\n", in.name.c_str(), height.describe().c_str());
        }
        inputs.push_back(std::move(in));
    }
    return inputs;
}

/// One thread's work: its own segmenter(s), one warm-up pass over all scans, then `repeat` timed
/// passes; samples[i] gets scan i's. A failure names the scan.
void timeOnThread(const std::vector<Input>& inputs, int repeat, bool perScanParams,
                  std::vector<std::vector<Sample>>& samples) {
    std::vector<GroundSegmenter> segs;
    for (std::size_t i = 0; i < (perScanParams ? inputs.size() : 1); ++i) segs.emplace_back(inputs[i].params);
    auto run = [&](std::size_t i) {
        const auto& s = inputs[i].scan;
        try {
            return segs[perScanParams ? i : 0].segment(PointCloudView(s.xyzi.data(), s.size(), 16), false);
        } catch (const std::exception& e) {
            throw std::runtime_error(inputs[i].name + ": " + e.what());
        }
    };
    for (std::size_t i = 0; i < inputs.size(); ++i) run(i);  // warm-up
    for (int r = 0; r < repeat; ++r)
        for (std::size_t i = 0; i < inputs.size(); ++i) {
            const Result res = run(i);
            samples[i].push_back({res.totalMs, res.phase1.ms, res.phase2.ms});
        }
}

/// timeOnThread() on `threads` threads at once (gseg::runOrdered, the one worker pool: one item
/// per thread). Returns the samples per scan (all threads) and the wall time of the whole run [s].
/// An exception in a thread is rethrown here once every thread has ended.
std::vector<std::vector<Sample>> timeAll(const std::vector<Input>& inputs, int repeat, int threads, bool perScanParams,
                                         double& wallS) {
    const unsigned n = unsigned(std::max(1, threads));
    std::vector<std::vector<std::vector<Sample>>> byThread(n, std::vector<std::vector<Sample>>(inputs.size()));
    const auto start = std::chrono::steady_clock::now();
    unsigned next = 0;
    runOrdered<unsigned, bool>([&](unsigned& t) { return next < n ? (t = next++, true) : false; },
                               [&](unsigned, unsigned& t) {
                                   timeOnThread(inputs, repeat, perScanParams, byThread[t]);
                                   return true;
                               },
                               [](std::size_t, bool&) {}, {n, n});
    wallS = gseg::secondsSince(start);
    std::vector<std::vector<Sample>> perScan(inputs.size());
    for (const auto& thread : byThread)
        for (std::size_t i = 0; i < inputs.size(); ++i) perScan[i].insert(perScan[i].end(), thread[i].begin(), thread[i].end());
    return perScan;
}

template <class Get>
Stats column(const std::vector<Sample>& samples, Get get) {
    std::vector<double> v;
    for (const Sample& s : samples) v.push_back(get(s));
    return stats(v);
}

void printPerScan(const std::vector<Input>& inputs, const std::vector<std::vector<Sample>>& perScan) {
    tools::say("\n%-22s %8s %10s %10s %10s %10s\n", "scan", "points", "median ms", "p90 ms", "min ms", "Mpoints/s");
    for (std::size_t i = 0; i < inputs.size(); ++i) {
        const Stats t = column(perScan[i], [](const Sample& s) { return s.total; });
        tools::say("%-22s %8zu %10.2f %10.2f %10.2f %10.2f\n", inputs[i].name.c_str(), inputs[i].scan.size(), t.median,
                    t.p90, t.min, double(inputs[i].scan.size()) / t.median / 1000.0);
    }
}

void printSteps(const std::vector<Sample>& all) {
    const struct {
        const char* name;
        double StepTimes::*step;
    } steps[] = {{"grid", &StepTimes::grid},
                 {"classification", &StepTimes::classification},
                 {"plane fit", &StepTimes::planeFit},
                 {"expansion", &StepTimes::expansion},
                 {"refinement", &StepTimes::refinement}};
    tools::say("\n%-16s %10s %10s   (median ms over all scans and repeats)\n", "step", "phase I", "phase II");
    for (const auto& st : steps)
        tools::say("%-16s %10.3f %10.3f\n", st.name, column(all, [&](const Sample& s) { return s.p1.*st.step; }).median,
                    column(all, [&](const Sample& s) { return s.p2.*st.step; }).median);
    tools::say("%-16s %10.3f %10.3f\n", "phase total", column(all, [](const Sample& s) { return s.p1.total(); }).median,
                column(all, [](const Sample& s) { return s.p2.total(); }).median);
}

int run(const std::vector<std::string>& paths, const std::string& config, int repeat, int threads) {
    std::vector<std::string> skipped;
    const std::vector<Input> inputs = loadInputs(paths, config, skipped);
    if (inputs.empty()) throw std::runtime_error("no scan to time (" + std::to_string(skipped.size()) + " skipped)");
    std::size_t points = 0;
    for (const auto& in : inputs) points += in.scan.size();
    const bool perScanParams = std::any_of(inputs.begin(), inputs.end(), [&](const Input& in) {
        return in.params.distToGround != inputs.front().params.distToGround;
    });
    tools::say("gseg bench: %zu scan(s), %zu points, warm-up + %d repeats, %d thread(s); build: %s; "
                "%u hardware threads\n",
                inputs.size(), points, repeat, threads, kBuild,
                std::thread::hardware_concurrency());

    double wallS = 0;
    const auto perScan = timeAll(inputs, repeat, threads, perScanParams, wallS);
    std::vector<Sample> all;
    for (const auto& v : perScan) all.insert(all.end(), v.begin(), v.end());
    printPerScan(inputs, perScan);
    const Stats t = column(all, [](const Sample& s) { return s.total; });
    tools::say("%-22s %8zu %10.2f %10.2f %10.2f %10.2f\n", "all scans", points / inputs.size(), t.median, t.p90,
                t.min, double(points) / double(inputs.size()) / t.median / 1000.0);
    printSteps(all);
    const double passes = double(repeat + 1) * threads;  // timed + warm-up passes in the wall time
    tools::say("\nthroughput: %.1f scans/s, %.2f Mpoints/s aggregate with %d thread(s) (wall %.2f s incl. warm-up)\n",
                passes * double(inputs.size()) / wallS, passes * double(points) / wallS / 1e6, threads, wallS);
    rusage ru{};
    ::getrusage(RUSAGE_SELF, &ru);
    tools::say("peak memory (ru_maxrss, scans loaded included): %.1f MB\n", double(ru.ru_maxrss) / 1024.0);
    if (!skipped.empty()) tools::say("%zu scan(s) skipped (named above)\n", skipped.size());
    return skipped.empty() ? tools::kDone : tools::kPartlyDone;
}

}  // namespace

int runBench(int argc, char** argv) {
    tools::CommandLine line("gseg bench",
                            "Time GSeg3D on scans: one warm-up pass, then median / p90 / min of the segment() call per "
                            "scan over N repeats, per phase and step, points per second, peak memory. Without "
                            "--config: the library defaults with distToGround: auto (the one default). The scans may also be given without -i (old form: gseg "
                            "bench SCAN...). Writes no file. Exit code: 0 done, 1 bad input, 2 bad usage, 3 done but "
                            "some scans could not be timed (named).",
                            false);
    TCLAP::CmdLine& cmd = line.cmd();
    TCLAP::MultiArg<std::string> input("i", "input", "a scan: KITTI .bin, PLY or rawlog (repeatable)", false, "SCAN", cmd);
    TCLAP::UnlabeledMultiArg<std::string> scanArgs("scans", "scans, old form (same as -i)", false, "SCAN", cmd);
    TCLAP::ValueArg<std::string> cfg("c", "config", "YAML or INI parameter file", false, "", "FILE", cmd);
    TCLAP::ValueArg<int> rep("", "repeat", "timed passes over all scans (default 20)", false, 20, "N", cmd);
    TCLAP::ValueArg<int> thr("", "threads", "N independent segmenters on N threads, each timing every scan "
                             "(scan-level parallelism; default 1)", false, 1, "N", cmd);
    if (const int code = line.parse(argc, argv); code >= 0) return code;
    std::vector<std::string> scans = input.getValue();
    scans.insert(scans.end(), scanArgs.getValue().begin(), scanArgs.getValue().end());
    const std::string config = cfg.getValue();
    const int repeat = rep.getValue(), threads = thr.getValue();
    if (scans.empty()) return line.usageError("no scan to time: give -i SCAN (repeatable)");
    if (repeat < 1 || threads < 1 || threads > 256)
        return line.usageError("--repeat must be >= 1 and --threads between 1 and 256");
    try {
        return run(scans, config, repeat, threads);
    } catch (...) {
        return tools::reportError("gseg bench", tools::InvalidArgument::BadInput);
    }
}

}  // namespace gseg::app
