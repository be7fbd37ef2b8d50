// gseg eval: precision / recall on SemanticKITTI under the Ground Segmentation Benchmark protocol.
#include "commands.hpp"
#include "common/cli.hpp"
#include "eval_plot.hpp"
#include "eval_report.hpp"

#include <gseg/eval/kitti_rings.hpp>
#include <gseg/eval/metrics.hpp>
#include <gseg/eval/kitti_sequence.hpp>
#include <gseg/ground_segmenter.hpp>
#include <gseg/io/atomic_file.hpp>
#include <gseg/io/kitti.hpp>
#include <gseg/progress.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/segment_scan.hpp>
#include <gseg/ordered_pipeline.hpp>
#include <gseg/map/poses.hpp>
#include <gseg/terrain_model.hpp>

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
    SensorHeightOptions sensorHeight;  ///< how (the config's sensorHeight:)
    std::string predDir;      ///< write each frame's predictions here ("" = not)
    bool breakdown = false;   ///< count where the errors are
    std::string pictureDir;   ///< breakdown picture per frame here ("" = none)
    unsigned ringStep = 1;    ///< score every ringStep-th laser ring only (a sparser sensor)
    unsigned pointStep = 1;   ///< ... and every pointStep-th point along the rings
    map::TraversabilityOptions traversability;  ///< the drive context's terrain model options (traversability:)
    std::string heightSummary;  ///< the sensor height and where it came from (the summary's line)
};

/// The frames found, and one line per sequence that gave none although asked for (or could not be
/// listed): such a sequence is named, the others are evaluated.
struct FrameList {
    std::vector<Frame> frames;
    std::vector<std::string> problems;
};

/// The scans of one sequence folder (gseg::eval::listKittiScans); throws std::runtime_error naming
/// the folder where it cannot be listed (a symbolic link loop, no permission).
std::vector<Frame> sequenceFrames(const fs::path& seq) {
    std::vector<Frame> frames;
    for (const eval::KittiScan& s : eval::listKittiScans(seq.string()))
        frames.push_back({seq.filename().string(), s.name, s.scan, s.label});
    return frames;
}

FrameList findFrames(const fs::path& root, const std::vector<std::string>& only) {
    const fs::path seqDir = root / "sequences";
    if (!fs::is_directory(seqDir))
        throw std::runtime_error(root.string() + ": no sequences/ folder (SemanticKITTI layout expected)");
    FrameList out;
    std::vector<std::string> names = only;  // the sequences asked for, or every folder
    if (names.empty()) {
        try {
            for (const auto& seq : fs::directory_iterator(seqDir)) names.push_back(seq.path().filename().string());
        } catch (const fs::filesystem_error& e) {
            throw std::runtime_error(seqDir.string() + ": cannot list the sequences (" + e.code().message() + ")");
        }
        std::sort(names.begin(), names.end());
    }
    for (const std::string& name : names) {
        const fs::path seq = seqDir / name;
        std::error_code ec;
        if (!fs::is_directory(seq / "velodyne", ec)) {
            if (!only.empty() || fs::exists(seq / "velodyne", ec) || ec)
                out.problems.push_back("sequence " + name + ": no folder " + (seq / "velodyne").string() +
                                       (ec ? " (" + ec.message() + ")" : ""));
            continue;
        }
        try {
            std::vector<Frame> frames = sequenceFrames(seq);
            if (frames.empty()) out.problems.push_back("sequence " + name + ": no scans (*.bin) in " + (seq / "velodyne").string());
            out.frames.insert(out.frames.end(), frames.begin(), frames.end());
        } catch (const std::runtime_error& e) {
            out.problems.push_back("sequence " + name + ": " + e.what());
        }
    }
    std::sort(out.frames.begin(), out.frames.end(), [](const Frame& a, const Frame& b) {
        return std::tie(a.sequence, a.name) < std::tie(b.sequence, b.name);
    });
    if (out.frames.empty()) {
        std::string why;
        for (const std::string& p : out.problems) why += "; " + p;
        throw std::runtime_error(root.string() + ": no scans under sequences/*/velodyne/*.bin" +
                                 (only.empty() ? "" : " for the sequences asked for") + why);
    }
    return out;
}

