#pragma once
/// \file map_score.hpp
/// Scores a 2D traversability map of a labelled KITTI drive against the drive's labels, under
/// exactly the rules of `../shared/tools/score_map.py` (the protocol of issue #19):
///
/// - Points: every frame of the drive (`velodyne/NNNNNN.bin` with `labels/NNNNNN.label`, frame
///   NNNNNN using line NNNNNN of `poses.txt`) in the map frame, the velodyne frame of the first
///   scan: Tr^-1 P_k Tr (gseg/map/poses.hpp). Unlabelled (0), outlier (1) and moving (>= 252)
///   points are left out; road, parking, sidewalk, other-ground, lane marking and terrain (40, 44,
///   48, 49, 60, 72) are ground.
/// - Truth per map cell: the reference height is the median z of the cell's ground points when it
///   has at least 3, else the median of those medians of the cells within 1 m (round(1 m / cell)
///   cells each way, at least 1), else the lowest point of the cell. Obstacle where at least 2
///   non-ground points lie strictly between ref + 0.3 m and ref + clearance; traversable where the
///   cell has at least 3 ground points and is no obstacle; otherwise unknown (not scored).
/// - A prediction per cell: free, occupied or unknown (outside the map: unknown).
/// - Figures: traversable precision / recall / F1 (a free obstacle cell is a false traversable),
///   obstacle recall, unsafe = obstacle cells predicted free, and those with no occupied cell
///   among their 8 neighbours (what a one-cell inflation still misses), in % of obstacle cells.
/// - The label-free baseline on the same grid (octomap_server's projected map): occupied where at
///   least 2 points lie between -1.73 + 0.3 m and -1.73 m + clearance (z, map frame), free where the
///   cell has points but not so, unknown where it has none.
/// - Elevation error: the map's elevation layer against the median z of the labelled ground
///   points of each truth cell with at least 3: RMSE and the share within 0.1 m.
///
/// "Median" is score_map.py's: the element n / 2 of the sorted values (the upper one of an even count).

#include <gseg/io/ros_map.hpp>
#include <gseg/map/layer_grid.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <unordered_map>
#include <vector>

namespace gseg::map {

/// One labelled point of a drive, in the map frame.
struct LabelledPoint {
    double x = 0, y = 0, z = 0;  ///< [m] map frame (velodyne frame of the first scan)
    std::uint16_t label = 0;     ///< SemanticKITTI class (the lower 16 bits of the .label entry)
};

/// The labelled points of a drive that score_map.py keeps (ignored classes left out).
struct LabelledDrive {
    std::vector<LabelledPoint> points;
    std::size_t frames = 0;       ///< scans read
    std::size_t pointsRead = 0;   ///< points in the scans, ignored ones included
};

/// True for the classes score_map.py leaves out: unlabelled (0), outlier (1), moving (>= 252).
bool ignoredClass(std::uint32_t label);
/// True for the ground classes: road 40, parking 44, sidewalk 48, other-ground 49, lane marking
/// 60, terrain 72.
bool groundClass(std::uint32_t label);

/// Reads a labelled KITTI drive folder (`velodyne/*.bin`, `labels/*.label`, `poses.txt`,
/// `calib.txt` with `Tr`): each scan's points in the map frame, in frame order (file names
/// sorted). `progress(done, total)` is called after each frame (may be empty). Memory: 32 bytes
/// per labelled point (computeTruth() about 40 more while it runs): ten HDL-64 scans, 40 MB. Throws
/// std::runtime_error naming the file: no velodyne/ folder or no scans in it, a scan whose name is
/// not a frame number, a missing `Tr`, fewer poses than the frame numbers need, a missing label
/// file or one whose count differs from its scan, a point whose x, y or z is not finite.
LabelledDrive readLabelledDrive(const std::string& sequenceDir,
                                const std::function<void(std::size_t, std::size_t)>& progress = {});

/// The grid a map is scored on: cell (cx, cy) covers x in [originX + cx * resolution, ...), y likewise.
struct ScoreGrid {
    double resolution = 0.2;          ///< [m]
    double originX = 0, originY = 0;  ///< [m] map frame
    long long cellX(double x) const;  ///< floor((x - originX) / resolution)
    long long cellY(double y) const;
};

/// The truth of one cell.
enum class TruthClass : std::uint8_t { Traversable = 1, Obstacle = 2 };

/// The truth of a drive on a grid, and what the baseline needs.
struct DriveTruth {
    ScoreGrid grid;
    double clearance = 2.0;  ///< [m] the obstacle band's top above the cell's ground
    struct Cell {
        long long cx = 0, cy = 0;
        TruthClass truth = TruthClass::Traversable;
    };
    std::vector<Cell> cells;  ///< the scored cells (traversable or obstacle), sorted by (cx, cy)
    /// [m] median z of the labelled ground points per cell with at least 3 (key: cellKey()).
    std::unordered_map<std::uint64_t, double> groundHeight;
    /// Points (ignored classes out) per cell with any, and those in the baseline's height band.
    struct Seen {
        std::uint32_t points = 0, inBand = 0;
    };
    std::unordered_map<std::uint64_t, Seen> seen;

