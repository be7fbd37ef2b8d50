#include <gseg/io/kitti.hpp>
#include <gseg/io/ply.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/observation_points.hpp>
#include <gseg/mrpt/rawlog_io.hpp>
#include <gseg/mrpt/scan_source.hpp>
#include <gseg/text.hpp>

#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CSensoryFrame.h>

#include <algorithm>
#include <stdexcept>

namespace gseg::mrpt {
namespace {

Scan fromRawlog(const std::string& path, int index) {
    Scan scan;
    int seen = 0;
    const int wanted = std::max(0, index);
    bool found = false;
    auto consider = [&](std::size_t entry, const ::mrpt::obs::CObservation& obs) {
        if (!isLidarObservation(obs) || seen++ != wanted) return;
        scan.description = "rawlog entry " + std::to_string(entry) + ": " + obs.GetRuntimeClass()->className + " '" +
                           obs.sensorLabel + "'";
        try {
            scan.xyzi = levelledPoints(obs);
        } catch (const std::exception& e) {
            throw std::runtime_error(path + ": rawlog entry " + std::to_string(entry) + ": " + errorReason(e));
        }
        found = true;
    };
    forEachRawlogEntry(path, [&](std::size_t entry, const auto& obj) {
        if (const auto obs = std::dynamic_pointer_cast<::mrpt::obs::CObservation>(obj)) {
            consider(entry, *obs);
        } else if (const auto sf = std::dynamic_pointer_cast<::mrpt::obs::CSensoryFrame>(obj)) {
            for (const auto& o : *sf)
                if (o && !found) consider(entry, *o);
        }
        return !found;
    });
    if (!found) {
        if (seen == 0) throw std::runtime_error(path + ": no 3D LiDAR observation in this rawlog");
        throw std::runtime_error(path + ": --index " + std::to_string(index) + " is past the last LiDAR observation (" +
                                 std::to_string(seen) + " found)");
    }
    return scan;
}

}  // namespace

Scan loadScan(const std::string& path, int index) {
    const std::string name = lowercase(path);
    if (endsWith(name, ".bin")) return {gseg::io::readKittiBin(path), "KITTI scan " + path};
    if (endsWith(name, ".ply")) return {gseg::io::readPly(path), "PLY cloud " + path};
    if (endsWith(name, ".rawlog") || endsWith(name, ".gz")) return fromRawlog(path, index);
    throw std::runtime_error(path + ": unknown scan format (expected .bin, .ply, .rawlog or .rawlog.gz)");
}

}  // namespace gseg::mrpt