/// A worker's segmenter: the one height policy (gseg::mrpt::ScanSegmenter; with `distToGround:
/// auto` each frame gets its own estimate, or the configured height where it gives none, so any
/// thread count agrees). `note` says when the fallback was used.
struct FrameSegmenter {
    explicit FrameSegmenter(const Setup& setup)
        : seg(::gseg::mrpt::LoadedConfig{setup.params, setup.autoHeight, setup.sensorHeight, {}, {}}) {}
    Result segment(const PointCloudView& cloud, std::string& note) {
        if (cloud.empty()) throw std::invalid_argument("gseg: the point cloud is empty");
        ::gseg::mrpt::ScanSegmentation s = seg.segment(cloud, false, ::gseg::mrpt::HeightCheck::Never);
        if (s.heightFallback()) note = s.height.describe();
        return std::move(s.result);
    }
    ::gseg::mrpt::ScanSegmenter seg;
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
        std::vector<float> pts = io::readKittiBin(f.scan);
        std::vector<std::uint32_t> labels = io::readKittiLabels(f.label, pts.size() / 4);
        eval::thinKittiScan(pts, labels, setup.ringStep, setup.pointStep);  // (1, 1: as read)
        const PointCloudView cloud(pts.data(), pts.size() / 4, 4 * sizeof(float));
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

/// The frames `todo` (indices into `frames`) are handed out one at a time to `threads` workers
/// (gseg::runOrdered, the one worker pool), each with its own segmenter; the segmenter is
/// deterministic, so the results equal a serial run's. Progress counts the frames scored, in frame
/// order, and names the skipped ones apart.
std::vector<FrameResult> evaluateAll(const std::vector<Frame>& frames, const std::vector<std::size_t>& todo,
                                     const Setup& setup, int threads) {
    std::vector<FrameResult> results(frames.size());
    std::size_t next = 0, scored = 0, skipped = 0;
    Progress progress(tools::progressOut(), "gseg eval", "frames");
    std::vector<FrameSegmenter> segs;
    for (int t = 0; t < std::max(1, threads); ++t) segs.emplace_back(setup);
    std::vector<char> warm(segs.size(), 0);  // a worker's first scored frame is segmented once untimed first
    auto produce = [&](std::size_t& i) { return next < todo.size() ? (i = todo[next++], true) : false; };
    auto work = [&](unsigned w, std::size_t& i) {
        FrameResult r = evaluate(segs[w], frames[i], setup, !warm[w]);
        if (r.skipped.empty()) warm[w] = 1;
        return r;
    };
    auto consume = [&](std::size_t k, FrameResult& r) {
        const std::size_t i = todo[k];
        if (r.skipped.empty()) ++scored;
        else ++skipped;
        if (r.skipped.empty())
            tools::detail("%s/%s: %zu points, precision %.2f %%, recall %.2f %%, F1 %.2f %%, %.1f ms\n",
                          frames[i].sequence.c_str(), frames[i].name.c_str(), r.row.points,
                          r.row.score.withVegetation.precision(), r.row.score.withVegetation.recall(),
                          r.row.score.withVegetation.f1(), r.row.ms);
        progress.update(scored, double(scored + skipped) / double(todo.size()), skipped ? std::to_string(skipped) + " skipped" : "");
        results[i] = std::move(r);
    };
    runOrdered<std::size_t, FrameResult>(produce, work, consume,
                                         {unsigned(std::max(1, threads)), 2 * std::size_t(std::max(1, threads)) + 2});
    progress.finish(scored, skipped ? std::to_string(skipped) + " skipped" : "");
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
            io::ByteWriter out;
            writeRow(out, results[i].row);
            bytes.push_back(out.str(results[i].skipped).str(results[i].heightNote).bytes());
        }
        return bytes;
    };
    const std::vector<std::string> all = tools::shareItems(ranks, tools::fileSizes(scans), evaluateMine, &owner);
    std::vector<FrameResult> results(all.size());
    for (std::size_t i = 0; i < all.size(); ++i) {
        io::ByteReader in(all[i]);
        results[i].row = readRow(in);
        results[i].skipped = in.str(), results[i].heightNote = in.str();
    }
    if (ranks.size() > 1 && ranks.root()) {
        std::string counts;
        for (int r = 0; r < ranks.size(); ++r)
            counts += (r ? ", " : "") + std::to_string(std::count(owner.begin(), owner.end(), r));
        tools::say("%zu frames split over %d processes by their points: %s\n", frames.size(), ranks.size(), counts.c_str());
    }
    return results;
}