    /// The key of cell (cx, cy) in the maps above (cells within +-2^31 of the origin).
    static std::uint64_t cellKey(long long cx, long long cy);
};

/// Truth per cell of `grid` from the drive's points; `clearance` [m] > 0.3. Throws
/// std::invalid_argument on a bad grid or clearance, or a point more than 2^31 cells from the origin.
/// `progress(done, total)`: called every 4096 cells of the truth's last pass (the one that takes
/// minutes on fine cells) and at its end; may be empty.
DriveTruth computeTruth(const LabelledDrive& drive, const ScoreGrid& grid, double clearance = 2.0,
                        const std::function<void(std::size_t, std::size_t)>& progress = {});

/// What a map says about a cell.
enum class Prediction : std::uint8_t { Unknown = 0, Free = 1, Occupied = 2 };

/// How a scored cell came out (the picture's colours).
enum class CellOutcome : std::uint8_t {
    TraversableFound,         ///< truth traversable, predicted free
    TraversableUnknown,       ///< truth traversable, predicted unknown (or outside the map)
    TraversableBlocked,       ///< truth traversable, predicted occupied
    ObstacleFound,            ///< truth obstacle, predicted occupied
    ObstacleUnknown,          ///< truth obstacle, predicted unknown
    FalseTraversable,         ///< truth obstacle, predicted free, an occupied cell among its 8 neighbours
    FalseTraversableBeyond,   ///< truth obstacle, predicted free, no occupied neighbour: unsafe beyond one cell
};
constexpr int kCellOutcomes = 7;

/// The figures of one map (score_map.py's JSON names in brackets). Percentages are NaN where
/// their denominator is 0 (as score_map.py's).
struct MapScore {
    double travPrecision = 0;     ///< [%] free cells that are traversable (trav_P)
    double travRecall = 0;        ///< [%] traversable cells predicted free (trav_R)
    double travF1 = 0;            ///< [%] (trav_F1; 0 where P + R = 0)
    double obstacleRecall = 0;    ///< [%] obstacle cells predicted occupied (obst_R)
    double unsafe = 0;            ///< [%] obstacle cells predicted free (unsafe)
    double unsafeBeyondCell = 0;  ///< [%] of those, no occupied cell among the 8 neighbours (unsafe1)
    std::size_t cellsScored = 0;  ///< truth cells (cells_scored)
    std::size_t cellsSeen = 0;    ///< truth cells the map predicts free or occupied (cells_seen)
    std::size_t outcomes[kCellOutcomes] = {};  ///< cells per CellOutcome
};

/// The per-cell outcomes of a scoring (same order as DriveTruth::cells).
using CellOutcomes = std::vector<CellOutcome>;

/// Scores `predict(cx, cy)` on the truth; `outcomes` (if not null) gets each cell's.
MapScore scorePredictions(const DriveTruth& truth, const std::function<Prediction(long long, long long)>& predict,
                          CellOutcomes* outcomes = nullptr);
/// The map's cells under its thresholds (the truth must be on the map's grid).
MapScore scoreMap(const DriveTruth& truth, const io::RosMap& map, CellOutcomes* outcomes = nullptr);
/// The label-free height-band baseline on the truth's grid.
MapScore scoreHeightBand(const DriveTruth& truth, CellOutcomes* outcomes = nullptr);

/// The scoring grid of a map.
ScoreGrid gridOf(const io::RosMap& map);

/// The elevation error of a layer grid against the labelled ground.
struct ElevationError {
    double rmse = 0;        ///< [m]
    double within10cm = 0;  ///< [%] cells within 0.1 m
    std::size_t cells = 0;  ///< layer cells compared
};
/// Name of the layer compared: "elevation" if there is one, else the first whose name contains
/// "elev" (any case), as score_map.py picks the band. Throws std::runtime_error if none.
const LayerGrid::Layer& elevationLayer(const LayerGrid& layers);
/// Each layer cell with a finite elevation whose centre falls in a truth cell with a ground height
/// (>= 3 labelled ground points) gives one error, layer - truth. Throws std::runtime_error when no
/// layer or no cell compares.
ElevationError elevationError(const LayerGrid& layers, const DriveTruth& truth);

/// The top-down picture of the scored cells (one colour per CellOutcome, in the legend; on the
/// map page of gseg/map/map_page.hpp: x right, y up as the costmap PGM; scale bar and axes), as PNG bytes. `title` is the first line.
std::string encodeMapScorePng(const DriveTruth& truth, const CellOutcomes& outcomes, const std::string& title);
/// Colour of an outcome in the picture, and its legend text.
struct OutcomeStyle {
    std::uint8_t r, g, b;
    const char* text;
};
OutcomeStyle outcomeStyle(CellOutcome c);

}  // namespace gseg::map
