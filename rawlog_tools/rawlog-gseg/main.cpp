// rawlog-gseg: split every LiDAR scan of a rawlog into ground and obstacle point clouds.
//
// Streams the input (constant memory), accepts both rawlog layouts, and writes every entry it does
// not segment through unchanged and in order (gseg::mrpt::RawlogSegmenter). Each segmented scan is
// followed by two CObservationPointCloud, "<label>_ground" and "<label>_obstacles" (inside the same
// sensory frame in the sensory-frame layout); --replace drops the original scan. A scan that cannot
// be segmented is passed through and named, and the exit code is then 3. The output is written
// through a temporary file (every write checked) and renamed only when complete; an interrupted or
// crashed run removes the temporary.
//
// A batch (#12): several inputs (-i repeated, or --list FILE) into a folder (-o DIR), one output
// per input under its file name. Each input is done by segmentFile(), exactly as a run on it
// alone; a failing input is named, leaves no output, and the others go on (exit 1). Under
// mpirun/srun the inputs are split over the ranks by size, and rank 0 reports on all of them.
#include "common/cli.hpp"
#include "common/ranks.hpp"

#include <gseg/io/atomic_file.hpp>
#include <gseg/io/bytes.hpp>
#include <gseg/map/drive_model.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/segment_scan.hpp>
#include <gseg/mrpt/rawlog_io.hpp>
#include <gseg/mrpt/rawlog_segmenter.hpp>
#include <gseg/progress.hpp>
#include <gseg/ordered_pipeline.hpp>

#include <mrpt/serialization/CSerializable.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

struct Cli {
    std::vector<std::string> inputs;  ///< -i, repeatable
    std::string list;                 ///< --list: a file with one input rawlog a line
    std::string out, config, frame = "sensor";
    std::vector<std::string> sensors;
    bool replace = false;
    bool overwrite = false;  ///< -w: replace outputs that exist
    bool driveContext = true;  ///< label with the whole drive's terrain model where the rawlog has poses (#31)
    unsigned workers = 1;  ///< scans segmented at once, in both passes (every usable core; 1 under MPI: the ranks share the inputs)
};

/// Exit codes (also in --help).
using gseg::tools::kBadInput;  // the exit codes of every tool (common/cli.hpp)
using gseg::tools::kBadUsage;
using gseg::tools::kDone;
using gseg::tools::kPartlyDone;

/// Reports on the scans of one input: progress (gseg::Progress: a live line on a terminal, else a
/// line every 10 s), the skipped scans (always: they make the exit code 3) and with --verbose a
/// line per scan.
class Reporter {
public:
    /// `name`: the input, shown in the lines of a batch ("" for one input); the skipped scans'
    /// lines are also kept in `skipped` (for rank 0 to print those of other ranks).
    Reporter(const std::string& name, std::vector<std::string>& skipped, std::vector<std::string>& warnings,
             gseg::Progress& progress)
        : name_(name.empty() ? "" : name + ": "), skipped_(skipped), warnings_(warnings), progress_(progress) {}

    void operator()(const gseg::mrpt::ScanReport& r) {
        if (!r.skipped.empty()) {
            char line[200];
            std::snprintf(line, sizeof line, "entry %zu ('%s') skipped, passed through unchanged: ", r.entry, r.label.c_str());
            skipped_.push_back(name_ + line + r.skipped);
            if (gseg::tools::progressOut()) progress_.message("rawlog-gseg: " + skipped_.back());
            else std::fprintf(stderr, "rawlog-gseg: %s\n", skipped_.back().c_str());
            return;
        }
        ++scans_;
        if (r.distToGroundEstimated) {
            minHeight_ = std::min(minHeight_, r.distToGround), maxHeight_ = std::max(maxHeight_, r.distToGround);
            ++estimated_;
        } else {
            fallback_ = r.distToGround, ++fixed_;
        }
        if (!r.heightWarning.empty())  // a warning, not an error: said with the input's summary
            warnings_.push_back(name_ + "entry " + std::to_string(r.entry) + " ('" + r.label + "'): " + r.heightWarning);
        const double ground = 100.0 * double(r.ground) / double(std::max<std::size_t>(1, r.points));
        gseg::tools::detail("rawlog-gseg: %sentry %zu ('%s'): %zu points, %.1f %% ground%s\n", name_.c_str(), r.entry,
                            r.label.c_str(), r.points, ground,
                            r.distToGroundEstimated ? (", height " + std::to_string(r.distToGround).substr(0, 5) + " m").c_str() : "");
        progress_.update(scans_, -1, "entry " + std::to_string(r.entry));
    }

    std::size_t scans() const { return scans_; }

