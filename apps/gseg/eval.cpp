// gseg eval: precision / recall on SemanticKITTI under the Ground Segmentation Benchmark protocol.
#include "cli.hpp"
#include "commands.hpp"
#include "progress.hpp"

#include <gseg/ground_segmenter.hpp>
#include <gseg/io/kitti.hpp>
#include <gseg/metrics.hpp>
#include <gseg/mrpt/config.hpp>

#include <mrpt/img/CImage.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;

namespace gseg::app {
namespace {

struct Frame {
    std::string sequence, name, scan, label;
};

struct FrameResult {
    std::size_t points = 0;
    FrameScore score;
    double ms = 0;
    std::string skipped;  // why, if skipped
};

struct SequenceSummary {
    std::string sequence;
    std::size_t frames = 0;
    MeanStd p, r, f1;                    // over frames, no range cut, with vegetation
    MeanStd pNoVeg, rNoVeg;              // over frames, without vegetation
    std::array<double, 10> rangeP{}, rangeR{};  // mean over frames at each range limit
    MeanStd rangePStats, rangeRStats, rangeF1Stats;  // over the ten limits (the paper's Table II)
    double ms = 0;                       // mean time per frame
};

std::vector<Frame> findFrames(const fs::path& root, const std::vector<std::string>& only) {
    const fs::path seqDir = root / "sequences";
    if (!fs::is_directory(seqDir)) throw std::runtime_error(root.string() + ": no sequences/ folder (SemanticKITTI layout expected)");
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
    if (frames.empty()) throw std::runtime_error(root.string() + ": no scans under sequences/*/velodyne/*.bin" +
                                                 (only.empty() ? "" : " for the sequences asked for"));
    return frames;
}

FrameResult evaluate(GroundSegmenter& seg, const Frame& f, const std::string& predDir) {
    FrameResult out;
    if (!fs::exists(f.label)) {
        out.skipped = "no label file " + f.label;
        return out;
    }
    try {
        const std::vector<float> pts = io::readKittiBin(f.scan);
        const PointCloudView cloud(pts.data(), pts.size() / 4, 16);
        const std::vector<std::uint32_t> labels = io::readKittiLabels(f.label, cloud.size());
        const Result r = seg.segment(cloud, false);
        out.points = cloud.size();
        out.ms = r.totalMs;
        out.score = scoreFrame(cloud, labels, r.labels);
        if (!predDir.empty())
            io::writeFileAtomic(predDir + "/" + f.sequence + "_" + f.name + ".pred", r.labels.data(), r.labels.size());
    } catch (const std::exception& e) {
        out.skipped = e.what();
    }
    return out;
}

std::vector<FrameResult> evaluateAll(const std::vector<Frame>& frames, const Params& params, int threads,
                                     const std::string& predDir) {
    std::vector<FrameResult> results(frames.size());
    std::atomic<std::size_t> next{0};
    Progress progress("evaluating", frames.size());
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t)
        pool.emplace_back([&] {
            GroundSegmenter seg(params);  // one per worker: results identical to a serial run
            for (std::size_t i; (i = next++) < frames.size();) {
                results[i] = evaluate(seg, frames[i], predDir);
                progress.step();
            }
        });
    for (auto& th : pool) th.join();
    return results;
}

std::vector<SequenceSummary> summarise(const std::vector<Frame>& frames, const std::vector<FrameResult>& results) {
    std::map<std::string, std::vector<std::size_t>> bySeq;
    for (std::size_t i = 0; i < frames.size(); ++i)
        if (results[i].skipped.empty()) bySeq[frames[i].sequence].push_back(i);
    std::vector<SequenceSummary> out;
    for (const auto& [seq, idx] : bySeq) {
        SequenceSummary s;
        s.sequence = seq;
        s.frames = idx.size();
        std::vector<double> p, r, f, pn, rn;
        double ms = 0;
        for (std::size_t i : idx) {
            const FrameScore& fs = results[i].score;
            p.push_back(fs.withVegetation.precision()), r.push_back(fs.withVegetation.recall());
            f.push_back(fs.withVegetation.f1());
            pn.push_back(fs.withoutVegetation.precision()), rn.push_back(fs.withoutVegetation.recall());
            ms += results[i].ms;
        }
        s.p = meanStd(p), s.r = meanStd(r), s.f1 = meanStd(f), s.pNoVeg = meanStd(pn), s.rNoVeg = meanStd(rn);
        s.ms = ms / double(idx.size());
        std::vector<double> limP, limR, limF;
        for (std::size_t k = 0; k < s.rangeP.size(); ++k) {
            std::vector<double> pk, rk;
            for (std::size_t i : idx) {
                pk.push_back(results[i].score.byRange[k].precision());
                rk.push_back(results[i].score.byRange[k].recall());
            }
            s.rangeP[k] = meanStd(pk).mean, s.rangeR[k] = meanStd(rk).mean;
            limP.push_back(s.rangeP[k]), limR.push_back(s.rangeR[k]);
            limF.push_back(2 * s.rangeP[k] * s.rangeR[k] / (s.rangeP[k] + s.rangeR[k]));
        }
        s.rangePStats = meanStd(limP), s.rangeRStats = meanStd(limR), s.rangeF1Stats = meanStd(limF);
        out.push_back(s);
    }
    return out;
}

std::string framesCsv(const std::vector<Frame>& frames, const std::vector<FrameResult>& results) {
    std::ostringstream o;
    o << "sequence,frame,points,TP,FP,FN,precision,recall,F1,precision_noveg,recall_noveg,ms\n";
    char line[512];
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const FrameResult& r = results[i];
        if (!r.skipped.empty()) continue;
        const Counts& c = r.score.withVegetation;
        std::snprintf(line, sizeof line, "%s,%s,%zu,%llu,%llu,%llu,%.4f,%.4f,%.4f,%.4f,%.4f,%.3f\n",
                      frames[i].sequence.c_str(), frames[i].name.c_str(), r.points, (unsigned long long)c.tp,
                      (unsigned long long)c.fp, (unsigned long long)c.fn, c.precision(), c.recall(), c.f1(),
                      r.score.withoutVegetation.precision(), r.score.withoutVegetation.recall(), r.ms);
        o << line;
    }
    return o.str();
}

