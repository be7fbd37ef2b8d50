// rawlog-gseg: split every LiDAR scan of a rawlog into ground and obstacle point clouds.
//
// Streams the input (constant memory), accepts both rawlog layouts, and writes every entry it does
// not segment through unchanged and in order. Each segmented scan is followed by two
// CObservationPointCloud, "<label>_ground" and "<label>_obstacles" (inside the same sensory frame
// in the sensory-frame layout); --replace drops the original scan. The output is written to a
// temporary file and renamed only when complete.
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
#include <unistd.h>

namespace {

struct Cli {
    std::string in, out, config, frame = "sensor";
    std::vector<std::string> sensors;
    bool replace = false;
};

struct Totals {
    std::size_t entries = 0, scans = 0, points = 0, ground = 0;
    double ms = 0;
};

class Segmenter {
public:
    Segmenter(const Cli& cli, Totals& totals) : cli_(cli), totals_(totals), tty_(::isatty(::fileno(stderr)) != 0) {
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
            std::fprintf(stderr, "\rrawlog-gseg: entry %zu, %zu scans segmented (last: %zu points, %.1f %% ground%s)   ",
                         entry, totals_.scans, o.result.labels.size(),
                         100.0 * double(o.result.numGround) / double(std::max<std::size_t>(1, o.result.labels.size())),
                         o.distToGroundEstimated ? (", height " + std::to_string(o.distToGround).substr(0, 5) + " m").c_str() : "");
        else if (totals_.scans % 100 == 1)
            std::fprintf(stderr, "rawlog-gseg: entry %zu, %zu scans segmented\n", entry, totals_.scans);
    }

    const Cli& cli_;
    Totals& totals_;
    bool tty_;
    gseg::GroundFilter filter_;
};

int run(const Cli& cli) {
    if (cli.frame != "sensor" && cli.frame != "vehicle") throw std::runtime_error("--frame must be sensor or vehicle");
    Totals totals;
    Segmenter seg(cli, totals);
    const std::string tmp = cli.out + ".tmp" + std::to_string(::getpid());
    try {
        mrpt::io::CFileGZOutputStream file;
        if (!file.open(tmp)) throw std::runtime_error(cli.out + ": cannot create the output");
        auto out = mrpt::serialization::archiveFrom(file);
        gseg::mrpt::forEachRawlogEntry(cli.in, [&](std::size_t entry, const auto& obj) {
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
        std::filesystem::rename(tmp, cli.out);
    } catch (...) {
        std::remove(tmp.c_str());
        throw;
    }
    if (::isatty(::fileno(stderr))) std::fprintf(stderr, "\n");
    std::printf("rawlog-gseg: %zu entries, %zu scans segmented, %zu points, %.1f %% ground, %.2f ms per scan; wrote %s\n",
                totals.entries, totals.scans, totals.points,
                100.0 * double(totals.ground) / double(std::max<std::size_t>(1, totals.points)),
                totals.scans ? totals.ms / double(totals.scans) : 0.0, cli.out.c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    Cli cli;
    try {
        TCLAP::CmdLine cmd("Split every LiDAR scan of a rawlog into <label>_ground and <label>_obstacles point clouds "
                           "with GSeg3D.", ' ', "0.1");
        TCLAP::ValueArg<std::string> in("i", "input", "input rawlog (plain or gzip, either layout)", true, "", "IN", cmd);
        TCLAP::ValueArg<std::string> outArg("o", "output", "output rawlog (gzip)", true, "", "OUT", cmd);
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
        cli = {in.getValue(), outArg.getValue(), cfg.getValue(), frame.getValue(), sensor.getValue(), replace.getValue()};
    } catch (const TCLAP::ArgException& e) {
        std::fprintf(stderr, "rawlog-gseg: %s (%s)\n", e.error().c_str(), e.argId().c_str());
        return 2;
    }
    try {
        return run(cli);
    } catch (const std::exception& e) {
        std::string what = e.what();
        std::fprintf(stderr, "\nrawlog-gseg: %s\n", what.substr(0, what.find('\n')).c_str());
        return 1;
    }
}
