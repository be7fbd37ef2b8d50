// gseg eval-map: a 2D map (ROS map_server YAML + PGM) of a labelled KITTI drive scored against the
// labels, beside the label-free height-band baseline (the rules of ../shared/tools/score_map.py).
#include "commands.hpp"
#include "common/cli.hpp"

#include <gseg/io/atomic_file.hpp>
#include <gseg/io/output_checks.hpp>
#include <gseg/io/ros_map.hpp>
#include <gseg/map/layer_file.hpp>
#include <gseg/eval/map_score.hpp>
#include <gseg/mrpt/picture.hpp>
#include <gseg/progress.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace gseg::app {
namespace {

struct EvalMapCli {
    std::string drive, map, elevation, report;
    double clearance = 2.0;
    bool overwrite = false;
};

/// The figures of the run, the map's and the baseline's.
struct EvalMapResult {
    map::MapScore map, band;
    bool hasElevation = false;
    map::ElevationError elevation;
};

std::string figure(double v, const char* format = "%.2f") {
    if (std::isnan(v)) return "-";
    char buf[48];
    std::snprintf(buf, sizeof buf, format, v);
    return buf;
}

/// The table printed: one row per figure, the map and the baseline side by side.
std::string tableText(const EvalMapResult& r) {
    std::string out;
    char line[160];
    auto row = [&](const char* name, double a, double b, const char* unit) {
        std::snprintf(line, sizeof line, "%-30s %10s %12s   %s\n", name, figure(a).c_str(), figure(b).c_str(), unit);
        out += line;
    };
    std::snprintf(line, sizeof line, "%-30s %10s %12s\n", "", "map", "height band");
    out += line;
    row("traversable precision", r.map.travPrecision, r.band.travPrecision, "% of free cells truly traversable");
    row("traversable recall", r.map.travRecall, r.band.travRecall, "% of traversable cells called free");
    row("traversable F1", r.map.travF1, r.band.travF1, "%");
    row("obstacle recall", r.map.obstacleRecall, r.band.obstacleRecall, "% of obstacle cells called occupied");
    row("unsafe", r.map.unsafe, r.band.unsafe, "% of obstacle cells called free");
    row("unsafe beyond 1 cell", r.map.unsafeBeyondCell, r.band.unsafeBeyondCell, "% of obstacle cells free with no occupied neighbour");
    std::snprintf(line, sizeof line, "%-30s %10zu %12zu   cells with a truth (traversable or obstacle)\n", "cells scored",
                  r.map.cellsScored, r.band.cellsScored);
    out += line;
    std::snprintf(line, sizeof line, "%-30s %10zu %12zu   of those, called free or occupied\n", "cells seen", r.map.cellsSeen,
                  r.band.cellsSeen);
    out += line;
    if (r.hasElevation) {
        std::snprintf(line, sizeof line, "elevation: RMSE %.3f m, %.1f %% within 0.1 m (%zu cells over labelled ground)\n",
                      r.elevation.rmse, r.elevation.within10cm, r.elevation.cells);
        out += line;
    }
    return out;
}

/// PREFIX_map_score.csv: a row for the map and one for the baseline, score_map.py's JSON names,
/// then the cells per outcome (the picture's colours).
std::string scoreCsv(const EvalMapResult& r) {
    std::string out =
        "scored,trav_P,trav_R,trav_F1,obst_R,unsafe,unsafe1,cells_scored,cells_seen,trav_found,trav_unknown,trav_blocked,"
        "obst_found,obst_unknown,unsafe_within_1_cell,unsafe_beyond_1_cell,elev_rmse,elev_within_10cm,elev_cells\n";
    auto row = [&](const char* name, const map::MapScore& s, bool elevation) {
        char buf[512];
        std::snprintf(buf, sizeof buf, "%s,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%zu,%zu", name, s.travPrecision, s.travRecall, s.travF1,
                      s.obstacleRecall, s.unsafe, s.unsafeBeyondCell, s.cellsScored, s.cellsSeen);
        out += buf;
        for (std::size_t n : s.outcomes) out += "," + std::to_string(n);
        if (elevation) {
            std::snprintf(buf, sizeof buf, ",%.4f,%.4f,%zu\n", r.elevation.rmse, r.elevation.within10cm, r.elevation.cells);
            out += buf;
        } else {
            out += ",,,\n";
        }
    };
    row("map", r.map, r.hasElevation);
    row("height_band", r.band, false);
    return out;
}

std::vector<std::string> reportPaths(const std::string& prefix) {
    io::checkOutputPrefix(prefix);
    return {prefix + "_map_score.csv", prefix + "_map_cells.png"};
}

int run(const EvalMapCli& cli) {
    const io::RosMap rosMap = io::readRosMap(cli.map);
    map::LayerGrid layers;
    if (!cli.elevation.empty()) {
        layers = map::readLayersGeoTiff(cli.elevation);
        try {
            map::elevationLayer(layers);
        } catch (const std::exception& e) {
            throw std::runtime_error(cli.elevation + ": " + e.what());
        }
    }
    Progress progress(tools::progressOut(), "gseg eval-map", "scans");
    const map::LabelledDrive drive = map::readLabelledDrive(cli.drive, [&](std::size_t done, std::size_t total) {
        progress.update(done, double(done) / double(total));
    });
    progress.finish(drive.frames);
    // The stages after reading show what they do: on fine cells they take minutes (SemanticKITTI 00
    // on 0.01 m cells: about 8 minutes), which a silent run cannot be told from a hung one.
    char stage[200];
    std::snprintf(stage, sizeof stage, "gseg eval-map: the truth of %zu labelled points on %.3g m cells%s", drive.points.size(), rosMap.resolution,
                  rosMap.resolution < 0.05 ? " (cells finer than 0.05 m: this and the scoring may take minutes)" : "");
    progress.message(stage);
    Progress cells(tools::progressOut(), "gseg eval-map", "cells");  // the truth's cells: minutes on fine cells
    const map::DriveTruth truth = map::computeTruth(drive, map::gridOf(rosMap), cli.clearance, [&](std::size_t done, std::size_t total) {
        cells.update(done, double(done) / double(total));
    });
    cells.finish(truth.cells.size());
    if (truth.cells.empty())
        throw std::runtime_error(cli.drive + ": no cell of the drive has a truth (no labelled ground or obstacle)");
    EvalMapResult r;
    map::CellOutcomes outcomes;
    progress.message("gseg eval-map: scoring " + std::to_string(truth.cells.size()) + " cells with a truth");
    r.map = map::scoreMap(truth, rosMap, &outcomes);
    r.band = map::scoreHeightBand(truth);
    if (!cli.elevation.empty()) {
        try {
            r.elevation = map::elevationError(layers, truth), r.hasElevation = true;
        } catch (const std::exception& e) {
            throw std::runtime_error(cli.elevation + ": " + e.what());
        }
    }
    tools::say("%s against %s: %zu scans, %zu labelled points (%zu read), %.2f m cells, clearance %.2f m\n",
               mrpt::displayName(cli.map).c_str(), cli.drive.c_str(), drive.frames, drive.points.size(), drive.pointsRead,
               rosMap.resolution, cli.clearance);
    tools::say("%s", tableText(r).c_str());
    if (!cli.report.empty()) {
        const std::string png = map::encodeMapScorePng(
            truth, outcomes, "gseg eval-map: " + mrpt::displayName(cli.map) + " against " + fs::path(cli.drive).filename().string());
        const std::string csv = scoreCsv(r);
        if (const fs::path dir = fs::path(cli.report).parent_path(); !dir.empty()) fs::create_directories(dir);
        io::AtomicFileSet set(reportPaths(cli.report));  // the report is this run's or the previous one's, whole
        set[0].write(csv.data(), csv.size());
        set[1].write(png.data(), png.size());
        set.commit();
        tools::say("wrote %s_map_score.csv, %s_map_cells.png\n", cli.report.c_str(), cli.report.c_str());
    }
    return tools::kDone;
}

}  // namespace