std::string summaryCsv(const std::vector<SequenceSummary>& seqs) {
    std::ostringstream o;
    o << "sequence,frames,precision,recall,F1,precision_noveg,recall_noveg,range_precision_mean,range_precision_std,"
         "range_recall_mean,range_recall_std,ms";
    for (int d = 10; d <= 100; d += 10) o << ",P<" << d << "m,R<" << d << "m";
    o << "\n";
    char buf[256];
    for (const auto& s : seqs) {
        std::snprintf(buf, sizeof buf, "%s,%zu,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.3f", s.sequence.c_str(),
                      s.frames, s.p.mean, s.r.mean, s.f1.mean, s.pNoVeg.mean, s.rNoVeg.mean, s.rangePStats.mean,
                      s.rangePStats.stddev, s.rangeRStats.mean, s.rangeRStats.stddev, s.ms);
        o << buf;
        for (std::size_t k = 0; k < s.rangeP.size(); ++k) {
            std::snprintf(buf, sizeof buf, ",%.4f,%.4f", s.rangeP[k], s.rangeR[k]);
            o << buf;
        }
        o << "\n";
    }
    return o.str();
}

// The paper's Table II: per sequence Pr. / Rc. / F1 as mean +- std over the range limits 10..100 m.
std::string markdownTable(const std::vector<SequenceSummary>& seqs) {
    std::ostringstream o;
    char buf[256];
    o << "| Seq. | frames | Pr. (%) | Rc. (%) | F1 (%) | Pr. no range cut | Rc. no range cut | ms/scan |\n"
      << "|---|---|---|---|---|---|---|---|\n";
    std::vector<double> p, r, f, p0, r0, ms;
    for (const auto& s : seqs) {
        std::snprintf(buf, sizeof buf, "| %s | %zu | %.2f ± %.2f | %.2f ± %.2f | %.2f ± %.2f | %.2f | %.2f | %.1f |\n",
                      s.sequence.c_str(), s.frames, s.rangePStats.mean, s.rangePStats.stddev, s.rangeRStats.mean,
                      s.rangeRStats.stddev, s.rangeF1Stats.mean, s.rangeF1Stats.stddev, s.p.mean, s.r.mean, s.ms);
        o << buf;
        p.push_back(s.rangePStats.mean), r.push_back(s.rangeRStats.mean), f.push_back(s.rangeF1Stats.mean);
        p0.push_back(s.p.mean), r0.push_back(s.r.mean), ms.push_back(s.ms);
    }
    std::snprintf(buf, sizeof buf, "| **mean** | | **%.2f** | **%.2f** | **%.2f** | %.2f | %.2f | %.1f |\n",
                  meanStd(p).mean, meanStd(r).mean, meanStd(f).mean, meanStd(p0).mean, meanStd(r0).mean,
                  meanStd(ms).mean);
    o << buf;
    return o.str();
}

