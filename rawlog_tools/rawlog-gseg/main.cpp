// rawlog-gseg: split every LiDAR scan of a rawlog into ground and obstacle point clouds.
//
// Streams the input (constant memory), accepts both rawlog layouts, and writes every entry it does
// not segment through unchanged and in order. Each segmented scan is followed by two
// CObservationPointCloud, "<label>_ground" and "<label>_obstacles" (inside the same sensory frame
// in the sensory-frame layout); --replace drops the original scan. The output is written to a
// temporary file and renamed only when complete.
//
// A batch (#12): several inputs (-i repeated, or --list FILE) into a folder (-o DIR), one output
// per input under its file name. Each input is done by segmentFile(), exactly as a run on it
// alone; a failing input is named, leaves no output, and the others go on. Under mpirun/srun the
// inputs are split over the ranks by size, and rank 0 reports on all of them.
#include "common/bytes.hpp"
#include "common/ranks.hpp"

#include <gseg/mrpt/ground_filter.hpp>
#include <gseg/mrpt/observation_points.hpp>
#include <gseg/mrpt/rawlog_io.hpp>

#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
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
};

struct Totals {
    std::size_t entries = 0, scans = 0, points = 0, ground = 0;
    double ms = 0;
};

class Segmenter {
public:
    /// `name`: the input, shown in the progress of a batch ("" for one input).
    Segmenter(const Cli& cli, Totals& totals, std::string name)
        : cli_(cli), totals_(totals), name_(name.empty() ? "" : name + ": "), tty_(::isatty(::fileno(stderr)) != 0) {
        if (!cli.config.empty()) filter_.loadConfig(cli.config);
        filter_.outputFrame = cli.frame == "vehicle" ? gseg::GroundFilter::OutputFrame::Vehicle
                                                     : gseg::GroundFilter::OutputFrame::Sensor;
    }

    bool wanted(const mrpt::obs::CObservation& obs) const {
        return gseg::mrpt::isLidarObservation(obs) &&
               (cli_.sensors.empty() ||
                std::find(cli_.sensors.begin(), cli_.sensors.end(), obs.sensorLabel) != cli_.sensors.end());
    }

    /// The observations that replace `obs` in the output: [obs], ground, obstacles.
    std::vector<mrpt::obs::CObservation::Ptr> process(const mrpt::obs::CObservation::Ptr& obs, std::size_t entry) {
        gseg::GroundFilter::Output o;
        try {
            o = filter_.filter(*obs);
        } catch (const std::exception& e) {
            throw std::runtime_error("entry " + std::to_string(entry) + " ('" + obs->sensorLabel + "'): " + e.what());
        }
        ++totals_.scans;
        totals_.points += o.result.labels.size();
        totals_.ground += o.result.numGround;
        totals_.ms += o.result.totalMs;
        progress(entry, o);
        std::vector<mrpt::obs::CObservation::Ptr> out;
        if (!cli_.replace) out.push_back(obs);
        out.push_back(o.ground);
        out.push_back(o.obstacles);
        return out;
    }

private:
    void progress(std::size_t entry, const gseg::GroundFilter::Output& o) {
        if (tty_)
            std::fprintf(stderr, "\rrawlog-gseg: %sentry %zu, %zu scans segmented (last: %zu points, %.1f %% ground%s)   ",
                         name_.c_str(), entry, totals_.scans, o.result.labels.size(),
                         100.0 * double(o.result.numGround) / double(std::max<std::size_t>(1, o.result.labels.size())),
                         o.distToGroundEstimated ? (", height " + std::to_string(o.distToGround).substr(0, 5) + " m").c_str() : "");
        else if (totals_.scans % 100 == 1)
            std::fprintf(stderr, "rawlog-gseg: %sentry %zu, %zu scans segmented\n", name_.c_str(), entry, totals_.scans);
    }

    const Cli& cli_;
    Totals& totals_;
    std::string name_;
    bool tty_;
    gseg::GroundFilter filter_;
};