/// Drive context (#31): the frames of a sequence that is a drive (poses.txt and calib.txt with
/// Tr beside velodyne/) scored again with the labels TerrainModel::relabel() gives them, the model
/// built from every frame of the drive (the offline form: pass 1 segments every frame and adds its
/// samples in frame order, pass 2 segments each frame again and relabels it). The same frames,
/// segmentation and thinning as the scores alone.
struct DriveContext {
    std::string sequence;
    std::vector<FrameRow> alone, withContext;
    std::size_t relabelled = 0;       ///< points relabelled (both ways), all frames
    std::size_t anchors = 0, grown = 0;  ///< cells of the model
    std::string skipped;               ///< why the sequence has no context figures ("" if it has)
};

/// The frames' world poses (Tr^-1 P_k Tr) by frame number, or throws naming the file.
std::vector<Eigen::Isometry3d> drivePoses(const fs::path& seq) {
    return map::kittiToVelodyneFrame(map::readKittiPoses((seq / "poses.txt").string()),
                                     map::readKittiCalibTr((seq / "calib.txt").string()));
}

/// One frame segmented, in the world frame: its points (x, y, z), labels and segmentation.
struct WorldFrame {
    std::vector<float> xyz;
    std::vector<std::uint32_t> truth;
    std::vector<std::uint8_t> labels;
    std::vector<float> sensorXyzi;  ///< as read (and thinned): what scoreFrame() scores
};

WorldFrame segmentInWorld(FrameSegmenter& seg, const Frame& f, const Setup& setup, const Eigen::Isometry3d& pose) {
    WorldFrame w;
    w.sensorXyzi = io::readKittiBin(f.scan);
    w.truth = io::readKittiLabels(f.label, w.sensorXyzi.size() / 4);
    eval::thinKittiScan(w.sensorXyzi, w.truth, setup.ringStep, setup.pointStep);
    const PointCloudView cloud(w.sensorXyzi.data(), w.sensorXyzi.size() / 4, 4 * sizeof(float));
    std::string note;
    w.labels = seg.segment(cloud, note).labels;
    w.xyz.resize(3 * cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d p = pose * Eigen::Vector3d(cloud.x(i), cloud.y(i), cloud.z(i));
        w.xyz[3 * i] = float(p.x()), w.xyz[3 * i + 1] = float(p.y()), w.xyz[3 * i + 2] = float(p.z());
    }
    return w;
}