void plotRanges(const std::string& path, const std::vector<SequenceSummary>& seqs) {
    const int w = 900, h = 560, left = 70, right = 200, top = 40, bottom = 60;
    double lo = 100;
    for (const auto& s : seqs)
        for (std::size_t k = 0; k < 10; ++k)
            for (double v : {s.rangeP[k], s.rangeR[k]})
                if (!std::isnan(v)) lo = std::min(lo, v);
    lo = std::max(0.0, std::floor(lo / 5.0) * 5.0 - 5.0);
    auto X = [&](double d) { return left + int((d - 10) / 90.0 * (w - left - right)); };
    auto Y = [&](double v) { return top + int((100.0 - v) / (100.0 - lo) * (h - top - bottom)); };
    ::mrpt::img::CImage img(w, h, ::mrpt::img::CH_RGB);
    img.filledRectangle(0, 0, w - 1, h - 1, ::mrpt::img::TColor(255, 255, 255));
    const ::mrpt::img::TColor grey(200, 200, 200), black(0, 0, 0);
    for (double v = lo; v <= 100.0 + 1e-9; v += 5) {
        img.line(left, Y(v), w - right, Y(v), grey);
        img.textOut(left - 40, Y(v) - 6, std::to_string(int(v)), black);
    }
    for (int d = 10; d <= 100; d += 10) {
        img.line(X(d), top, X(d), h - bottom, grey);
        img.textOut(X(d) - 8, h - bottom + 8, std::to_string(d), black);
    }
    img.textOut(left, 12, "precision (thick line) and recall (thin line, squares) [%] within each range limit", black);
    img.textOut((w - right) / 2, h - 24, "range limit [m]", black);
    const ::mrpt::img::TColor palette[] = {{31, 119, 180}, {214, 39, 40},  {44, 160, 44},  {148, 103, 189},
                                           {255, 127, 14}, {140, 86, 75},  {227, 119, 194}, {23, 190, 207}};
    for (std::size_t s = 0; s < seqs.size(); ++s) {
        const auto colour = palette[s % 8];
        for (std::size_t k = 0; k + 1 < 10; ++k) {
            const double d0 = 10.0 * double(k + 1), d1 = d0 + 10;
            if (!std::isnan(seqs[s].rangeP[k]) && !std::isnan(seqs[s].rangeP[k + 1]))
                img.line(X(d0), Y(seqs[s].rangeP[k]), X(d1), Y(seqs[s].rangeP[k + 1]), colour, 2);
            if (!std::isnan(seqs[s].rangeR[k]) && !std::isnan(seqs[s].rangeR[k + 1]))
                img.line(X(d0), Y(seqs[s].rangeR[k]), X(d1), Y(seqs[s].rangeR[k + 1]), colour, 1);
        }
        for (std::size_t k = 0; k < 10; ++k)  // recall points: squares
            if (!std::isnan(seqs[s].rangeR[k]))
                img.filledRectangle(X(10.0 * double(k + 1)) - 3, Y(seqs[s].rangeR[k]) - 3, X(10.0 * double(k + 1)) + 3,
                                    Y(seqs[s].rangeR[k]) + 3, colour);
        const int ly = top + 20 * int(s);
        img.line(w - right + 20, ly + 6, w - right + 50, ly + 6, colour, 2);
        img.textOut(w - right + 58, ly, "seq " + seqs[s].sequence, black);
    }
    const std::string tmp = path + ".tmp" + std::to_string(::getpid()) + ".png";
    if (!img.saveToFile(tmp)) throw std::runtime_error(path + ": cannot write the PNG");
    fs::rename(tmp, path);
}

void writeText(const std::string& path, const std::string& text) { io::writeFileAtomic(path, text.data(), text.size()); }

struct Cli {
    std::string root, scan, labels, config, report, predDir;
    std::vector<std::string> sequences;
    int threads = 1;
};