/// Segments the rawlog `in` into `out`: what rawlog-gseg does to one input. Returns the summary
/// ("N entries, ... wrote OUT"); throws naming the entry on a bad input, leaving nothing at `out`.
/// `name`: the input in the progress lines of a batch ("" for one input).
std::string segmentFile(const Cli& cli, const std::string& in, const std::string& outPath, const std::string& name) {
    Totals totals;
    Segmenter seg(cli, totals, name);
    const std::string tmp = outPath + ".tmp" + std::to_string(::getpid());
    try {
        mrpt::io::CFileGZOutputStream file;
        if (!file.open(tmp)) throw std::runtime_error(outPath + ": cannot create the output");
        auto out = mrpt::serialization::archiveFrom(file);
        gseg::mrpt::forEachRawlogEntry(in, [&](std::size_t entry, const auto& obj) {
            ++totals.entries;
            if (auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj); obs && seg.wanted(*obs)) {
                for (const auto& o : seg.process(obs, entry)) out << *o;
            } else if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(obj)) {
                mrpt::obs::CSensoryFrame result;
                for (const auto& o : *sf) {
                    if (!o || !seg.wanted(*o)) {
                        result.insert(o);
                        continue;
                    }
                    for (const auto& p : seg.process(o, entry)) result.insert(p);
                }
                out << result;
            } else {
                out << *obj;
            }
            return true;
        });
        file.close();
        fs::rename(tmp, outPath);
    } catch (...) {
        std::remove(tmp.c_str());
        throw;
    }
    if (::isatty(::fileno(stderr))) std::fprintf(stderr, "\n");
    char summary[400];
    std::snprintf(summary, sizeof summary, "%zu entries, %zu scans segmented, %zu points, %.1f %% ground, %.2f ms per scan; wrote ",
                  totals.entries, totals.scans, totals.points,
                  100.0 * double(totals.ground) / double(std::max<std::size_t>(1, totals.points)),
                  totals.scans ? totals.ms / double(totals.scans) : 0.0);
    return summary + outPath;
}

/// What one input of a batch gave.
struct FileResult {
    bool failed = false;
    std::string message;  ///< the summary, or why it failed
};

/// The inputs (-i, then --list) and their outputs: `-o` itself for one input given with -i, else
/// DIR/<input file name>. Throws std::invalid_argument on a batch that cannot be written (two
/// inputs with the same name, an output that is an input), std::runtime_error on an unreadable list.
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
        const std::string out = batch ? (fs::path(cli.out) / name).string() : cli.out;
        if (batch && !names.insert(name).second)
            throw std::invalid_argument("two inputs named " + name + ": their outputs in " + cli.out + " would collide");
        std::error_code ec;
        if (fs::equivalent(in, out, ec)) throw std::invalid_argument(out + " is the input " + in + ": choose another output");
        jobs.emplace_back(in, out);
    }
    return jobs;
}

/// Rank 0 prints every input's result in input order; the exit code: 1 if any failed.
/// `owner`: the rank of each input (the split is printed for several ranks).
int report(const std::vector<std::pair<std::string, std::string>>& jobs, const std::vector<FileResult>& results, bool batch,
           const std::vector<int>& owner, int processes) {
    std::vector<std::string> failed;
    for (std::size_t i = 0; i < jobs.size(); ++i) {
        const std::string& in = jobs[i].first;
        const std::string what = batch ? in + ": " : "";
        if (results[i].failed) {
            const bool named = results[i].message.rfind(in, 0) == 0;  // reader errors start with the file
            std::fprintf(stderr, "%srawlog-gseg: %s%s\n", batch ? "" : "\n", named ? "" : what.c_str(), results[i].message.c_str());
            failed.push_back(in);
        } else {
            std::printf("rawlog-gseg: %s%s\n", what.c_str(), results[i].message.c_str());
        }
    }
    if (batch) {
        std::string names, split;
        for (const std::string& f : failed) names += (names.empty() ? ": " : ", ") + f;
        for (int r = 0; r < processes && processes > 1; ++r)
            split += (r ? ", " : " (inputs per process: ") + std::to_string(std::count(owner.begin(), owner.end(), r));
        std::printf("rawlog-gseg: %zu of %zu rawlogs written%s%s%s\n", jobs.size() - failed.size(), jobs.size(),
                    split.empty() ? "" : (split + ")").c_str(), failed.empty() ? "" : ", failed", names.c_str());
    }
    std::fflush(stdout);
    return failed.empty() ? 0 : 1;
}