    /// The sensor heights used, for the summary: "distToGround auto: estimated 2.27 m" (a range
    /// over several scans, and the scans that fell back to the configured height), or
    /// "distToGround 1.723 m (fixed)".
    std::string heights(bool autoHeight) const {
        char text[200];
        if (!autoHeight) {
            std::snprintf(text, sizeof text, "distToGround %.3f m (fixed)", fallback_);
            return text;
        }
        std::string out = "distToGround auto: ";
        if (estimated_ == 1 || (estimated_ > 1 && maxHeight_ - minHeight_ < 0.005))
            std::snprintf(text, sizeof text, "estimated %.2f m", minHeight_);
        else if (estimated_ > 1)
            std::snprintf(text, sizeof text, "estimated %.2f to %.2f m", minHeight_, maxHeight_);
        else
            std::snprintf(text, sizeof text, "no estimate");
        out += text;
        if (fixed_) {
            std::snprintf(text, sizeof text, ", %zu scan(s) at the configured %.3f m", fixed_, fallback_);
            out += text;
        }
        return out;
    }

private:
    std::string name_;
    std::vector<std::string>& skipped_;
    std::vector<std::string>& warnings_;
    gseg::Progress& progress_;
    double minHeight_ = 1e300, maxHeight_ = -1e300, fallback_ = 0;
    std::size_t estimated_ = 0, fixed_ = 0;
    std::size_t scans_ = 0;
};

/// What one input gave.
struct FileResult {
    int code = kDone;                  ///< kDone, kPartlyDone (scans skipped), or kBadInput (nothing written)
    std::string message;               ///< the summary, or why it failed
    std::vector<std::string> skipped;  ///< the lines naming the scans passed through unsegmented
    std::vector<std::string> warnings; ///< remarks that are no error (a distToGround the scan contradicts)
    std::string unmatched;             ///< a --sensor that matched no observation, and the labels the rawlog has
};

/// "--sensor X matched no observation; the rawlog has: VELODYNE (6), ..." for the first --sensor
/// label without a LiDAR observation in the input, or "" when every one matched (or none was given).
std::string unmatchedSensor(const std::vector<std::string>& sensors, const std::map<std::string, std::size_t>& seen) {
    for (const std::string& label : sensors) {
        if (seen.count(label)) continue;
        std::string has;
        for (const auto& [name, n] : seen) has += (has.empty() ? "" : ", ") + (name.empty() ? "(no label)" : name) + " (" + std::to_string(n) + ")";
        return "--sensor " + label + " matched no observation; the rawlog has " +
               (has.empty() ? "no LiDAR observation" : "LiDAR observations from: " + has);
    }
    return "";
}