int run(const Cli& cli) {
    Params params;
    params.maxGroundHeightDeviation = 0.1;  // the paper's KITTI setup (config/kitti_hdl64.yaml)
    if (!cli.config.empty()) {
        const auto cfg = mrpt::loadConfig(cli.config);
        if (cfg.distToGroundAuto) throw std::runtime_error(cli.config + ": eval needs a numeric distToGround");
        params = cfg.params;
    }
    std::vector<Frame> frames;
    if (!cli.scan.empty()) {
        if (cli.labels.empty()) throw std::runtime_error("--scan needs --labels");
        frames.push_back({"scan", fs::path(cli.scan).stem().string(), cli.scan, cli.labels});
    } else {
        frames = findFrames(cli.root, cli.sequences);
    }
    if (!cli.predDir.empty()) fs::create_directories(cli.predDir);
    const auto results = evaluateAll(frames, params, cli.threads, cli.predDir);

    std::size_t skipped = 0;
    for (std::size_t i = 0; i < frames.size(); ++i)
        if (!results[i].skipped.empty()) {
            ++skipped;
            std::fprintf(stderr, "skipped %s/%s: %s\n", frames[i].sequence.c_str(), frames[i].name.c_str(),
                         results[i].skipped.c_str());
        }
    const auto seqs = summarise(frames, results);
    std::printf("%zu frames evaluated, %zu skipped\n", frames.size() - skipped, skipped);
    for (const auto& s : seqs)
        std::printf("sequence %s: %zu frames, P %.2f R %.2f F1 %.2f (no range cut; without vegetation P %.2f R %.2f); "
                    "range-limited P %.2f ± %.2f R %.2f ± %.2f; %.1f ms/scan\n",
                    s.sequence.c_str(), s.frames, s.p.mean, s.r.mean, s.f1.mean, s.pNoVeg.mean, s.rNoVeg.mean,
                    s.rangePStats.mean, s.rangePStats.stddev, s.rangeRStats.mean, s.rangeRStats.stddev, s.ms);
    const std::string table = markdownTable(seqs);
    std::printf("\n%s", table.c_str());
    if (!cli.report.empty()) {
        const fs::path dir = fs::path(cli.report).parent_path();
        if (!dir.empty()) fs::create_directories(dir);
        writeText(cli.report + "_frames.csv", framesCsv(frames, results));
        writeText(cli.report + "_sequences.csv", summaryCsv(seqs));
        writeText(cli.report + "_table.md", table);
        if (!seqs.empty()) plotRanges(cli.report + "_range.png", seqs);
        std::printf("\nwrote %s_frames.csv, _sequences.csv, _table.md, _range.png\n", cli.report.c_str());
    }
    return seqs.empty() ? 1 : 0;
}

std::vector<std::string> splitCommas(const std::string& s) {
    std::vector<std::string> out;
    std::istringstream in(s);
    for (std::string item; std::getline(in, item, ',');)
        if (!item.empty()) out.push_back(item);
    return out;
}

}  // namespace

int runEval(int argc, char** argv) {
    Cli cli;
    try {
        TCLAP::CmdLine cmd("Score GSeg3D on SemanticKITTI under the Ground Segmentation Benchmark protocol. Without "
                           "--config: the paper's KITTI setup (config/kitti_hdl64.yaml).", ' ', "0.1");
        TCLAP::UnlabeledValueArg<std::string> root("root", "SemanticKITTI root (sequences/NN/velodyne, labels)", false,
                                                   "", "ROOT", cmd);
        TCLAP::ValueArg<std::string> seqs("", "sequences", "comma-separated sequences (default all)", false, "", "00,08", cmd);
        TCLAP::ValueArg<std::string> cfg("c", "config", "YAML or INI parameter file", false, "", "FILE", cmd);
        TCLAP::ValueArg<std::string> report("", "report", "write PREFIX_frames.csv, _sequences.csv, _table.md, _range.png",
                                            false, "", "PREFIX", cmd);
        TCLAP::ValueArg<int> threads("", "threads", "worker threads (default: hardware threads)", false,
                                     int(std::max(1u, std::thread::hardware_concurrency())), "N", cmd);
        TCLAP::ValueArg<std::string> scan("", "scan", "score one scan instead of a tree", false, "", "X.bin", cmd);
        TCLAP::ValueArg<std::string> labels("", "labels", "label file of --scan", false, "", "X.label", cmd);
        TCLAP::ValueArg<std::string> preds("", "labels-out-dir", "write each frame's predictions (1 byte per point) "
                                           "as DIR/SEQ_FRAME.pred", false, "", "DIR", cmd);
        if (const int code = parseArgs(cmd, argc, argv); code >= 0) return code;
        cli = {root.getValue(), scan.getValue(), labels.getValue(), cfg.getValue(), report.getValue(),
               preds.getValue(), splitCommas(seqs.getValue()), threads.getValue()};
    } catch (const TCLAP::ArgException& e) {
        std::fprintf(stderr, "gseg eval: %s (%s)\n", e.error().c_str(), e.argId().c_str());
        return 2;
    }
    if (cli.root.empty() == cli.scan.empty() || cli.threads < 1 || cli.threads > 256) {
        std::fprintf(stderr, "gseg eval: give either ROOT or --scan X.bin --labels X.label, and --threads 1..256\n");
        return 2;
    }
    try {
        return run(cli);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "gseg eval: %s\n", e.what());
        return 1;
    }
}

}  // namespace gseg::app
