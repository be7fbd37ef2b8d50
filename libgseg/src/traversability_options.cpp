#include <gseg/option_table.hpp>
#include <gseg/traversability_options.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace gseg::map {
namespace {

const OptionTable<TraversabilityOptions>& table() {
    using O = TraversabilityOptions;
    static const OptionTable<O> t(
        "traversability option",
        {
            {"resolution", &O::resolution, "m", "voxel edge (also the top-down grid cell), 0.01 to 10"},
            {"maxRange", &O::maxRange, "m", "longer rays clear free space up to this range and add no hit"},
            {"probHit", &O::probHit, "-", "occupancy probability of a hit, in (0.5, 1)"},
            {"probMiss", &O::probMiss, "-", "occupancy probability of a ray passing through, in (0, 0.5)"},
            {"clampMin", &O::clampMin, "-", "lower clamping of the occupancy probability, in (0, 0.5)"},
            {"clampMax", &O::clampMax, "-", "upper clamping, in (0.5, 1) (lower: quicker clearing of moved obstacles)"},
            {"occupancyThreshold", &O::occupancyThreshold, "-", "a voxel is occupied above this probability, in (0, 1)"},
            {"clearance", &O::clearance, "m",
             "obstacle voxels higher than this above the column's ground do not block it (branches, bridges); the robot's minimum clearance"},
            {"minGroundPoints", &O::minGroundPoints, "points", "ground points (whole drive) a cell needs for an elevation, >= 1"},
            {"maxSlope", &O::maxSlope, "deg", "steepest ground slope that is traversable, in (0, 90)"},
            {"slopeRadius", &O::slopeRadius, "m",
             "where the plane through a cell and its 8 neighbours is steeper than maxSlope and no obstacle voxel lower than "
             "clearance above the cell stands within this radius, the plane through the cells within it judges (a rough "
             "surface's bumps averaged at the robot's scale), [0, 10] and at most 50 cells (below 2 cells: the 3 x 3 plane alone)"},
            {"maxStep", &O::maxStep, "m", "largest height jump (up or down) to a neighbouring cell that is traversable, > 0"},
            {"maxRoughness", &O::maxRoughness, "m", "largest standard deviation of a cell's ground heights that is traversable, > 0"},
            {"maxGroundRise", &O::maxGroundRise, "m",
             "a cell whose elevation lies more than this above the lowest elevation within groundRiseRadius is not traversable "
             "(flat tops of hedges and bushes the segmenter calls ground); > groundRiseRadius * tan(maxSlope)"},
            {"groundRiseRadius", &O::groundRiseRadius, "m", "radius of the neighbourhood of maxGroundRise, (0, 100] and at most 200 cells (below the resolution: the cell alone)"},
            {"obstacleClearProbability", &O::obstacleClearProbability, "-",
             "an obstacle voxel once hit stays an obstacle in the layers and costmap until its occupancy probability falls to this "
             "or below (porous vegetation and fences stay, what moved away is cleared), in (0, occupancyThreshold]"},
            {"minObstacleHeight", &O::minObstacleHeight, "m",
             "obstacle voxels lower than this above the cell's ground do not block it (the step rule judges them), >= 0"},
            {"driveTerrain", &O::driveTerrain, "-",
             "cells without ground points get the ground the drive's terrain model grows from confident ground (several scans) and "
             "the scans' lowest returns (false: only the ground the scans found)"},
            {"terrainTolerance", &O::terrainTolerance, "m",
             "a cell's lowest returns within this of the ground predicted from the modelled cells around it join the model, > 0"},
            {"terrainRadius", &O::terrainRadius, "m", "modelled cells within this predict a cell's ground, > 0 (used as at least one cell and at most 50)"},
            {"terrainSparseRadius", &O::terrainSparseRadius, "m",
             "where fewer than 3 modelled cells lie within terrainRadius (a sparse sensor's rings far out), the modelled cells within "
             "this predict a cell's ground, > 0 (used as at least terrainRadius and at most 50 cells)"},
            {"terrainMinScans", &O::terrainMinScans, "scans", "scans that must agree on a cell before it anchors or joins the terrain model, >= 1"},
            {"terrainPointTolerance", &O::terrainPointTolerance, "m",
             "labels with the drive's context (rawlog-gseg, gseg eval on drives, Python): a non-ground point within this of its "
             "cell's modelled ground becomes ground, > 0"},
            {"terrainStandHeight", &O::terrainStandHeight, "m",
             "... unless a return of any scan in its cell or the 8 around stands more than this above that ground (the foot of a "
             "wall, fence, car or bush), > terrainPointTolerance"},
            {"terrainFootHeight", &O::terrainFootHeight, "m",
             "... and where such a return stands, a ground point more than this above that ground becomes non-ground (the foot of a "
             "wall, fence or car the segmenter took for ground), > 0"},
            {"fillGaps", &O::fillGaps, "-",
             "an unknown cell between traversable cells becomes traversable (layer source = 2) where the ground interpolates within "
             "maxStep and maxSlope, rays passed over it and none below it"},
            {"maxGapWidth", &O::maxGapWidth, "m", "widest gap filled (wider ones, ditches among them, stay unknown), > 0 (used as at most 50 cells)"},
        });
    return t;
}

/// [cells] the largest groundRiseRadius / resolution (a disc of about 126,000 cells looked at per cell).
constexpr double kMaxGroundRiseCells = 200;
/// [cells] the largest slopeRadius / resolution (a disc of about 7,900 cells, for the cells steeper than maxSlope).
constexpr double kMaxSlopeCells = 50;

/// lo < v < hi (or lo <= v <= hi with `inclusive`).
void requireInRange(double v, const char* name, double lo, double hi, bool inclusive = false) {
    const bool ok = inclusive ? (v >= lo && v <= hi) : (v > lo && v < hi);
    if (!ok) {
        std::ostringstream s;
        s << "TraversabilityOptions." << name << " = " << v << ": must lie in " << (inclusive ? "[" : "(") << lo << ", "
          << hi << (inclusive ? "]" : ")");
        throw std::invalid_argument(s.str());
    }
}

}  // namespace

