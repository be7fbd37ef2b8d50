// gseg segment: label one scan as ground / non-ground.
#include "commands.hpp"
#include "common/cli.hpp"

#include <gseg/io/atomic_file.hpp>
#include <gseg/io/ply.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/render.hpp>
#include <gseg/mrpt/scene.hpp>
#include <gseg/mrpt/scan_source.hpp>
#include <gseg/mrpt/segment_scan.hpp>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <memory>

namespace gseg::app {
namespace {

struct Cli {
    std::string scan, config, labelsOut, plyOut, pngOut, sceneOut;
    int index = -1;
};

void printPhase(const char* name, const PhaseReport& r) {
    tools::say("  %s: %zu -> %zu ground points, %zu cells (%zu candidates, %zu ground), %.2f ms "
                "[grid %.2f, classification %.2f, plane fit %.2f, expansion %.2f, refinement %.2f]\n",
                name, r.inputPoints, r.groundPoints, r.occupiedCells, r.candidateCells, r.groundCells, r.ms.total(),
                r.ms.grid, r.ms.classification, r.ms.planeFit, r.ms.expansion, r.ms.refinement);
}

int run(const Cli& cli) {
    using tools::say;
    const mrpt::LoadedConfig cfg = mrpt::loadConfigOrDefault(cli.config);  // the one default without -c
    tools::noteWarnings("gseg segment", cfg.warnings);
    tools::detail("parameters (%s):\n%s", cli.config.empty() ? "the default" : cli.config.c_str(),
                  mrpt::toYaml(cfg).c_str());
    const mrpt::Scan scan = mrpt::loadScan(cli.scan, cli.index);
    const PointCloudView cloud(scan.xyzi.data(), scan.size(), 4 * sizeof(float));
    mrpt::ScanSegmenter segmenter(cfg);
    const mrpt::ScanSegmentation s = segmenter.segment(cloud, false);
    const Result& r = s.result;
    say("%s\n", mrpt::heightSummary(cfg, cli.config).c_str());
    if (cfg.distToGroundAuto) say("distToGround auto: %s\n", s.height.describe().c_str());
    if (!s.heightWarning.empty()) tools::note("gseg segment: %s: %s\n", cli.scan.c_str(), s.heightWarning.c_str());

    say("%s\n", scan.description.c_str());
    say("points %zu, ground %zu (%.1f %%), non-ground %zu; segmentation %.2f ms\n", cloud.size(), r.numGround,
                100.0 * double(r.numGround) / double(std::max<std::size_t>(1, cloud.size())), r.numNonGround, r.totalMs);
    if (r.numNonFinite)
        say("%zu non-finite point(s) (NaN or infinite coordinates) labelled non-ground\n", r.numNonFinite);
    printPhase("phase I ", r.phase1);
    printPhase("phase II", r.phase2);

    // Every output to its temporary first; all put in place together when all are complete.
    std::vector<std::pair<std::string, std::string>> outputs;  // path, bytes
    auto add = [&](const std::string& path, std::string bytes) {
        if (!path.empty()) outputs.emplace_back(path, std::move(bytes));
    };
    add(cli.labelsOut, std::string(r.labels.begin(), r.labels.end()));
    if (!cli.plyOut.empty()) {
        io::PlyOptions ply;
        ply.intensity = true;  // the cloud views x, y, z, intensity
        ply.comment = "gseg ground segmentation of " + mrpt::displayName(cli.scan);
        add(cli.plyOut, io::labelledPlyBytes(cloud, r.labels, {}, ply));
    }
    // The pictures' name of the scan: the file, and for a rawlog which entry and sensor
    // ("x.rawlog, entry 0 'Velodyne1_SCAN'"; the description also names the class).
    std::string name = mrpt::displayName(cli.scan);
    if (scan.description.rfind("rawlog entry", 0) == 0) {
        const std::size_t colon = scan.description.find(':'), quote = scan.description.find(" '");
        name += ", " + scan.description.substr(7, colon - 7) + (quote == std::string::npos ? "" : scan.description.substr(quote));
    }
    if (!cli.pngOut.empty()) {
        mrpt::RenderOptions ro;
        ro.title = name + ": ground / non-ground";
        add(cli.pngOut, mrpt::topDownPng(cloud, r.labels, ro));
    }
    if (!cli.sceneOut.empty()) add(cli.sceneOut, mrpt::scanSceneBytes(cloud, r.labels, "gseg: " + name));
    std::vector<std::string> paths;
    for (const auto& o : outputs) paths.push_back(o.first);
    io::AtomicFileSet files(paths);
    for (std::size_t i = 0; i < outputs.size(); ++i) files[i].write(outputs[i].second.data(), outputs[i].second.size());
    files.commit();
    for (const auto& path : paths) say("wrote %s\n", path.c_str());
    return 0;
}

}  // namespace

int runSegment(int argc, char** argv) {
    Cli cli;
    tools::CommandLine line("gseg segment", "Label every point of one scan as ground (1) or non-ground (0) with GSeg3D. "
                            "The scan may also be given without -i (old form: gseg segment SCAN).", true);
    TCLAP::CmdLine& cmd = line.cmd();
    TCLAP::ValueArg<std::string> input("i", "input", "the scan: KITTI .bin (float32 x,y,z,intensity), PLY, or MRPT "
                                       "rawlog", false, "", "SCAN", cmd);
    TCLAP::UnlabeledValueArg<std::string> scan("scan", "the scan, old form (same as -i)", false, "", "SCAN", cmd);
    TCLAP::ValueArg<std::string> config("c", "config", "YAML or INI parameter file (default: the library "
                                        "defaults with distToGround: auto, the sensor height estimated)", false, "", "FILE", cmd);
    TCLAP::ValueArg<std::string> labels("", "labels-out", "write one byte per input point, in input order: "
                                        "1 ground, 0 non-ground", false, "", "FILE", cmd);
    TCLAP::ValueArg<std::string> ply("", "ply-out", "write the cloud as binary PLY: x, y, z, the class (scalar_class: "
                                     "1 ground, 2 non-ground; CloudCompare loads it as the scalar field 'class' and "
                                     "filters by it), intensity, colour (green ground, red non-ground) and label "
                                     "(1 ground, 0 non-ground, as --labels-out)", false, "", "FILE", cmd);
    TCLAP::ValueArg<std::string> png("", "png-out", "write a top-down picture of ground and obstacles", false, "",
                                     "FILE", cmd);
    TCLAP::ValueArg<std::string> scene("", "scene-out", "write an MRPT 3D scene (.3Dscene, for SceneViewer3D of "
                                       "mrpt-apps): ground points green, non-ground red", false, "", "FILE", cmd);
    TCLAP::ValueArg<int> index("", "index", "rawlogs: segment the N-th LiDAR observation (0-based; default the "
                               "first)", false, -1, "N", cmd);
    if (const int code = line.parse(argc, argv); code >= 0) return code;
    if (input.getValue().empty() == scan.getValue().empty())
        return line.usageError("give the scan once: -i SCAN (or the old form, gseg segment SCAN)");
    if (index.isSet() && index.getValue() < 0)
        return line.usageError("--index needs N >= 0 (the N-th LiDAR observation of a rawlog, 0-based), got " +
                               std::to_string(index.getValue()));
    cli = {input.getValue().empty() ? scan.getValue() : input.getValue(), config.getValue(), labels.getValue(),
           ply.getValue(), png.getValue(), scene.getValue(), index.getValue()};
    try {
        io::checkOutputs({{"scan", cli.scan}, {"--config", cli.config}},
                         {{"--labels-out", cli.labelsOut}, {"--ply-out", cli.plyOut}, {"--png-out", cli.pngOut},
                          {"--scene-out", cli.sceneOut}},
                         {line.overwrite(), false});
    } catch (const std::invalid_argument&) {
        return tools::reportError("gseg segment", tools::InvalidArgument::BadUsage);
    }
    try {
        return run(cli);
    } catch (...) {
        return tools::reportError("gseg segment", tools::InvalidArgument::BadInput);
    }
}

}  // namespace gseg::app