/// Segments the rawlog `in` into `outPath`: what rawlog-gseg does to one input, whole. `name`: the
/// input in the progress lines of a batch ("" for one input). Throws naming the entry on a bad
/// input, leaving nothing at `outPath`. `config`: -c (or the default), loaded once per run.
FileResult segmentFile(const Cli& cli, const gseg::mrpt::LoadedConfig& config, const std::string& in,
                       const std::string& outPath, const std::string& name) {
    gseg::mrpt::RawlogSegmenterOptions options;
    options.sensors = cli.sensors;
    options.replace = cli.replace;
    options.frame = cli.frame == "vehicle" ? gseg::GroundFilter::OutputFrame::Vehicle : gseg::GroundFilter::OutputFrame::Sensor;

    // The drive's context (#31): pass 1 builds the whole drive's terrain model where every scan
    // has a pose; pass 2 (below) labels each scan with it.
    // A pipe or FIFO can be read only once: its scans are labelled alone, and the summary says why.
    gseg::map::DriveModel drive;
    std::error_code notAFile;
    if (cli.driveContext && !std::filesystem::is_regular_file(in, notAFile)) {
        drive.why = "the input is not a regular file and can be read only once; give a file for the drive's context";
    } else if (cli.driveContext) {
        gseg::Progress pass1(gseg::tools::progressOut(), "rawlog-gseg" + (name.empty() ? "" : ": " + name) + ": the drive's terrain (pass 1 of 2)",
                             "scans");
        drive = gseg::map::driveModelOf(in, config, cli.sensors, [&](std::size_t scans, double) { pass1.update(scans, -1, ""); },
                                        cli.workers);
        if (drive.model) pass1.finish(drive.scans);
        if (drive.model) {
            options.driveModel = drive.model;
            options.poseOf = [&drive](std::size_t entry, const std::string& label) { return drive.poseOf(entry, label); };
        }
    }

    FileResult result;
    gseg::mrpt::RawlogWriter writer(outPath);
    gseg::Progress progress(gseg::tools::progressOut(), "rawlog-gseg" + (name.empty() ? "" : ": " + name) + (drive.model ? " (pass 2 of 2)" : ""),
                            "scans");
    Reporter reporter(name, result.skipped, result.warnings, progress);
    gseg::mrpt::RawlogSegmenter segmenter(
        config, options, [&](const mrpt::serialization::CSerializable& o) { writer.write(o); },
        [&](const gseg::mrpt::ScanReport& r) { reporter(r); });
    gseg::mrpt::RawlogReader reader(in);
    segmenter.run(reader, cli.workers);
    writer.commit();
    progress.finish(reporter.scans());

    const gseg::mrpt::RawlogTotals t = segmenter.totals();
    char text[300];
    std::snprintf(text, sizeof text, "%zu entries, %zu scans segmented, %zu points, %.1f %% ground, %.2f ms per scan",
                  t.entries, t.scans, t.points, 100.0 * double(t.ground) / double(std::max<std::size_t>(1, t.points)),
                  t.scans ? t.ms / double(t.scans) : 0.0);
    result.message = text;
    if (reporter.scans()) result.message += ", " + reporter.heights(config.distToGroundAuto) + " " + gseg::mrpt::configOrigin(cli.config);
    if (drive.model) {
        std::snprintf(text, sizeof text, ", %zu scans labelled with the drive's terrain model (%zu anchored + %zu grown cells, poses: %s): "
                      "%zu points turned ground, %zu non-ground", t.withDrive, drive.model->anchors(), drive.model->grown(), drive.poseSource.c_str(),
                      t.driveRelabelled, t.driveDropped);
        result.message += text;
    } else if (t.scans && !drive.why.empty()) {
        result.message += ", single-scan labels (no drive context: " + drive.why + ")";
    }
    if (t.nonFinite) result.message += ", " + std::to_string(t.nonFinite) + " non-finite points labelled non-ground";
    if (t.alreadySplit) result.message += ", " + std::to_string(t.alreadySplit) + " already split (passed through)";
    if (!t.skipped.empty()) result.message += ", " + std::to_string(t.skipped.size()) + " skipped (passed through, named above)";
    result.message += "; wrote " + outPath;
    result.unmatched = unmatchedSensor(cli.sensors, t.lidarScans);
    if (result.unmatched.empty() && t.lidarScans.empty() && t.segmentedHalves == 0)  // exit 3, said whatever the verbosity
        result.unmatched = "no 3D LiDAR scan in the rawlog (CObservationPointCloud, CObservationVelodyneScan, "
                           "CObservation3DRangeScan): nothing segmented, every entry passed through";
    result.code = t.skipped.empty() && result.unmatched.empty() ? kDone : kPartlyDone;
    return result;
}

/// The inputs (-i, then --list) and their outputs: `-o` itself for one input given with -i (and
/// -o not a folder), else DIR/<input file name>. Throws std::invalid_argument on a run that cannot
/// be written (two inputs with one name), std::runtime_error on an unreadable list.
std::vector<std::pair<std::string, std::string>> plan(const Cli& cli, bool& batch) {
    std::vector<std::string> inputs = cli.inputs;
    if (!cli.list.empty()) {
        std::ifstream list(cli.list);
        if (!list) throw std::runtime_error(cli.list + ": cannot read the list of rawlogs");
        for (std::string line; std::getline(list, line);) {
            line.erase(0, line.find_first_not_of(" \t"));
            line.erase(line.find_last_not_of(" \t\r") + 1);
            if (!line.empty() && line[0] != '#') inputs.push_back(line);
        }
    }
    if (inputs.empty()) throw std::invalid_argument("no input: give -i IN (repeatable) or --list FILE");
    batch = inputs.size() > 1 || !cli.list.empty() || fs::is_directory(cli.out);
    std::vector<std::pair<std::string, std::string>> jobs;
    std::set<std::string> names;
    for (const std::string& in : inputs) {
        const std::string name = fs::path(in).filename().string();
        if (batch && !names.insert(name).second)
            throw std::invalid_argument("two inputs named " + name + ": their outputs in " + cli.out + " would collide");
        jobs.emplace_back(in, batch ? (fs::path(cli.out) / name).string() : cli.out);
    }
    return jobs;
}

/// Before any work (by rank 0, which makes the folder of a batch): every output can be written,
/// is no input, and does not exist unless -w. Throws std::invalid_argument naming it.
void checkOutputs(const Cli& cli, const std::vector<std::pair<std::string, std::string>>& jobs, bool batch) {
    std::vector<gseg::io::NamedPath> ins = {{"--config", cli.config}, {"--list", cli.list}}, outs;
    for (const auto& job : jobs) ins.push_back({"input", job.first}), outs.push_back({"-o", job.second});
    gseg::io::checkOutputs(ins, outs, {cli.overwrite, batch});
}

