#include <gseg/map/memory_policy.hpp>

#include <gseg/map/map_builder.hpp>
#include <gseg/map/world_scan.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace gseg::map {

std::string memoryOptionsText(const TraversabilityOptions& options) {
    char text[120];
    std::snprintf(text, sizeof text, " (at --resolution %g m, --max-range %g m)", options.resolution, options.maxRange);
    return text;
}

std::string outOfMemoryMessage(const std::string& what, const TraversabilityOptions& options) {
    const std::string head = what.rfind("out of memory while ", 0) == 0 ? what : "out of memory while " + what;
    return head + memoryOptionsText(options) + "; nothing written";
}

MemoryGuard::MemoryGuard(const ScanJob& first, const ScanJob* second, std::size_t workers, std::size_t inFlight,
                         const TraversabilityOptions& options, const MapOutputOptions& outputs, double maxMemory)
    : options_(options), outputs_(outputs) {
    std::vector<float> points;
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    try {
        for (const auto* part : {&first.raw, &first.ground, &first.obstacles})
            if (*part && (part != &first.raw || !first.presegmented()))
                origin = appendWorldPoints(**part, first.robotPose, points);
    } catch (const std::invalid_argument&) {
        return;  // a scan the builder will skip and name (e.g. a 2D scan): nothing to estimate from
    }
    const RayFootprint f = rayFootprint(PointCloudView(points.data(), points.size() / 3), origin, options);
    // The scans of the drive, from the bytes of the rawlog the second scan took.
    const double step = second ? second->fraction - first.fraction : 0;
    const std::size_t scans = !second ? 1 : step > 0 ? std::size_t(std::lround(std::min(1e9, 2 + (1 - second->fraction) / step))) : 2;
    const MemoryEstimate estimate = estimateMemory(f);
    const double need = estimate.peak(workers, inFlight, std::max<std::size_t>(1, scans));
    MemoryLimit limit = memoryLimit();
    if (maxMemory > 0 && (maxMemory < limit.bytes || limit.machine))  // the user's word, within ulimit's
        limit = {maxMemory, "--max-memory", false};
    char line[600];
    std::snprintf(line, sizeof line, "memory estimated from %s: %s for about %zu scans%s; limit %s (%s)",
                  first.describe().c_str(), formatBytes(need).c_str(), scans, memoryOptionsText(options).c_str(),
                  formatBytes(limit.bytes).c_str(), limit.what.c_str());
    estimateLine_ = line;
    if (need > limit.bytes) {
        char text[400];
        std::snprintf(text, sizeof text, "--resolution %g m needs about %s for the maps and ray casting (estimated from "
                      "%s: %zu points, rays up to --max-range %g m, about %zu scans), more than %s (%s); use a coarser "
                      "--resolution or a shorter --max-range%s", options.resolution, formatBytes(need).c_str(),
                      first.describe().c_str(), f.rays, options.maxRange, scans, limit.what.c_str(),
                      formatBytes(limit.bytes).c_str(), limit.what == "--max-memory" ? "" : ", or give --max-memory");
        refusal_ = text;
        return;
    }
    known_ = true, estimate_ = estimate, workers_ = workers, inFlight_ = inFlight, scans_ = std::max<std::size_t>(1, scans), limit_ = limit;
}

void MemoryGuard::refuseIfTooBig() const {
    if (!refusal_.empty()) throw std::runtime_error(refusal_);
}

void MemoryGuard::add(std::size_t k, const ScanResult& r) {
    if (!known_ || !r.skipped.empty()) return;
    const double before = box_.cells(), tilesBefore = box_.tiles();
    box_.add(r.update);
    if (haveOrigin_) {
        const double jump = (r.update.origin - lastOrigin_).norm();
        if (jump > jump_) jump_ = jump, jumpScan_ = k;
    }
    haveOrigin_ = true, lastOrigin_ = r.update.origin;
    if (box_.cells() == before && box_.tiles() == tilesBefore) return;
    const double layers = layerBytes(), needed = need(layers);
    if (needed <= limit_.bytes) return;
    const double res = options_.resolution;
    char text[800];
    std::snprintf(text, sizeof text, "the scans up to %s cover %.0f m x %.0f m (x from %.1f m, y from %.1f m; %.0f tiles "
                  "of 64 x 64 cells seen): the 2.5D layers need about %s at --resolution %g m%s (%s with the maps), more "
                  "than %s (%s); the largest step between two scans is %.0f m (to scan %zu): %s",
                  r.describe.c_str(), box_.cellsX() * res, box_.cellsY() * res, box_.minX(res), box_.minY(res), box_.tiles(),
                  formatBytes(layers).c_str(), res, tiled() ? ", written as tiles" : ", written as one grid of the box",
                  formatBytes(needed).c_str(), limit_.what.c_str(), formatBytes(limit_.bytes).c_str(), jump_, jumpScan_,
                  advice().c_str());
    throw std::runtime_error(std::string(text) + (limit_.what == "--max-memory" ? "" : ", or give --max-memory"));
}

std::string MemoryGuard::summary() const {
    char text[240];
    std::snprintf(text, sizeof text, "%s with writing (%s while integrating, maps %s, layers in %.0f tiles over a box of "
                  "%.0f x %.0f cells, %s: %s)", formatBytes(need(layerBytes())).c_str(),
                  formatBytes(estimate_.peak(workers_, inFlight_, scans_)).c_str(), formatBytes(estimate_.maps(scans_)).c_str(),
                  box_.tiles(), box_.cellsX(), box_.cellsY(), tiled() ? "tiled" : "one grid", formatBytes(layerBytes()).c_str());
    return text;
}

bool MemoryGuard::tiled() const { return outputs_.tiled(std::int64_t(box_.cellsX()), std::int64_t(box_.cellsY())); }

double MemoryGuard::layerBytes() const {
    const MapOutputOptions& o = outputs_;
    const double dense = tiled() ? double(o.pictureSide) * o.pictureSide + double(o.costmapTile) * o.costmapTile : box_.cells();
    return gseg::map::layerBytes(box_.tiles(), dense, o.writers);
}

std::string MemoryGuard::advice() const {
    const MapOutputOptions& o = outputs_;
    const double dense = gseg::map::layerBytes(0, tiled() ? 0 : box_.cells());
    if (!tiled() && dense > gseg::map::layerBytes(box_.tiles(), 0)) {
        char text[200];
        std::snprintf(text, sizeof text, "write the map as tiles (--tiles, or --tiled-above below %d cells, the box's %.0f "
                      "x %.0f cells)", o.tiledAbove, box_.cellsX(), box_.cellsY());
        return text;
    }
    return jump_ > 100 ? "do the poses jump? Fix them, or map the parts of the drive separately, or use a coarser --resolution"
                       : "use a coarser --resolution, or map the drive in parts";
}

}  // namespace gseg::map
