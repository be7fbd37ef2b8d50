#pragma once
/// \file drive_terrain.hpp
/// Labels with the drive's context for streams (#31): the causal form of the drive's terrain
/// model. Each scan, given with its points in the world frame, is relabelled with the model of the
/// scans before it (TerrainModel::relabel()), then its own samples (from the segmenter's labels,
/// not the relabelled ones: the evidence stays the segmenter's confident ground) join the model,
/// which is built again. Only earlier scans count, so a stream (an MRPT observation filter, Python)
/// labels each scan as it comes. Memory: the model keeps the tiles within `keepRadius` of the
/// latest sensor position (a rolling model), so it follows the area around the sensor, not the drive.
///
/// The offline tools (rawlog-gseg, gseg eval on drives) use the model of the whole drive instead:
/// TerrainModel directly, pass 1 adding every scan, pass 2 relabelling.

#include <gseg/ground_segmenter.hpp>
#include <gseg/point_cloud.hpp>
#include <gseg/terrain_model.hpp>

#include <Eigen/Geometry>

#include <cstdint>
#include <vector>

namespace gseg {

class DriveTerrain {
public:
    /// `maxRange`: [m] points farther from the sensor add no evidence (the maps' maxRange);
    /// `keepRadius`: [m] evidence farther than this from the latest sensor position is dropped
    /// (0: maxRange + 2 x options.supportRadius, enough for every cell a scan's points fall in).
    /// Throws std::invalid_argument on invalid options.
    explicit DriveTerrain(const TerrainOptions& options, double maxRange = 50, double keepRadius = 0);

    /// One scan, in stream order: `world` its points in the world frame (x, y, z; NaN allowed),
    /// `labels` the segmenter's (1 ground, 0 not; any other value: a point left alone, e.g. a
    /// reflection below the ground), `sensor` the sensor's position. Relabels the scan with the
    /// model of the earlier scans (TerrainModel::relabel(): ground found, feet of what stands
    /// dropped), then adds the scan. Returns the points relabelled (both ways; `promoted`, if given,
    /// gets those turned ground). Throws std::invalid_argument if the sizes differ.
    std::size_t label(const PointCloudView& world, std::vector<std::uint8_t>& labels, const Eigen::Vector3d& sensor,
                      std::size_t* promoted = nullptr);

    /// The same on a segmenter's Result (its labels and counts; its reflections, belowGround, are
    /// neither evidence nor relabelled).
    std::size_t label(const PointCloudView& world, Result& result, const Eigen::Vector3d& sensor, std::size_t* promoted = nullptr);

    const TerrainModel& model() const { return model_; }
    std::size_t scans() const { return model_.scans(); }

private:
    TerrainModel model_;
    double maxRange_, keepRadius_;
};

/// The evidence of one scan from a segmenter's Result (terrainSamples() on its labels; its
/// reflections, belowGround, left out): what DriveTerrain adds, for a first pass that builds a
/// whole drive's model. Throws std::invalid_argument if the sizes differ.
std::vector<TerrainSample> terrainSamples(const PointCloudView& world, const Result& result, double cellSize, double maxRange,
                                          const Eigen::Vector3d& sensor);

/// The offline form on a segmenter's Result: `model` (built from the whole drive) relabels the
/// scan whose points in the world frame are `world` (TerrainModel::relabel()); reflections
/// (belowGround) stay non-ground; the counts follow. Returns the points relabelled (both ways;
/// `promoted`, if given, gets those turned ground).
std::size_t relabelWithModel(const TerrainModel& model, const PointCloudView& world, Result& result, std::size_t* promoted = nullptr);

}  // namespace gseg