/// Rank 0 prints every input's result in input order (and the skipped scans of inputs other
/// ranks did: its own were printed as they came). Returns the exit code: 1 if an input failed,
/// else 3 if scans were skipped, else 0. `owner`: the rank of each input.
int report(const std::vector<std::pair<std::string, std::string>>& jobs, const std::vector<FileResult>& results, bool batch,
           const std::vector<int>& owner, int processes) {
    std::vector<std::string> failed;
    int code = kDone;
    for (std::size_t i = 0; i < jobs.size(); ++i) {
        const std::string& in = jobs[i].first;
        const std::string what = batch ? in + ": " : "";
        if (owner[i] != 0)  // errors: printed whatever the verbosity
            for (const std::string& line : results[i].skipped) std::fprintf(stderr, "rawlog-gseg: %s\n", line.c_str());
        for (const std::string& line : results[i].warnings) gseg::tools::note("rawlog-gseg: %s\n", line.c_str());
        if (!results[i].unmatched.empty())  // what the user asked for is not there: printed whatever the verbosity
            std::fprintf(stderr, "rawlog-gseg: %s%s\n", what.c_str(), results[i].unmatched.c_str());
        if (results[i].code == kBadInput) {
            const bool named = results[i].message.rfind(in, 0) == 0;  // reader errors start with the file
            std::fprintf(stderr, "%srawlog-gseg: %s%s\n", !batch && ::isatty(::fileno(stderr)) ? "\n" : "",
                         named ? "" : what.c_str(), results[i].message.c_str());
            failed.push_back(in);
        } else {
            gseg::tools::say("rawlog-gseg: %s%s\n", what.c_str(), results[i].message.c_str());
            code = std::max(code, results[i].code);
        }
    }
    if (batch) {
        std::string names, split;
        for (const std::string& f : failed) names += (names.empty() ? ": " : ", ") + f;
        for (int r = 0; r < processes && processes > 1; ++r)
            split += (r ? ", " : " (inputs per process: ") + std::to_string(std::count(owner.begin(), owner.end(), r));
        gseg::tools::say("rawlog-gseg: %zu of %zu rawlogs written%s%s%s\n", jobs.size() - failed.size(), jobs.size(),
                    split.empty() ? "" : (split + ")").c_str(), failed.empty() ? "" : ", failed", names.c_str());
    }
    std::fflush(stdout);
    return failed.empty() ? code : kBadInput;
}

/// One rank's part: its inputs (split by size), then rank 0 gathers and reports. The exit code.
int runBatch(const Cli& cli, gseg::tools::Ranks& ranks) {
    std::vector<std::pair<std::string, std::string>> jobs;
    bool batch = false;
    std::string error;
    int code = kDone;
    gseg::mrpt::LoadedConfig config;
    try {
        if (cli.frame != "sensor" && cli.frame != "vehicle") throw std::invalid_argument("--frame must be sensor or vehicle");
        jobs = plan(cli, batch);
        if (ranks.root()) checkOutputs(cli, jobs, batch);
        try {
            config = gseg::mrpt::loadConfigOrDefault(cli.config);  // once: a bad config fails once, not per input
        } catch (const std::invalid_argument& e) {  // a bad file is bad input, not bad usage
            throw std::runtime_error(e.what());
        }
        if (ranks.root()) gseg::tools::noteWarnings("rawlog-gseg", config.warnings);
        if (ranks.root() && !cli.config.empty())
            gseg::tools::detail("parameters (%s):\n%s", cli.config.c_str(),
                                gseg::mrpt::toYaml(config).c_str());
        if (batch && ranks.root()) fs::create_directories(cli.out);
    } catch (...) {
        error = gseg::tools::currentError(), code = gseg::tools::exitCodeOf(gseg::tools::InvalidArgument::BadUsage);
    }
    if (const std::string first = ranks.firstError(error); !first.empty()) {
        std::fprintf(stderr, "rawlog-gseg: %s\n", first.c_str());
        return code ? code : kBadInput;
    }
    std::vector<std::string> inputs;
    for (const auto& job : jobs) inputs.push_back(job.first);
    auto segmentMine = [&](const std::vector<std::size_t>& mine) {
        std::vector<std::string> done;
        for (const std::size_t i : mine) {
            FileResult r;
            try {
                r = segmentFile(cli, config, jobs[i].first, jobs[i].second, batch ? jobs[i].first : "");
            } catch (const std::exception& e) {
                r.code = kBadInput, r.message = gseg::mrpt::errorReason(e);
            }
            gseg::io::ByteWriter out;
            out.u64(std::uint64_t(r.code)).str(r.message).u64(r.skipped.size());
            for (const std::string& line : r.skipped) out.str(line);
            out.u64(r.warnings.size());
            for (const std::string& line : r.warnings) out.str(line);
            out.str(r.unmatched);
            done.push_back(out.bytes());
        }
        return done;
    };
    std::vector<int> owner;
    const std::vector<std::string> all = gseg::tools::shareItems(ranks, gseg::tools::fileSizes(inputs), segmentMine, &owner);
    std::vector<FileResult> results;
    for (const std::string& one : all) {
        gseg::io::ByteReader in(one);
        FileResult& r = results.emplace_back();
        r.code = int(in.u64()), r.message = in.str();
        for (std::uint64_t n = in.u64(); n > 0; --n) r.skipped.push_back(in.str());
        for (std::uint64_t n = in.u64(); n > 0; --n) r.warnings.push_back(in.str());
        r.unmatched = in.str();
    }
    return ranks.root() ? report(jobs, results, batch, owner, ranks.size()) : kDone;
}

