#pragma once
/// \file traversability_options.hpp
/// How scans are fused into gseg's traversability maps (gseg::map::TraversabilityMap). A plain
/// options struct with a key table (gseg/option_table.hpp), in the core so that every configuration
/// loader can read and check it.

#include <gseg/terrain_model.hpp>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

namespace gseg::map {

/// How scans are fused. Probabilities are OctoMap's (log-odds update per scan and voxel).
struct TraversabilityOptions {
    double resolution = 0.2;          ///< [m] voxel edge (also the top-down grid cell), 0.01 to 10
    double maxRange = 50.0;           ///< [m] longer rays clear free space up to this range and add no hit
    double probHit = 0.7;             ///< [-] occupancy probability of a hit
    double probMiss = 0.4;            ///< [-] occupancy probability of a ray passing through
    double clampMin = 0.12;           ///< [-] lower clamping of the occupancy probability
    double clampMax = 0.97;           ///< [-] upper clamping (lower: quicker clearing of moved obstacles)
    double occupancyThreshold = 0.5;  ///< [-] a voxel is occupied above this probability
    double clearance = 2.0;           ///< [m] obstacle voxels higher than this above the column's ground do not block it (branches, bridges); also the robot's minimum clearance
    // ---- the 2.5D layers and the costmap (gseg/map/terrain_layers.hpp); defaults for a car-sized robot ----
    int minGroundPoints = 3;          ///< [points] ground points (whole drive) a cell needs for an elevation, >= 1
    double maxSlope = 20.0;           ///< [deg] steepest ground a cell may have and be traversable, (0, 90)
    double slopeRadius = 0.5;         ///< [m] where the plane through a cell and its 8 neighbours is steeper than maxSlope and no obstacle voxel lower than clearance above the cell stands within this, the plane through the cells within this judges (rough ground's bumps averaged at the robot's scale), [0, 10] and at most 50 cells (below 2 cells: the 3 x 3 plane alone)
    double maxStep = 0.25;            ///< [m] largest height jump (up or down) to a neighbouring cell that is traversable, > 0
    double maxRoughness = 0.1;        ///< [m] largest standard deviation of a cell's ground heights that is traversable, > 0
    double maxGroundRise = 0.38;      ///< [m] a cell whose elevation lies more than this above the lowest elevation within groundRiseRadius is not traversable (flat tops of hedges and bushes the segmenter calls ground); > groundRiseRadius * tan(maxSlope)
    double groundRiseRadius = 1.0;    ///< [m] radius of the neighbourhood of maxGroundRise, (0, 100] and at most 200 cells (below the resolution: the cell alone)
    double obstacleClearProbability = 0.12;  ///< [-] in the layers and costmap an obstacle voxel once hit stays an obstacle until its occupancy probability falls to this or below (porous vegetation and fences stay; what moved away is cleared), in (0, occupancyThreshold]
    double minObstacleHeight = 0.3;   ///< [m] obstacle voxels whose centre lies lower than this above the cell's ground do not block it (the step rules judge it), >= 0
    // ---- the drive's terrain model (#31, gseg/terrain_model.hpp) and gap filling in the layers ----
    bool driveTerrain = true;         ///< cells without ground points get the ground the drive's terrain model grows from confident ground and the scans' lowest returns
    double terrainTolerance = 0.1;    ///< [m] a cell's lowest returns (or a point) within this of the ground predicted from the model around it join the model, > 0
    double terrainRadius = 2.0;       ///< [m] modelled cells within this predict a cell's ground, > 0 (used as at least one cell and at most 50: terrainOptions())
    double terrainSparseRadius = 3.0; ///< [m] where fewer than 3 modelled cells lie within terrainRadius (a sparse sensor's rings far out), those within this predict, > 0 (used as at least terrainRadius and at most 50 cells: terrainOptions())
    int terrainMinScans = 1;          ///< [scans] scans that must agree on a cell before it anchors or joins the model, >= 1
    double terrainPointTolerance = 0.05;  ///< [m] labels with the drive's context (rawlog-gseg, gseg eval on drives, Python): a non-ground point within this of its cell's modelled ground becomes ground, > 0
    double terrainStandHeight = 0.3;  ///< [m] ... unless a return of any scan in its cell or the 8 around stands more than this above that ground (the foot of a wall, fence, car or bush), > terrainPointTolerance
    double terrainFootHeight = 0.08;  ///< [m] ... and where such a return stands, a ground point more than this above that ground becomes non-ground (the foot of a wall, fence or car the segmenter took for ground), > 0
    bool fillGaps = true;             ///< an unknown cell between traversable cells (ring stripes) becomes traversable (layer `source` = 2) where the ground interpolates within maxStep and maxSlope, rays passed over it and none below it
    double maxGapWidth = 1.5;         ///< [m] widest gap filled (wider ones, ditches among them, stay unknown), > 0 (used as at most 50 cells: gapWidth())
    /// Throws std::invalid_argument naming the first invalid field (also a ray longer than
    /// kMaxRayVoxels voxels: maxRange / resolution).
    void validate() const;
    /// The keys (the field names, in declaration order), as in YAML `traversability:` and the
    /// plugin's `_creationOpts` INI section.
    static const std::vector<std::string>& keys();
    /// Sets a field from text; throws std::invalid_argument on an unknown key or an unreadable value.
    void set(const std::string& key, const std::string& value);
    std::string get(const std::string& key) const;  ///< the field as text (set() reads it back)
    /// [unit, meaning] of a key (for --help and the README), e.g. {"m", "voxel edge ..."}.
    static std::pair<std::string, std::string> describe(const std::string& key);
    /// [m] the maps span -extent() .. +extent() on each axis (OctoMap's 16-bit keys: 32768 voxels
    /// each side of the origin); points outside are skipped, a sensor outside is an error.
    double extent() const { return 32768.0 * resolution; }
    static constexpr double kMaxRayVoxels = 5000;  ///< longest ray, in voxels
    /// [m] the widest gap filled: maxGapWidth, at most 50 cells (each unknown cell's search is bounded).
    double gapWidth() const { return std::min(maxGapWidth, 50 * resolution); }
    /// The terrain model's options at the map's resolution.
    gseg::TerrainOptions terrainOptions() const {
        gseg::TerrainOptions t;
        t.cellSize = resolution, t.tolerance = terrainTolerance, t.minScans = terrainMinScans;
        t.supportRadius = std::min(std::max(terrainRadius, resolution), 50 * resolution);  // the search window's cost is bounded
        t.sparseRadius = std::min(std::max(terrainSparseRadius, t.supportRadius), 50 * resolution);
        t.pointTolerance = terrainPointTolerance, t.standHeight = terrainStandHeight, t.footHeight = terrainFootHeight;
        t.minAnchorPoints = minGroundPoints, t.maxSlope = maxSlope;
        return t;
    }
};

}  // namespace gseg::map
