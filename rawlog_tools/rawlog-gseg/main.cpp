// rawlog-gseg: split every LiDAR scan of a rawlog into ground and obstacle point clouds.
//
// Streams the input (constant memory), accepts both rawlog layouts, and writes every entry it does
// not segment through unchanged and in order (gseg::mrpt::RawlogSegmenter). Each segmented scan is
// followed by two CObservationPointCloud, "<label>_ground" and "<label>_obstacles" (inside the same
// sensory frame in the sensory-frame layout); --replace drops the original scan. A scan that cannot
// be segmented is passed through and named, and the exit code is then 3. The output is written
// through a temporary file (every write checked) and renamed only when complete; an interrupted or
// crashed run removes the temporary.
#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/rawlog_io.hpp>
#include <gseg/mrpt/rawlog_segmenter.hpp>

#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/serialization/CSerializable.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <unistd.h>

namespace {

struct Cli {
    std::string in, out, config, frame = "sensor";
    std::vector<std::string> sensors;
    bool replace = false;
};

/// Exit codes (also in --help).
enum Exit { kDone = 0, kBadInput = 1, kBadUsage = 2, kScansSkipped = 3 };

class Reporter {
public:
    Reporter() : tty_(::isatty(::fileno(stderr)) != 0) {}

    void operator()(const gseg::mrpt::ScanReport& r) {
        if (!r.skipped.empty()) {
            std::fprintf(stderr, "%srawlog-gseg: entry %zu ('%s') skipped, passed through unchanged: %s\n",
                         tty_ ? "\n" : "", r.entry, r.label.c_str(), r.skipped.c_str());
            return;
        }
        ++scans_;
        if (tty_)
            std::fprintf(stderr, "\rrawlog-gseg: entry %zu, %zu scans segmented (last: %zu points, %.1f %% ground%s)   ",
                         r.entry, scans_, r.points, 100.0 * double(r.ground) / double(std::max<std::size_t>(1, r.points)),
                         r.distToGroundEstimated ? (", height " + std::to_string(r.distToGround).substr(0, 5) + " m").c_str() : "");
        else if (scans_ % 100 == 1)
            std::fprintf(stderr, "rawlog-gseg: entry %zu, %zu scans segmented\n", r.entry, scans_);
    }

private:
    bool tty_;
    std::size_t scans_ = 0;
};

int run(const Cli& cli) {
    gseg::mrpt::LoadedConfig config;
    if (!cli.config.empty()) config = gseg::mrpt::loadConfig(cli.config);
    gseg::mrpt::RawlogSegmenterOptions options;
    options.sensors = cli.sensors;
    options.replace = cli.replace;
    options.frame = cli.frame == "vehicle" ? gseg::GroundFilter::OutputFrame::Vehicle : gseg::GroundFilter::OutputFrame::Sensor;

    gseg::mrpt::RawlogWriter writer(cli.out);
    gseg::mrpt::RawlogSegmenter segmenter(
        config, options, [&](const mrpt::serialization::CSerializable& o) { writer.write(o); }, Reporter());
    gseg::mrpt::forEachRawlogEntry(cli.in, [&](std::size_t entry, const auto& obj) {
        segmenter.push(entry, obj);
        return true;
    });
    segmenter.finish();
    writer.commit();

    const gseg::mrpt::RawlogTotals& t = segmenter.totals();
    if (::isatty(::fileno(stderr))) std::fprintf(stderr, "\n");
    std::printf("rawlog-gseg: %zu entries, %zu scans segmented, %zu points, %.1f %% ground, %.2f ms per scan",
                t.entries, t.scans, t.points, 100.0 * double(t.ground) / double(std::max<std::size_t>(1, t.points)),
                t.scans ? t.ms / double(t.scans) : 0.0);
    if (t.nonFinite) std::printf(", %zu non-finite points labelled non-ground", t.nonFinite);
    if (t.alreadySplit) std::printf(", %zu already split (passed through)", t.alreadySplit);
    if (!t.skipped.empty()) std::printf(", %zu skipped (passed through, named above)", t.skipped.size());
    std::printf("; wrote %s\n", cli.out.c_str());
    return t.skipped.empty() ? kDone : kScansSkipped;
}

}  // namespace

int main(int argc, char** argv) {
    Cli cli;
    try {
        TCLAP::CmdLine cmd("Split every LiDAR scan of a rawlog into <label>_ground and <label>_obstacles point clouds "
                           "with GSeg3D. Exit code: 0 done, 1 bad input (nothing written), 2 bad usage, 3 done but "
                           "some scans could not be segmented (passed through unchanged and named on stderr).",
                           ' ', "0.1");
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
                    return kDone;
            return kBadUsage;
        }
        cli = {in.getValue(), outArg.getValue(), cfg.getValue(), frame.getValue(), sensor.getValue(), replace.getValue()};
        if (cli.frame != "sensor" && cli.frame != "vehicle") throw std::invalid_argument("--frame must be sensor or vehicle");
        gseg::io::checkOutputsAreNotInputs({{"input", cli.in}, {"--config", cli.config}}, {{"-o", cli.out}});
    } catch (const TCLAP::ArgException& e) {
        std::fprintf(stderr, "rawlog-gseg: %s (%s)\n", e.error().c_str(), e.argId().c_str());
        return kBadUsage;
    } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "rawlog-gseg: %s\n", e.what());
        return kBadUsage;
    }
    gseg::io::installTemporaryCleanup("rawlog-gseg");
    try {
        return run(cli);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%srawlog-gseg: %s\n", ::isatty(::fileno(stderr)) ? "\n" : "",
                     gseg::mrpt::errorReason(e).c_str());
        return kBadInput;
    }
}
