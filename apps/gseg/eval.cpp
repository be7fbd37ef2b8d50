// gseg eval: precision / recall on SemanticKITTI under the Ground Segmentation Benchmark protocol.
#include "cli.hpp"
#include "commands.hpp"
#include "eval_plot.hpp"
#include "eval_report.hpp"
#include "progress.hpp"

#include <gseg/ground_segmenter.hpp>
#include <gseg/io/kitti.hpp>
#include <gseg/metrics.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/sensor_height.hpp>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;

namespace gseg::app {
namespace {

struct Frame {
    std::string sequence, name, scan, label;
};

struct FrameResult {
    FrameRow row;
    std::string skipped;     ///< why the frame was not scored ("" if it was)
    std::string heightNote;  ///< distToGround: auto could not estimate: what was used instead
};

struct Setup {
    Params params;
    bool autoHeight = false;  ///< distToGround: auto, estimated per frame
    std::string predDir;      ///< write each frame's predictions here ("" = not)
    bool breakdown = false;   ///< count where the errors are
    std::string pictureDir;   ///< breakdown picture per frame here ("" = none)
};

std::vector<Frame> findFrames(const fs::path& root, const std::vector<std::string>& only) {
    const fs::path seqDir = root / "sequences";
    if (!fs::is_directory(seqDir))
        throw std::runtime_error(root.string() + ": no sequences/ folder (SemanticKITTI layout expected)");
    std::vector<Frame> frames;
    for (const auto& seq : fs::directory_iterator(seqDir)) {
        const std::string name = seq.path().filename().string();
        if (!only.empty() && std::find(only.begin(), only.end(), name) == only.end()) continue;
        if (!fs::is_directory(seq.path() / "velodyne")) continue;
        for (const auto& bin : fs::directory_iterator(seq.path() / "velodyne"))
            if (bin.path().extension() == ".bin")
                frames.push_back({name, bin.path().stem().string(), bin.path().string(),
                                  (seq.path() / "labels" / (bin.path().stem().string() + ".label")).string()});
    }
    std::sort(frames.begin(), frames.end(), [](const Frame& a, const Frame& b) {
        return std::tie(a.sequence, a.name) < std::tie(b.sequence, b.name);
    });
    if (frames.empty())
        throw std::runtime_error(root.string() + ": no scans under sequences/*/velodyne/*.bin" +
                                 (only.empty() ? "" : " for the sequences asked for"));
    return frames;
}

/// A worker's segmenter: the fixed-height one, or with `distToGround: auto` the estimating one
/// (frames are independent: each worker's frames get their own estimate, falling back to the
/// configured height where a frame gives none).
struct FrameSegmenter {
    explicit FrameSegmenter(const Setup& setup) : fixed(setup.params), automatic(setup.params), useAuto(setup.autoHeight) {}
    Result segment(const PointCloudView& cloud, std::string& note) {
        if (!useAuto) return fixed.segment(cloud, false);
        automatic.reset();  // frames of a tree are independent: no history (and any thread count agrees)
        Result r = automatic.segment(cloud, false);
        if (automatic.lastDecision().source != HeightDecision::Source::Estimated) note = automatic.lastDecision().describe();
        return r;
    }
    GroundSegmenter fixed;
    AutoHeightSegmenter automatic;
    bool useAuto;
};

/// `warmUp`: segment once untimed first (a worker's first frame), so ms is a warm call's time.
FrameResult evaluate(FrameSegmenter& seg, const Frame& f, const Setup& setup, bool warmUp) {
    FrameResult out;
    out.row.sequence = f.sequence, out.row.name = f.name;
    if (!fs::exists(f.label)) {
        out.skipped = "no label file " + f.label;
        return out;
    }
    try {
        const std::vector<float> pts = io::readKittiBin(f.scan);
        const PointCloudView cloud(pts.data(), pts.size() / 4, 4 * sizeof(float));
        const std::vector<std::uint32_t> labels = io::readKittiLabels(f.label, cloud.size());
        std::string note;
        if (warmUp) seg.segment(cloud, note);
        const Result r = seg.segment(cloud, note);
        out.heightNote = note;
        out.row.points = cloud.size();
        out.row.ms = r.totalMs;
        out.row.score = scoreFrame(cloud, labels, r.labels);
        if (setup.breakdown) {
            std::vector<PointOutcome> outcomes;
            out.row.breakdown = breakdownFrame(cloud, labels, r.labels, BreakdownOptions(), &outcomes);
            if (!setup.pictureDir.empty())
                plotOutcomes(setup.pictureDir + "/" + f.sequence + "_" + f.name + ".png", cloud, outcomes,
                             "sequence " + f.sequence + ", frame " + f.name + ": true / false / missed ground");
        }
        if (!setup.predDir.empty())
            io::writeFileAtomic(setup.predDir + "/" + f.sequence + "_" + f.name + ".pred", r.labels.data(),
                                r.labels.size());
    } catch (const std::exception& e) {
        out.skipped = e.what();
    }
    return out;
}

/// The frames `todo` (indices into `frames`) are handed out one at a time to `threads` workers,
/// each with its own segmenter; the segmenter is deterministic, so the results equal a serial run's.
std::vector<FrameResult> evaluateAll(const std::vector<Frame>& frames, const std::vector<std::size_t>& todo,
                                     const Setup& setup, int threads) {
    std::vector<FrameResult> results(frames.size());
    std::atomic<std::size_t> next{0};
    Progress progress("evaluating", todo.size());
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t)
        pool.emplace_back([&] {
            FrameSegmenter seg(setup);
            bool first = true;
            for (std::size_t k; (k = next++) < todo.size();) {
                const std::size_t i = todo[k];
                results[i] = evaluate(seg, frames[i], setup, first);
                first = first && !results[i].skipped.empty();
                progress.step();
            }
        });
    for (auto& th : pool) th.join();
    return results;
}

/// Under MPI: the frames split over the ranks by their points (the size of the .bin), each rank
/// evaluating its own with `threads` workers; rank 0 gathers every result, exactly, and returns
/// them in frame order (the other ranks return nothing). One process: all frames here.
std::vector<FrameResult> evaluateOnRanks(const std::vector<Frame>& frames, const Setup& setup, int threads,
                                         tools::Ranks& ranks) {
    std::vector<std::string> scans;
    for (const Frame& f : frames) scans.push_back(f.scan);
    std::vector<int> owner;
    auto evaluateMine = [&](const std::vector<std::size_t>& mine) {
        const std::vector<FrameResult> results = evaluateAll(frames, mine, setup, threads);
        std::vector<std::string> bytes;
        for (const std::size_t i : mine) {
            tools::ByteWriter out;
            writeRow(out, results[i].row);
            bytes.push_back(out.str(results[i].skipped).str(results[i].heightNote).bytes());
        }
        return bytes;
    };
    const std::vector<std::string> all = tools::shareItems(ranks, tools::fileSizes(scans), evaluateMine, &owner);
    std::vector<FrameResult> results(all.size());
    for (std::size_t i = 0; i < all.size(); ++i) {
        tools::ByteReader in(all[i]);
        results[i].row = readRow(in);
        results[i].skipped = in.str(), results[i].heightNote = in.str();
    }
    if (ranks.size() > 1 && ranks.root()) {
        std::string counts;
        for (int r = 0; r < ranks.size(); ++r)
            counts += (r ? ", " : "") + std::to_string(std::count(owner.begin(), owner.end(), r));
        std::printf("%zu frames split over %d processes by their points: %s\n", frames.size(), ranks.size(), counts.c_str());
    }
    return results;
}

void writeText(const std::string& path, const std::string& text) { io::writeFileAtomic(path, text.data(), text.size()); }

struct Cli {
    std::string root, scan, labels, config, report, predDir;
    std::vector<std::string> sequences;
    int threads = 1;
    bool breakdown = false;
};

Setup makeSetup(const Cli& cli) {
    Setup setup;  // library defaults = config/kitti_hdl64.yaml
    if (!cli.config.empty()) {
        const auto cfg = mrpt::loadConfig(cli.config);
        setup.params = cfg.params, setup.autoHeight = cfg.distToGroundAuto;
    }
    setup.predDir = cli.predDir;
    setup.breakdown = cli.breakdown;
    if (cli.breakdown && !cli.report.empty()) setup.pictureDir = cli.report + "_breakdown";
    return setup;
}

int run(const Cli& cli, tools::Ranks& ranks) {
    Setup setup;
    std::vector<Frame> frames;
    std::string error;  // every rank finds the frames; any rank's failure stops all alike
    try {
        setup = makeSetup(cli);
        if (!cli.scan.empty()) {
            if (cli.labels.empty()) throw std::runtime_error("--scan needs --labels");
            frames.push_back({"scan", fs::path(cli.scan).stem().string(), cli.scan, cli.labels});
        } else {
            frames = findFrames(cli.root, cli.sequences);
        }
        if (ranks.root() && !cli.predDir.empty()) fs::create_directories(cli.predDir);
        if (ranks.root() && !setup.pictureDir.empty()) fs::create_directories(setup.pictureDir);
    } catch (const std::exception& e) {
        error = e.what();
    }
    if (const std::string first = ranks.firstError(error); !first.empty()) throw std::runtime_error(first);
    const auto results = evaluateOnRanks(frames, setup, cli.threads, ranks);
    if (!ranks.root()) return 0;

    std::vector<FrameRow> rows;
    std::size_t fallbacks = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        if (!results[i].heightNote.empty()) {
            ++fallbacks;
            std::fprintf(stderr, "%s/%s: distToGround: auto: %s\n", frames[i].sequence.c_str(), frames[i].name.c_str(),
                         results[i].heightNote.c_str());
        }
        if (results[i].skipped.empty()) {
            rows.push_back(results[i].row);
            continue;
        }
        std::fprintf(stderr, "skipped %s/%s: %s\n", frames[i].sequence.c_str(), frames[i].name.c_str(),
                     results[i].skipped.c_str());
    }
    std::printf("%zu frames evaluated, %zu skipped", rows.size(), frames.size() - rows.size());
    if (setup.autoHeight) std::printf(", %zu without a height estimate (fallback used)", fallbacks);
    std::printf("\n");
    if (rows.empty()) throw std::runtime_error("no frame could be scored (see the skipped frames above)");
    const auto seqs = summarise(rows);
    const std::string table = markdownTable(seqs);
    std::printf("%s\n%s", summaryText(seqs).c_str(), table.c_str());
    if (cli.breakdown) std::printf("\n%s", breakdownText(seqs).c_str());
    if (!cli.report.empty()) {
        const fs::path dir = fs::path(cli.report).parent_path();
        if (!dir.empty()) fs::create_directories(dir);
        writeText(cli.report + "_frames.csv", framesCsv(rows));
        writeText(cli.report + "_sequences.csv", sequencesCsv(seqs));
        writeText(cli.report + "_table.md", table);
        plotRanges(cli.report + "_range.png", seqs);
        std::printf("\nwrote %s_frames.csv, _sequences.csv, _table.md, _range.png\n", cli.report.c_str());
        if (cli.breakdown) {
            writeText(cli.report + "_breakdown.csv", breakdownCsv(rows, seqs));
            std::printf("wrote %s_breakdown.csv and a picture per frame in %s/\n", cli.report.c_str(),
                        setup.pictureDir.c_str());
        }
    }
    return 0;
}