DriveContext driveContext(const fs::path& seq, const std::vector<const Frame*>& frames, const std::vector<FrameRow>& alone,
                          const Setup& setup, const map::TraversabilityOptions& traversability) {
    DriveContext out;
    out.sequence = frames.front()->sequence;
    std::vector<Eigen::Isometry3d> poses;
    try {
        poses = drivePoses(seq);
    } catch (const std::exception& e) {
        out.skipped = e.what();
        return out;
    }
    std::vector<std::size_t> index;
    for (const Frame* f : frames) {
        std::size_t k = 0;
        try {
            k = std::stoul(f->name);
        } catch (const std::exception&) {
            k = poses.size();
        }
        if (k >= poses.size()) {
            out.skipped = "frame " + f->name + " has no line in " + (seq / "poses.txt").string();
            return out;
        }
        index.push_back(k);
    }
    FrameSegmenter seg(setup);
    gseg::TerrainModel model(traversability.terrainOptions());
    auto samplesOf = [&](const WorldFrame& w, const Eigen::Vector3d& origin) {
        std::vector<float> ground, other;
        for (std::size_t i = 0; i < w.labels.size(); ++i)
            (w.labels[i] ? ground : other).insert((w.labels[i] ? ground : other).end(), &w.xyz[3 * i], &w.xyz[3 * i] + 3);
        return gseg::terrainSamples(PointCloudView(ground.data(), ground.size() / 3), PointCloudView(other.data(), other.size() / 3),
                                    traversability.resolution, traversability.maxRange, origin);
    };
    for (std::size_t j = 0; j < frames.size(); ++j) {
        const Eigen::Isometry3d& pose = poses[index[j]];
        model.add(samplesOf(segmentInWorld(seg, *frames[j], setup, pose), pose.translation()));
    }
    model.build();
    out.anchors = model.anchors(), out.grown = model.grown();
    for (std::size_t j = 0; j < frames.size(); ++j) {
        WorldFrame w = segmentInWorld(seg, *frames[j], setup, poses[index[j]]);
        out.relabelled += model.relabel(PointCloudView(w.xyz.data(), w.xyz.size() / 3), w.labels);
        FrameRow row = alone[j];
        row.score = scoreFrame(PointCloudView(w.sensorXyzi.data(), w.sensorXyzi.size() / 4, 4 * sizeof(float)), w.truth, w.labels);
        out.alone.push_back(alone[j]);
        out.withContext.push_back(row);
    }
    return out;
}

/// Mean precision, recall and F1 [%] over frames (with vegetation, the benchmark's protocol).
std::string meanScores(const std::vector<FrameRow>& rows) {
    double p = 0, r = 0, f = 0;
    for (const FrameRow& row : rows)
        p += row.score.withVegetation.precision(), r += row.score.withVegetation.recall(), f += row.score.withVegetation.f1();
    const double n = double(std::max<std::size_t>(1, rows.size()));
    char buf[96];
    std::snprintf(buf, sizeof buf, "%6.2f %6.2f %6.2f", p / n, r / n, f / n);
    return buf;
}

/// The drive-context table: each drive alone and with its context, and the mean over their frames.
std::string driveContextText(const std::vector<DriveContext>& drives) {
    std::string out = "\ndrive context (the terrain model of each drive's frames, #31; mean over frames, P / R / F1 %):\n";
    out += "sequence  frames   alone: P      R      F1  | with the drive: P    R      F1  | points relabelled, model cells (anchors + grown)\n";
    std::vector<FrameRow> allAlone, allWith;
    char line[256];
    for (const DriveContext& d : drives) {
        if (!d.skipped.empty()) {
            out += d.sequence + ": no drive context: " + d.skipped + "\n";
            continue;
        }
        std::snprintf(line, sizeof line, "%-8s %7zu  %s  |   %s  | %zu, %zu + %zu\n", d.sequence.c_str(), d.alone.size(),
                      meanScores(d.alone).c_str(), meanScores(d.withContext).c_str(), d.relabelled, d.anchors, d.grown);
        out += line;
        allAlone.insert(allAlone.end(), d.alone.begin(), d.alone.end());
        allWith.insert(allWith.end(), d.withContext.begin(), d.withContext.end());
    }
    if (!allAlone.empty()) {
        std::snprintf(line, sizeof line, "%-8s %7zu  %s  |   %s\n", "all", allAlone.size(), meanScores(allAlone).c_str(),
                      meanScores(allWith).c_str());
        out += line;
    }
    return out;
}

struct Cli {
    std::string root, scan, labels, config, report, predDir;
    std::vector<std::string> sequences;
    int threads = 1;
    bool breakdown = false;
    bool overwrite = false;  ///< -w
    int ringStep = 1, pointStep = 1;
    bool driveContext = true;  ///< score drives (poses.txt + calib.txt) with their terrain model too
};