/// One rank's part: its inputs (split by size), then rank 0 gathers and reports. The exit code.
int runBatch(const Cli& cli, gseg::tools::Ranks& ranks) {
    std::vector<std::pair<std::string, std::string>> jobs;
    bool batch = false;
    std::string error;
    int code = 0;
    try {
        if (cli.frame != "sensor" && cli.frame != "vehicle") throw std::invalid_argument("--frame must be sensor or vehicle");
        jobs = plan(cli, batch);
        if (!cli.config.empty()) gseg::GroundFilter().loadConfig(cli.config);  // a bad config fails once, not per input
        if (batch && ranks.root()) fs::create_directories(cli.out);
    } catch (const std::invalid_argument& e) {
        error = e.what(), code = 2;
    } catch (const std::exception& e) {
        error = e.what(), code = 1;
    }
    if (const std::string first = ranks.firstError(error); !first.empty()) {
        std::fprintf(stderr, "rawlog-gseg: %s\n", first.substr(0, first.find('\n')).c_str());
        return code ? code : 1;
    }
    std::vector<std::string> inputs;
    for (const auto& job : jobs) inputs.push_back(job.first);
    std::vector<int> owner;
    auto segmentMine = [&](const std::vector<std::size_t>& mine) {
        std::vector<std::string> done;
        for (const std::size_t i : mine) {
            FileResult r;
            try {
                r.message = segmentFile(cli, jobs[i].first, jobs[i].second, batch ? jobs[i].first : "");
            } catch (const std::exception& e) {
                const std::string what = e.what();
                r.failed = true, r.message = what.substr(0, what.find('\n'));
            }
            done.push_back(gseg::tools::ByteWriter().u64(r.failed).str(r.message).bytes());
        }
        return done;
    };
    const std::vector<std::string> all = gseg::tools::shareItems(ranks, gseg::tools::fileSizes(inputs), segmentMine, &owner);
    std::vector<FileResult> results;
    for (const std::string& one : all) {
        gseg::tools::ByteReader in(one);
        const bool failed = in.u64() != 0;
        results.push_back({failed, in.str()});
    }
    return ranks.root() ? report(jobs, results, batch, owner, ranks.size()) : 0;
}

int run(int argc, char** argv, gseg::tools::Ranks& ranks) {
    Cli cli;
    try {
        TCLAP::CmdLine cmd("Split every LiDAR scan of a rawlog into <label>_ground and <label>_obstacles point clouds "
                           "with GSeg3D. Several inputs (-i repeated, or --list) go into the folder -o DIR under their "
                           "file names; a failing input is named and leaves no output, the others are written (exit 1 "
                           "if any failed). Under mpirun or srun the inputs are split over the processes.", ' ', "0.1");
        TCLAP::MultiArg<std::string> in("i", "input", "input rawlog (plain or gzip, either layout); repeatable", false, "IN", cmd);
        TCLAP::ValueArg<std::string> list("", "list", "a file listing input rawlogs, one a line (# comments)", false, "",
                                          "FILE", cmd);
        TCLAP::ValueArg<std::string> outArg("o", "output", "output rawlog (gzip); with several inputs or --list, the "
                                            "folder for them (made if missing)", true, "", "OUT|DIR", cmd);
        TCLAP::ValueArg<std::string> cfg("c", "config", "YAML or INI parameters (distToGround: auto allowed)", false,
                                         "", "FILE", cmd);
        TCLAP::SwitchArg replace("", "replace", "drop the original scans (default: keep them)", cmd);
        TCLAP::MultiArg<std::string> sensor("", "sensor", "segment only observations with this sensorLabel "
                                            "(repeatable; default all LiDAR observations)", false, "LABEL", cmd);
        TCLAP::ValueArg<std::string> frame("", "frame", "output points in the sensor frame (default) or the vehicle "
                                           "frame", false, "sensor", "sensor|vehicle", cmd);
        if (!cmd.parse(argc, argv)) {
            for (int i = 1; i < argc; ++i)
                if (!std::strcmp(argv[i], "-h") || !std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "--version"))
                    return 0;
            return 2;
        }
        cli = {in.getValue(), list.getValue(), outArg.getValue(), cfg.getValue(), frame.getValue(), sensor.getValue(),
               replace.getValue()};
    } catch (const TCLAP::ArgException& e) {
        std::fprintf(stderr, "rawlog-gseg: %s (%s)\n", e.error().c_str(), e.argId().c_str());
        return 2;
    }
    try {
        return runBatch(cli, ranks);
    } catch (const std::exception& e) {  // not an input's failure (those are reported per input)
        std::fprintf(stderr, "rawlog-gseg: %s\n", e.what());
        return 1;
    }
}

}  // namespace

int main(int argc, char** argv) {
    gseg::tools::Ranks ranks(argc, argv);
    return ranks.exitCode(run(argc, argv, ranks));
}