void TraversabilityOptions::validate() const {
    requireInRange(resolution, "resolution [m]", 0.01, 10.0, true);
    if (!(maxRange >= resolution)) {
        std::ostringstream s;  // %g: 1e-300 must not read as 0.000000
        s << "TraversabilityOptions.maxRange = " << maxRange << ": must be at least the resolution (" << resolution
          << " m; a shorter ray leaves the map empty)";
        throw std::invalid_argument(s.str());
    }
    if (maxRange / resolution > kMaxRayVoxels)
        throw std::invalid_argument("TraversabilityOptions: maxRange / resolution = " + std::to_string(maxRange) + " / " +
                                    std::to_string(resolution) + " gives rays of " + std::to_string(long(maxRange / resolution)) +
                                    " voxels: at most " + std::to_string(long(kMaxRayVoxels)));
    requireInRange(probHit, "probHit", 0.5, 1.0);
    requireInRange(probMiss, "probMiss", 0.0, 0.5);
    requireInRange(clampMin, "clampMin", 0.0, 0.5);
    requireInRange(clampMax, "clampMax", 0.5, 1.0);
    requireInRange(occupancyThreshold, "occupancyThreshold", 0.0, 1.0);
    if (!(clearance > 0)) throw std::invalid_argument("TraversabilityOptions.clearance = " + std::to_string(clearance) + ": must be > 0 m");
    if (minGroundPoints < 1)
        throw std::invalid_argument("TraversabilityOptions.minGroundPoints = " + std::to_string(minGroundPoints) + ": must be >= 1");
    requireInRange(maxSlope, "maxSlope [deg]", 0.0, 90.0);
    requireInRange(slopeRadius, "slopeRadius [m]", 0.0, 10.0, true);
    if (slopeRadius / resolution > kMaxSlopeCells) {
        std::ostringstream s;
        s << "TraversabilityOptions.slopeRadius = " << slopeRadius << " m at resolution " << resolution << " m is a disc of "
          << long(slopeRadius / resolution) << " cells' radius: at most " << kMaxSlopeCells << " (lower slopeRadius or raise the resolution)";
        throw std::invalid_argument(s.str());
    }
    if (!(maxStep > 0)) throw std::invalid_argument("TraversabilityOptions.maxStep = " + std::to_string(maxStep) + ": must be > 0 m");
    if (!(maxRoughness > 0))
        throw std::invalid_argument("TraversabilityOptions.maxRoughness = " + std::to_string(maxRoughness) + ": must be > 0 m");
    // Below the resolution the neighbourhood is the cell alone (no rise): accepted, so a coarse
    // --resolution is not refused for a default radius the user never set. Its cost grows with
    // (radius / resolution)^2 per cell: bounded in cells.
    if (!(groundRiseRadius > 0 && groundRiseRadius <= 100))
        throw std::invalid_argument("TraversabilityOptions.groundRiseRadius = " + std::to_string(groundRiseRadius) +
                                    ": must lie in (0, 100] m");
    if (groundRiseRadius / resolution > kMaxGroundRiseCells) {
        std::ostringstream s;
        s << "TraversabilityOptions.groundRiseRadius = " << groundRiseRadius << " m at resolution " << resolution << " m is a disc of "
          << long(groundRiseRadius / resolution) << " cells' radius per cell: at most " << kMaxGroundRiseCells
          << " (its time grows with the square; lower groundRiseRadius or raise the resolution)";
        throw std::invalid_argument(s.str());
    }
    if (!(maxGroundRise > groundRiseRadius * std::tan(maxSlope * 3.14159265358979323846 / 180.0)))
        throw std::invalid_argument("TraversabilityOptions.maxGroundRise = " + std::to_string(maxGroundRise) +
                                    ": must exceed groundRiseRadius * tan(maxSlope) = " +
                                    std::to_string(groundRiseRadius * std::tan(maxSlope * 3.14159265358979323846 / 180.0)) +
                                    " m (a ramp within maxSlope would be refused)");
    if (!(obstacleClearProbability > 0 && obstacleClearProbability <= occupancyThreshold))
        throw std::invalid_argument("TraversabilityOptions.obstacleClearProbability = " + std::to_string(obstacleClearProbability) +
                                    ": must lie in (0, occupancyThreshold]");
    if (!(terrainTolerance > 0 && std::isfinite(terrainTolerance)))
        throw std::invalid_argument("TraversabilityOptions.terrainTolerance = " + std::to_string(terrainTolerance) + ": must be > 0 m");
    if (!(terrainRadius > 0 && std::isfinite(terrainRadius)))
        throw std::invalid_argument("TraversabilityOptions.terrainRadius = " + std::to_string(terrainRadius) + ": must be > 0 m");
    if (!(terrainSparseRadius > 0 && std::isfinite(terrainSparseRadius)))
        throw std::invalid_argument("TraversabilityOptions.terrainSparseRadius = " + std::to_string(terrainSparseRadius) + ": must be > 0 m");
    if (terrainMinScans < 1)
        throw std::invalid_argument("TraversabilityOptions.terrainMinScans = " + std::to_string(terrainMinScans) + ": must be >= 1");
    if (!(terrainPointTolerance > 0 && std::isfinite(terrainPointTolerance)))
        throw std::invalid_argument("TraversabilityOptions.terrainPointTolerance = " + std::to_string(terrainPointTolerance) + ": must be > 0 m");
    if (!(terrainStandHeight > terrainPointTolerance && std::isfinite(terrainStandHeight)))
        throw std::invalid_argument("TraversabilityOptions.terrainStandHeight = " + std::to_string(terrainStandHeight) +
                                    ": must exceed terrainPointTolerance");
    if (!(terrainFootHeight > 0 && std::isfinite(terrainFootHeight)))
        throw std::invalid_argument("TraversabilityOptions.terrainFootHeight = " + std::to_string(terrainFootHeight) + ": must be > 0 m");
    if (!(maxGapWidth > 0 && std::isfinite(maxGapWidth)))
        throw std::invalid_argument("TraversabilityOptions.maxGapWidth = " + std::to_string(maxGapWidth) + ": must be > 0 m");
    if (!(minObstacleHeight >= 0 && minObstacleHeight < clearance))
        throw std::invalid_argument("TraversabilityOptions.minObstacleHeight = " + std::to_string(minObstacleHeight) +
                                    ": must lie in [0, clearance) m");
}

const std::vector<std::string>& TraversabilityOptions::keys() { return table().names(); }

void TraversabilityOptions::set(const std::string& key, const std::string& value) { table().set(*this, key, value); }

std::string TraversabilityOptions::get(const std::string& key) const { return table().get(*this, key); }

std::pair<std::string, std::string> TraversabilityOptions::describe(const std::string& key) { return table().describe(key); }

}  // namespace gseg::map