Setup makeSetup(const Cli& cli, bool root) {
    Setup setup;
    mrpt::LoadedConfig cfg;
    try {
        cfg = mrpt::loadConfigOrDefault(cli.config);  // the one default without -c: distToGround auto
    } catch (const std::invalid_argument& e) {  // a bad file is bad input, not bad usage
        throw std::runtime_error(e.what());
    }
    if (root) tools::noteWarnings("gseg eval", cfg.warnings);  // once, not once per rank
    setup.params = cfg.params, setup.autoHeight = cfg.distToGroundAuto, setup.sensorHeight = cfg.sensorHeight;
    setup.traversability = cfg.traversability;
    tools::detail("parameters (%s):\n%s", cli.config.empty() ? "the default" : cli.config.c_str(),
                  mrpt::toYaml(cfg).c_str());
    setup.heightSummary = mrpt::heightSummary(cfg, cli.config);
    setup.predDir = cli.predDir;
    setup.breakdown = cli.breakdown;
    setup.ringStep = unsigned(cli.ringStep), setup.pointStep = unsigned(cli.pointStep);
    if (cli.breakdown && !cli.report.empty()) setup.pictureDir = cli.report + "_breakdown";
    return setup;
}

/// Every file the run writes, checked before any work (exit 2): not an input, not there already
/// unless -w, in a folder that exists or can be made and takes a new file.
void checkEvalOutputs(const Cli& cli, const Setup& setup, const std::vector<Frame>& frames) {
    std::vector<io::NamedPath> inputs = {{"--config", cli.config}}, outputs;
    for (const Frame& f : frames) inputs.push_back({"scan", f.scan}), inputs.push_back({"labels", f.label});
    if (!cli.report.empty()) {
        for (const char* suffix : {"_frames.csv", "_sequences.csv", "_table.md", "_range.png"})
            outputs.push_back({"--report", cli.report + suffix});
        if (cli.breakdown) outputs.push_back({"--report", cli.report + "_breakdown.csv"});
    }
    for (const Frame& f : frames) {
        if (!setup.pictureDir.empty())
            outputs.push_back({"--report", setup.pictureDir + "/" + f.sequence + "_" + f.name + ".png"});
        if (!setup.predDir.empty()) outputs.push_back({"--labels-out-dir", setup.predDir + "/" + f.sequence + "_" + f.name + ".pred"});
    }
    io::checkOutputs(inputs, outputs, {cli.overwrite, true});
}