int runEvalMap(int argc, char** argv) {
    tools::CommandLine line(
        "gseg eval-map",
        "Score a 2D traversability map (ROS map_server YAML + binary PGM, in the frame of the drive's first scan as "
        "kitti2rawlog writes it) against a labelled KITTI drive (DRIVE/velodyne/*.bin, labels/*.label, poses.txt, "
        "calib.txt with Tr) under the rules of score_map.py: truth per map cell from the labelled points of every "
        "scan (obstacle: >= 2 non-ground points 0.3 m to --clearance above the cell's ground; traversable: >= 3 "
        "ground points and no obstacle; other cells not scored), and the same figures for a label-free height band "
        "(octomap_server's projected map) on the same grid. The inputs may also be given as -i DRIVE --map MAP.yaml.",
        true);
    TCLAP::CmdLine& cmd = line.cmd();
    TCLAP::ValueArg<std::string> input("i", "input", "the labelled drive folder (a SemanticKITTI sequence)", false, "", "DRIVE", cmd);
    TCLAP::ValueArg<std::string> mapArg("", "map", "the map's YAML (map_server format)", false, "", "MAP.yaml", cmd);
    TCLAP::UnlabeledMultiArg<std::string> positional("inputs", "DRIVE MAP.yaml (positional form)", false, "DRIVE MAP.yaml", cmd);
    TCLAP::ValueArg<double> clearance("", "clearance", "[m] top of the obstacle band above a cell's ground (the robot's "
                                      "height; default 2)", false, 2.0, "M", cmd);
    TCLAP::ValueArg<std::string> elevation("", "elevation", "also the elevation error: the layer 'elevation' of this "
                                           "GeoTIFF (rawlog-octomap's PREFIX_layers.tif) against the median height of "
                                           "the labelled ground per cell (cells with >= 3 ground points): RMSE [m] and "
                                           "the share within 0.1 m", false, "", "LAYERS.tif", cmd);
    TCLAP::ValueArg<std::string> report("", "report", "write PREFIX_map_score.csv (the figures, and the cells per "
                                        "outcome) and PREFIX_map_cells.png (the scored cells, top view); the folder "
                                        "is made if missing", false, "", "PREFIX", cmd);
    if (const int code = line.parse(argc, argv); code >= 0) return code;
    EvalMapCli cli;
    cli.drive = input.getValue(), cli.map = mapArg.getValue();
    std::vector<std::string> rest = positional.getValue();
    if (cli.drive.empty() && !rest.empty()) cli.drive = rest.front(), rest.erase(rest.begin());
    if (cli.map.empty() && !rest.empty()) cli.map = rest.front(), rest.erase(rest.begin());
    if (cli.drive.empty() || cli.map.empty() || !rest.empty())
        return line.usageError("give the drive and the map once each: gseg eval-map DRIVE MAP.yaml (or -i DRIVE --map MAP.yaml)");
    cli.clearance = clearance.getValue(), cli.report = report.getValue(), cli.elevation = elevation.getValue(), cli.overwrite = line.overwrite();
    if (!(std::isfinite(cli.clearance) && cli.clearance > 0.3 && cli.clearance <= 100))
        return line.usageError("--clearance must be above 0.3 m (the obstacle band's bottom) and at most 100 m");
    try {
        std::vector<io::NamedPath> outputs;
        if (!cli.report.empty())
            for (const std::string& p : reportPaths(cli.report)) outputs.push_back({"--report", p});
        io::checkOutputs({{"map", cli.map}, {"drive", cli.drive}, {"--elevation", cli.elevation}}, outputs, {cli.overwrite, true});
    } catch (...) {
        return tools::reportError("gseg eval-map", tools::InvalidArgument::BadUsage);
    }
    try {
        return run(cli);
    } catch (...) {
        return tools::reportError("gseg eval-map", tools::InvalidArgument::BadInput);
    }
}

}  // namespace gseg::app
