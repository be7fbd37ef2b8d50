// gseg segment: label one scan as ground / non-ground.
#include "cli.hpp"
#include "commands.hpp"

#include <gseg/ground_segmenter.hpp>
#include <gseg/sensor_height.hpp>
#include <gseg/io/kitti.hpp>
#include <gseg/io/ply.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/render.hpp>
#include <gseg/mrpt/scan_source.hpp>

#include <cstdio>
#include <exception>

namespace gseg::app {
namespace {

struct Cli {
    std::string scan, config, labelsOut, plyOut, pngOut;
    int index = -1;
};

void printPhase(const char* name, const PhaseReport& r) {
    std::printf("  %s: %zu -> %zu ground points, %zu cells (%zu candidates, %zu ground), %.2f ms "
                "[grid %.2f, classification %.2f, plane fit %.2f, expansion %.2f, refinement %.2f]\n",
                name, r.inputPoints, r.groundPoints, r.occupiedCells, r.candidateCells, r.groundCells, r.ms.total(),
                r.ms.grid, r.ms.classification, r.ms.planeFit, r.ms.expansion, r.ms.refinement);
}

int run(const Cli& cli) {
    mrpt::LoadedConfig cfg;
    if (!cli.config.empty()) cfg = mrpt::loadConfig(cli.config);
    Params params = cfg.params;
    const mrpt::Scan scan = mrpt::loadScan(cli.scan, cli.index);
    const PointCloudView cloud(scan.xyzi.data(), scan.size(), 4 * sizeof(float));
    Result r;
    if (cfg.distToGroundAuto) {
        AutoHeightSegmenter segmenter(params);  // never refuses: falls back to distToGround's default
        r = segmenter.segment(cloud, false);
        std::printf("distToGround auto: %s\n", segmenter.lastDecision().describe().c_str());
    } else {
        r = GroundSegmenter(params).segment(cloud, false);
    }

    std::printf("%s\n", scan.description.c_str());
    std::printf("points %zu, ground %zu (%.1f %%), non-ground %zu; segmentation %.2f ms\n", cloud.size(), r.numGround,
                100.0 * double(r.numGround) / double(cloud.size()), r.numNonGround, r.totalMs);
    printPhase("phase I ", r.phase1);
    printPhase("phase II", r.phase2);

    if (!cli.labelsOut.empty()) io::writeFileAtomic(cli.labelsOut, r.labels.data(), r.labels.size());
    if (!cli.plyOut.empty()) io::writeLabelledPly(cli.plyOut, cloud, r.labels);
    if (!cli.pngOut.empty()) {
        mrpt::RenderOptions ro;
        ro.title = scan.description;
        mrpt::writeTopDownPng(cli.pngOut, cloud, r.labels, ro);
    }
    for (const std::string* out : {&cli.labelsOut, &cli.plyOut, &cli.pngOut})
        if (!out->empty()) std::printf("wrote %s\n", out->c_str());
    return 0;
}

}  // namespace

int runSegment(int argc, char** argv) {
    Cli cli;
    try {
        TCLAP::CmdLine cmd("Label every point of one scan as ground (1) or non-ground (0) with GSeg3D.", ' ', "0.1");
        TCLAP::UnlabeledValueArg<std::string> scan("scan", "KITTI .bin (float32 x,y,z,intensity), PLY, or MRPT rawlog",
                                                   true, "", "SCAN", cmd);
        TCLAP::ValueArg<std::string> config("c", "config", "YAML or INI parameter file (default: library defaults, "
                                            "identical to config/kitti_hdl64.yaml)", false, "", "FILE", cmd);
        TCLAP::ValueArg<std::string> labels("", "labels-out", "write one byte per input point, in input order: "
                                            "1 ground, 0 non-ground", false, "", "FILE", cmd);
        TCLAP::ValueArg<std::string> ply("", "ply-out", "write the cloud coloured by label (green ground, red "
                                         "non-ground) as binary PLY", false, "", "FILE", cmd);
        TCLAP::ValueArg<std::string> png("", "png-out", "write a top-down picture of ground and obstacles", false, "",
                                         "FILE", cmd);
        TCLAP::ValueArg<int> index("", "index", "rawlogs: segment the N-th LiDAR observation (0-based; default the "
                                   "first)", false, -1, "N", cmd);
        if (const int code = parseArgs(cmd, argc, argv); code >= 0) return code;
        cli = {scan.getValue(), config.getValue(), labels.getValue(), ply.getValue(), png.getValue(), index.getValue()};
    } catch (const TCLAP::ArgException& e) {
        std::fprintf(stderr, "gseg segment: %s (%s); see gseg segment --help\n", e.error().c_str(), e.argId().c_str());
        return 2;
    }
    try {
        return run(cli);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "gseg segment: %s\n", e.what());
        return 1;
    }
}

}  // namespace gseg::app