int run(const Cli& cli, tools::Ranks& ranks) {
    Setup setup;
    std::vector<Frame> frames;
    std::vector<std::string> sequenceProblems;  // sequences asked for that gave no frame: named, exit 3
    std::string error;  // every rank finds the frames; any rank's failure stops all alike
    int code = tools::kBadInput;
    try {
        setup = makeSetup(cli, ranks.root());
        if (!cli.scan.empty()) {
            if (cli.labels.empty()) throw std::invalid_argument("--scan needs --labels");
            frames.push_back({"scan", fs::path(cli.scan).stem().string(), cli.scan, cli.labels});
        } else {
            FrameList found = findFrames(cli.root, cli.sequences);
            frames = std::move(found.frames), sequenceProblems = std::move(found.problems);
        }
        if (ranks.root()) checkEvalOutputs(cli, setup, frames);  // rank 0 writes the reports
        if (ranks.root() && !cli.predDir.empty()) fs::create_directories(cli.predDir);
        if (ranks.root() && !setup.pictureDir.empty()) fs::create_directories(setup.pictureDir);
    } catch (...) {  // std::invalid_argument: bad usage (an output that cannot be written)
        error = tools::currentError(), code = tools::exitCodeOf(tools::InvalidArgument::BadUsage);
    }
    if (const std::string first = ranks.firstError(error); !first.empty()) {
        std::fprintf(stderr, "gseg eval: %s\n", first.c_str());
        return code;
    }
    if (ranks.root())
        for (const std::string& p : sequenceProblems) std::fprintf(stderr, "gseg eval: %s\n", p.c_str());
    const auto results = evaluateOnRanks(frames, setup, cli.threads, ranks);
    if (!ranks.root()) return 0;

    std::vector<FrameRow> rows;
    std::size_t fallbacks = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        if (!results[i].heightNote.empty()) {
            ++fallbacks;
            tools::note("%s/%s: distToGround: auto: %s\n", frames[i].sequence.c_str(), frames[i].name.c_str(),
                         results[i].heightNote.c_str());
        }
        if (results[i].skipped.empty()) {
            rows.push_back(results[i].row);
            continue;
        }
        std::fprintf(stderr, "skipped %s/%s: %s\n", frames[i].sequence.c_str(), frames[i].name.c_str(),
                     results[i].skipped.c_str());
    }
    tools::say("%zu frames evaluated, %zu skipped", rows.size(), frames.size() - rows.size());
    if (cli.ringStep > 1 || cli.pointStep > 1)
        tools::say(" (thinned: --ring-step %d, --point-step %d)", cli.ringStep, cli.pointStep);
    if (!sequenceProblems.empty()) tools::say(", %zu sequence(s) without frames (named above)", sequenceProblems.size());
    if (setup.autoHeight) tools::say(", %zu without a height estimate (fallback used)", fallbacks);
    tools::say("\n%s\n", setup.heightSummary.c_str());
    if (rows.empty()) throw std::runtime_error("no frame could be scored (see the skipped frames above)");
    const auto seqs = summarise(rows);
    const std::string table = markdownTable(seqs);
    tools::say("%s\n%s", summaryText(seqs).c_str(), table.c_str());
    if (cli.breakdown) tools::say("\n%s", breakdownText(seqs).c_str());
    if (cli.driveContext && cli.scan.empty()) {
        std::vector<DriveContext> drives;
        for (std::size_t i = 0; i < frames.size();) {  // frames are sorted by sequence
            std::vector<const Frame*> seqFrames;
            std::vector<FrameRow> alone;
            const std::string& name = frames[i].sequence;
            for (; i < frames.size() && frames[i].sequence == name; ++i)
                if (results[i].skipped.empty()) seqFrames.push_back(&frames[i]), alone.push_back(results[i].row);
            const fs::path seq = fs::path(cli.root) / "sequences" / name;
            if (seqFrames.size() < 2 || !fs::exists(seq / "poses.txt")) continue;  // a drive: poses and two frames or more
            drives.push_back(driveContext(seq, seqFrames, alone, setup, setup.traversability));
        }
        if (!drives.empty()) tools::say("%s", driveContextText(drives).c_str());
    }
    if (!cli.report.empty()) {
        const fs::path dir = fs::path(cli.report).parent_path();
        if (!dir.empty()) fs::create_directories(dir);
        // The report's files belong together: all of this run or all of the previous one.
        std::vector<std::pair<std::string, std::string>> files = {{cli.report + "_frames.csv", framesCsv(rows)},
                                                                  {cli.report + "_sequences.csv", sequencesCsv(seqs)},
                                                                  {cli.report + "_table.md", table},
                                                                  {cli.report + "_range.png", rangePlotPng(seqs)}};
        if (cli.breakdown) files.emplace_back(cli.report + "_breakdown.csv", breakdownCsv(rows, seqs));
        std::vector<std::string> paths;
        for (const auto& f : files) paths.push_back(f.first);
        io::AtomicFileSet set(paths);
        for (std::size_t i = 0; i < files.size(); ++i) set[i].write(files[i].second.data(), files[i].second.size());
        set.commit();
        tools::say("\nwrote %s_frames.csv, _sequences.csv, _table.md, _range.png\n", cli.report.c_str());
        if (cli.breakdown)
            tools::say("wrote %s_breakdown.csv and a picture per frame in %s/\n", cli.report.c_str(), setup.pictureDir.c_str());
    }
    return sequenceProblems.empty() ? int(tools::kDone) : int(tools::kPartlyDone);
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
    tools::CommandLine line(
        "gseg eval",
        "Score GSeg3D on SemanticKITTI (ROOT/sequences/NN/velodyne/*.bin + labels/*.label) under the Ground "
        "Segmentation Benchmark protocol; frames without a usable label file are reported and skipped; a sequence that gives no frame (none asked "
        "for, an empty or unreadable velodyne/ folder) is named and the others are evaluated (exit 3). Without "
        "--config: the library defaults with distToGround: auto (the sensor height estimated per frame); "
        "-c config/kitti_hdl64.yaml fixes KITTI's 1.723 m. The root may also be given "
        "without -i (old form: gseg eval ROOT). Under mpirun or srun the frames are split over the processes by their "
        "points (--threads workers in each) and rank 0 writes the reports.",
        true, ranks.root());
    line.addMpiTimeout();
    TCLAP::CmdLine& cmd = line.cmd();
    TCLAP::ValueArg<std::string> input("i", "input", "SemanticKITTI root (sequences/NN/velodyne, labels)", false, "",
                                       "ROOT", cmd);
    TCLAP::UnlabeledValueArg<std::string> root("root", "the root, old form (same as -i)", false, "", "ROOT", cmd);
    TCLAP::ValueArg<std::string> seqs("", "sequences", "comma-separated sequences (default all)", false, "", "00,08",
                                      cmd);
    TCLAP::ValueArg<std::string> cfg("c", "config", "YAML or INI parameter file (distToGround: auto is estimated "
                                     "per frame)", false, "", "FILE", cmd);
    TCLAP::ValueArg<std::string> report("", "report", "write PREFIX_frames.csv, _sequences.csv, _table.md, "
                                        "_range.png (the folder is made if missing)", false, "", "PREFIX", cmd);
    TCLAP::ValueArg<int> threads("", "threads", "worker threads (default: the cores this process may use)",
                                 false, int(gseg::usableCores()), "N", cmd);
    TCLAP::ValueArg<std::string> scan("", "scan", "score one scan instead of a tree", false, "", "X.bin", cmd);
    TCLAP::ValueArg<std::string> labels("", "labels", "label file of --scan", false, "", "X.label", cmd);
    TCLAP::ValueArg<std::string> preds("", "labels-out-dir", "write each frame's predictions (1 byte per point, "
                                       "1 ground) as DIR/SEQ_FRAME.pred", false, "", "DIR", cmd);
    TCLAP::SwitchArg breakdown("", "breakdown", "failure analysis: false ground by class, height above the local "
                               "labelled ground and range, missed ground by class and range, per frame and "
                               "sequence; with --report also PREFIX_breakdown.csv and a top-down PNG per frame "
                               "(true / false / missed ground) in PREFIX_breakdown/", cmd, false);
    TCLAP::ValueArg<int> ringStep("", "ring-step", "score each scan with only every Nth laser ring, as a sensor with N "
                                  "times fewer beams would see it (1-64; rings found from the order KITTI stores its "
                                  "points in, one azimuth sweep after another; --labels-out-dir then holds the kept "
                                  "points' predictions)", false, 1, "N", cmd);
    TCLAP::ValueArg<int> pointStep("", "point-step", "... and only every Nth point along the rings (1-64: a coarser "
                                   "azimuth step)", false, 1, "N", cmd);
    TCLAP::SwitchArg noContext("", "no-drive-context", "do not score drives (sequences with poses.txt and calib.txt) "
                               "again with their terrain model (#31); by default each such sequence's frames are "
                               "printed alone and with the model of the whole drive, side by side", cmd, false);
    if (const int code = line.parse(argc, argv); code >= 0) return code;
    ranks.setTimeout("gseg eval", line.mpiTimeout());
    if (!input.getValue().empty() && !root.getValue().empty())
        return line.usageError("give the root once: -i ROOT (or the old form, gseg eval ROOT)");
    cli = {input.getValue().empty() ? root.getValue() : input.getValue(), scan.getValue(), labels.getValue(),
           cfg.getValue(), report.getValue(), preds.getValue(), splitCommas(seqs.getValue()), threads.getValue(),
           breakdown.getValue(), line.overwrite(), ringStep.getValue(), pointStep.getValue(), !noContext.getValue()};
    if (cli.root.empty() == cli.scan.empty() || cli.threads < 1 || cli.threads > 256)
        return line.usageError("give either -i ROOT or --scan X.bin --labels X.label, and --threads 1..256");
    if (cli.ringStep < 1 || cli.ringStep > 64 || cli.pointStep < 1 || cli.pointStep > 64)
        return line.usageError("--ring-step and --point-step take 1..64");
    try {
        return run(cli, ranks);
    } catch (...) {
        return tools::reportError("gseg eval", tools::InvalidArgument::BadInput);
    }
}

}  // namespace gseg::app
