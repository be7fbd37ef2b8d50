#include <gseg/drive_terrain.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace gseg {

DriveTerrain::DriveTerrain(const TerrainOptions& options, double maxRange, double keepRadius)
    : model_(options), maxRange_(maxRange), keepRadius_(keepRadius > 0 ? keepRadius : maxRange + 2 * options.supportRadius) {
    if (!(maxRange > 0)) throw std::invalid_argument("DriveTerrain: maxRange = " + std::to_string(maxRange) + ": must be > 0 m");
    if (!std::isfinite(keepRadius_)) throw std::invalid_argument("DriveTerrain: keepRadius must be finite");
}

std::size_t DriveTerrain::label(const PointCloudView& world, std::vector<std::uint8_t>& labels, const Eigen::Vector3d& sensor,
                                std::size_t* promoted) {
    if (labels.size() != world.size())
        throw std::invalid_argument("DriveTerrain::label: " + std::to_string(labels.size()) + " labels for " +
                                    std::to_string(world.size()) + " points");
    // The evidence of this scan is the segmenter's, taken before relabelling.
    const std::vector<TerrainSample> samples = terrainSamples(world, labels, model_.options().cellSize, maxRange_, sensor);
    if (promoted) *promoted = 0;
    const std::size_t changed = model_.scans() ? model_.relabel(world, labels, promoted) : 0;
    model_.forgetFartherThan(sensor.x(), sensor.y(), keepRadius_);
    model_.add(samples);
    model_.build();
    return changed;
}

namespace {

/// `relabel(labels)` on the labels of `result` with its reflections marked 2 (left alone), the
/// counts then updated.
template <class F>
std::size_t onResult(Result& result, std::size_t* promotedOut, F&& relabel) {
    for (const std::uint32_t i : result.belowGround) result.labels.at(i) = 2;
    std::size_t promoted = 0;
    const std::size_t changed = relabel(result.labels, promoted);  // both ways
    for (const std::uint32_t i : result.belowGround) result.labels[i] = 0;
    const std::size_t demoted = changed - promoted;
    result.numGround = result.numGround + promoted - demoted;
    result.numNonGround = result.numNonGround + demoted - promoted;
    if (promotedOut) *promotedOut = promoted;
    return changed;
}

}  // namespace

std::vector<TerrainSample> terrainSamples(const PointCloudView& world, const Result& result, double cellSize, double maxRange,
                                          const Eigen::Vector3d& sensor) {
    std::vector<std::uint8_t> labels = result.labels;
    for (const std::uint32_t i : result.belowGround) labels.at(i) = 2;  // reflections: no evidence
    return terrainSamples(world, labels, cellSize, maxRange, sensor);
}

std::size_t DriveTerrain::label(const PointCloudView& world, Result& result, const Eigen::Vector3d& sensor, std::size_t* promoted) {
    return onResult(result, promoted, [&](std::vector<std::uint8_t>& labels, std::size_t& up) { return label(world, labels, sensor, &up); });
}

std::size_t relabelWithModel(const TerrainModel& model, const PointCloudView& world, Result& result, std::size_t* promoted) {
    return onResult(result, promoted, [&](std::vector<std::uint8_t>& labels, std::size_t& up) { return model.relabel(world, labels, &up); });
}

}  // namespace gseg