std::vector<std::string> splitCommas(const std::string& s) {
    std::vector<std::string> out;
    std::istringstream in(s);
    for (std::string item; std::getline(in, item, ',');)
        if (!item.empty()) out.push_back(item);
    return out;
}

}  // namespace

int runEval(int argc, char** argv, tools::Ranks& ranks) {
    Cli cli;
    try {
        TCLAP::CmdLine cmd(
            "Score GSeg3D on SemanticKITTI (ROOT/sequences/NN/velodyne/*.bin + labels/*.label) under the Ground "
            "Segmentation Benchmark protocol; frames without a usable label file are reported and skipped. Without "
            "--config: the library defaults, which are exactly config/kitti_hdl64.yaml. Under mpirun or srun the frames are "
            "split over the processes by their points (--threads workers in each) and rank 0 writes the reports.",
            ' ', "0.1");
        TCLAP::UnlabeledValueArg<std::string> root("root", "SemanticKITTI root (sequences/NN/velodyne, labels)", false,
                                                   "", "ROOT", cmd);
        TCLAP::ValueArg<std::string> seqs("", "sequences", "comma-separated sequences (default all)", false, "",
                                          "00,08", cmd);
        TCLAP::ValueArg<std::string> cfg("c", "config", "YAML or INI parameter file (distToGround: auto is estimated "
                                         "per frame)", false, "", "FILE", cmd);
        TCLAP::ValueArg<std::string> report("", "report", "write PREFIX_frames.csv, _sequences.csv, _table.md, "
                                            "_range.png", false, "", "PREFIX", cmd);
        TCLAP::ValueArg<int> threads("", "threads", "worker threads (default: hardware threads)", false,
                                     int(std::max(1u, std::thread::hardware_concurrency())), "N", cmd);
        TCLAP::ValueArg<std::string> scan("", "scan", "score one scan instead of a tree", false, "", "X.bin", cmd);
        TCLAP::ValueArg<std::string> labels("", "labels", "label file of --scan", false, "", "X.label", cmd);
        TCLAP::ValueArg<std::string> preds("", "labels-out-dir", "write each frame's predictions (1 byte per point, "
                                           "1 ground) as DIR/SEQ_FRAME.pred", false, "", "DIR", cmd);
        TCLAP::SwitchArg breakdown("", "breakdown", "failure analysis: false ground by class, height above the local "
                                   "labelled ground and range, missed ground by class and range, per frame and "
                                   "sequence; with --report also PREFIX_breakdown.csv and a top-down PNG per frame "
                                   "(true / false / missed ground) in PREFIX_breakdown/", cmd, false);
        if (const int code = parseArgs(cmd, argc, argv); code >= 0) return code;
        cli = {root.getValue(), scan.getValue(), labels.getValue(), cfg.getValue(), report.getValue(),
               preds.getValue(), splitCommas(seqs.getValue()), threads.getValue(), breakdown.getValue()};
    } catch (const TCLAP::ArgException& e) {
        std::fprintf(stderr, "gseg eval: %s (%s)\n", e.error().c_str(), e.argId().c_str());
        return 2;
    }
    if (cli.root.empty() == cli.scan.empty() || cli.threads < 1 || cli.threads > 256) {
        std::fprintf(stderr, "gseg eval: give either ROOT or --scan X.bin --labels X.label, and --threads 1..256\n");
        return 2;
    }
    try {
        return run(cli, ranks);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "gseg eval: %s\n", e.what());
        return 1;
    }
}

}  // namespace gseg::app