int run(int argc, char** argv, gseg::tools::Ranks& ranks) {
    gseg::tools::CommandLine line(
        "rawlog-gseg",
        "Split every LiDAR scan of a rawlog into <label>_ground and <label>_obstacles point clouds with GSeg3D. Several "
        "inputs (-i repeated, or --list) go into the folder -o DIR under their file names, each as a run on it alone; a "
        "failing input is named and leaves no output, the others are written. An output that exists is refused unless "
        "-w. Under mpirun or srun the inputs are split over the processes. Exit code: 0 done, 1 bad input (nothing "
        "written for it), 2 bad usage, 3 done but some scans could not be segmented (passed through unchanged and named "
        "on stderr), a --sensor label matched no observation (named with the labels the rawlog has) or the rawlog has no "
        "3D LiDAR scan at all (every entry passed through).",
        true, ranks.root());
    line.addMpiTimeout();
    TCLAP::CmdLine& cmd = line.cmd();
    TCLAP::MultiArg<std::string> in("i", "input", "input rawlog (plain or gzip, either layout); repeatable", false, "IN",
                                    cmd);
    TCLAP::ValueArg<std::string> list("", "list", "a file listing input rawlogs, one a line (# comments)", false, "",
                                      "FILE", cmd);
    TCLAP::ValueArg<std::string> outArg("o", "output", "output rawlog (gzip); with several inputs or --list, the "
                                        "folder for them (made if missing)", true, "", "OUT|DIR", cmd);
    TCLAP::ValueArg<std::string> cfg("c", "config", "YAML or INI parameters (distToGround: auto allowed)", false, "",
                                     "FILE", cmd);
    TCLAP::SwitchArg replace("", "replace", "drop the original scans (default: keep them)", cmd);
    TCLAP::SwitchArg noDrive("", "no-drive-context", "label each scan alone; by default, where the rawlog has a pose for "
                             "every scan, a first pass builds the drive's terrain model and each scan is labelled with it (ground the scan alone "
                             "missed; traversability: driveTerrain and terrain* keys); either way scans are segmented on every core at once", cmd);
    TCLAP::MultiArg<std::string> sensor("", "sensor", "segment only observations with this sensorLabel "
                                        "(repeatable; default all LiDAR observations)", false, "LABEL", cmd);
    TCLAP::ValueArg<std::string> frame("", "frame", "output points in the sensor frame (default) or the vehicle "
                                       "frame", false, "sensor", "sensor|vehicle", cmd);
    if (const int code = line.parse(argc, argv); code >= 0) return code;
    ranks.setTimeout("rawlog-gseg", line.mpiTimeout());
    const Cli cli = {in.getValue(),       list.getValue(),   outArg.getValue(), cfg.getValue(),
                     frame.getValue(),    sensor.getValue(), replace.getValue(), line.overwrite(), !noDrive.getValue(),
                     ranks.size() > 1 ? 1u : gseg::usableCores()};
    gseg::io::installTemporaryCleanup("rawlog-gseg");
    try {
        return runBatch(cli, ranks);
    } catch (...) {  // not an input's failure (those are reported per input)
        return gseg::tools::reportError("rawlog-gseg", gseg::tools::InvalidArgument::BadInput);
    }
}

}  // namespace

int main(int argc, char** argv) {
    gseg::tools::Ranks ranks(argc, argv);
    return ranks.exitCode(run(argc, argv, ranks));
}
