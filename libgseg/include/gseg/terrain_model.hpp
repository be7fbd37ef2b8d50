#pragma once
/// \file terrain_model.hpp
/// The terrain a drive has seen (#31): per world-frame cell, the ground elevation the segmenter
/// found in every scan that saw the cell, with its spread and support, and the lowest returns of
/// each scan; from them a model of the ground that reaches past what single scans call ground.
///
/// Evidence (TerrainModel::add(), one scan's TerrainSample list at a time, in scan order):
/// - *anchors*: cells where at least `minScans` scans found ground (Result::labels) and at least
///   `minAnchorPoints` ground points fell; their elevation is the mean height of those points;
/// - *candidates*: other cells whose lowest return (any label) was seen by at least `minScans`
///   scans, the per-scan lowest returns within 2 x `tolerance` of each other; their height is the
///   mean of those lowest returns (GroundGrid's evidence: the lowest return per cell over scans).
///
/// build() grows the model from the anchors: a candidate joins where the least-squares plane of the
/// modelled cells within `supportRadius` (at least `minSupport` of them; where fewer lie there,
/// those within `sparseRadius`) predicts its height within
/// `tolerance` and it lies within tolerance + cellSize x tan(maxSlope) of each modelled cell among
/// its 8 neighbours, in waves (each wave judged against the model at its start, so the result does not
/// depend on the order cells are visited), until no candidate joins. A hedge, a car or a wall has
/// its lowest returns well above the plane of the ground around it and stays out.
///
/// Frame: world (map) frame, metres, z up; cell (ix, iy) = (floor(x / cellSize), floor(y / cellSize)),
/// the OctoMap column of the map at the same resolution. Memory: tiles of 32 x 32 cells allocated
/// where samples land (never a grid over the bounding box). The same samples in the same scan
/// order give the same model (sums in scan order; waves independent of visiting order).

#include <gseg/point_cloud.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <unordered_map>
#include <vector>

namespace gseg {

/// How the drive's terrain model is built and used.
struct TerrainOptions {
    double cellSize = 0.2;       ///< [m] cell edge (the map route uses the map resolution)
    double tolerance = 0.1;      ///< [m] a candidate within this of the predicted ground joins the model
    double supportRadius = 2.0;  ///< [m] modelled cells within this predict a candidate's height
    double sparseRadius = 3.0;   ///< [m] where fewer than `minSupport` modelled cells lie within supportRadius (a sparse sensor's rings far out), those within this predict (used as at least supportRadius)
    int minScans = 1;            ///< [scans] scans that must agree on a cell (anchor or candidate), >= 1
    int minAnchorPoints = 3;     ///< [points] ground points (all scans) an anchor needs, >= 1
    int minSupport = 3;          ///< [cells] modelled cells a prediction needs, >= 1
    double maxSlope = 20;        ///< [deg] a candidate also lies within tolerance + cellSize x tan(maxSlope) of each modelled cell beside it (a kerb's face between two levels stays out), in (0, 90)
    double pointTolerance = 0.05;  ///< [m] relabel(): a non-ground point within this of its cell's modelled ground becomes ground
    double standHeight = 0.3;    ///< [m] relabel() leaves a point alone where a return of any scan in its cell or the 8 around stands more than this above the cell's modelled ground (the foot of a wall, a fence, a car, a bush), > tolerance
    double footHeight = 0.08;    ///< [m] relabel(): a ground point more than this above its cell's modelled ground, where such a return stands beside it (the foot of a wall, fence or car), becomes non-ground, > 0
    /// Throws std::invalid_argument naming the first invalid field.
    void validate() const;
};

/// What one scan says about one cell (terrainSamples()).
struct TerrainSample {
    std::int32_t ix = 0, iy = 0;     ///< cell index
    std::uint32_t groundCount = 0;   ///< ground points of the scan in the cell
    double groundSumZ = 0;           ///< [m] sum of their heights
    float lowZ = 0;                  ///< [m] lowest return of the scan in the cell (any label)
    float highZ = 0;                 ///< [m] highest return of the scan in the cell (any label)

    bool operator==(const TerrainSample& o) const {
        return ix == o.ix && iy == o.iy && groundCount == o.groundCount && groundSumZ == o.groundSumZ &&
               lowZ == o.lowZ && highZ == o.highZ;
    }
};

/// The samples of one scan: its ground and non-ground points in the world frame (NaN points and
/// points farther than `maxRange` from `origin` skipped), by cell of `cellSize`, sorted by (ix, iy).
/// Throws std::invalid_argument on a non-positive cell size.
std::vector<TerrainSample> terrainSamples(const PointCloudView& ground, const PointCloudView& nonGround, double cellSize,
                                          double maxRange = std::numeric_limits<double>::infinity(),
                                          const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());
/// The same from one scan's points and its labels (1: ground, 0: not, anything else: left out,
/// e.g. a reflection below the ground), without
/// copying the points apart; the same samples as the form above given the ground and the other
/// points in input order. Throws std::invalid_argument if the sizes differ.
std::vector<TerrainSample> terrainSamples(const PointCloudView& points, const std::vector<std::uint8_t>& labels, double cellSize,
                                          double maxRange = std::numeric_limits<double>::infinity(),
                                          const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/// One cell of the model.
struct TerrainCell {
    enum State : std::uint8_t { None = 0, Anchor = 1, Grown = 2 };
    std::uint32_t groundScans = 0;  ///< scans that found ground here
    std::uint32_t lowScans = 0;     ///< scans with a return here
    std::uint32_t groundCount = 0;  ///< ground points, all scans
    double groundSumZ = 0;          ///< [m] sum of their heights
    double lowSum = 0;              ///< [m] sum of the scans' lowest returns
    float lowMin = std::numeric_limits<float>::infinity(), lowMax = -std::numeric_limits<float>::infinity();  ///< [m] of the scans' lowest returns
    float highMax = -std::numeric_limits<float>::infinity();   ///< [m] highest return of any scan
    float elevation = std::numeric_limits<float>::quiet_NaN();  ///< [m] modelled ground (after build()), NaN where none
    State state = None;
};

/// The drive's terrain: evidence per cell, and the model build() grows from it.
class TerrainModel {
public:
    /// Throws std::invalid_argument on invalid options.
    explicit TerrainModel(const TerrainOptions& options = TerrainOptions());
    ~TerrainModel();
    TerrainModel(TerrainModel&&) noexcept;
    TerrainModel& operator=(TerrainModel&&) noexcept;

    const TerrainOptions& options() const { return options_; }

    /// One scan's samples (terrainSamples() with this model's cell size), in scan order.
    void add(const std::vector<TerrainSample>& samples);
    /// Marks the anchors and grows the model (again from the evidence if called again).
    void build();

    /// The cell holding (x, y), or nullptr where no sample landed.
    const TerrainCell* cellAt(double x, double y) const { return find(index(x), index(y)); }
    const TerrainCell* find(std::int32_t ix, std::int32_t iy) const;
    /// [m] modelled ground at (x, y) (its cell's), NaN where not modelled.
    float elevationAt(double x, double y) const {
        const TerrainCell* c = cellAt(x, y);
        return c ? c->elevation : std::numeric_limits<float>::quiet_NaN();
    }
    std::int32_t index(double v) const { return std::int32_t(std::floor(v / options_.cellSize)); }

    /// Turns non-ground points (labels 0) lying within `pointTolerance` of their cell's modelled ground
    /// into ground (1), except where a return of any scan in the cell or its 8 neighbours stands
    /// more than `standHeight` above that ground; where such a return stands, ground points (1)
    /// lying more than `footHeight` above that ground become non-ground (0): the foot of a wall, a
    /// fence or a car the segmenter took for ground. Other labels (2: reflections) stay. `points` in
    /// the world frame, one label per point; returns how many changed (both ways; `promoted`, if
    /// given, gets how many became ground). Throws std::invalid_argument if the sizes differ.
    std::size_t relabel(const PointCloudView& points, std::vector<std::uint8_t>& labels, std::size_t* promoted = nullptr) const;

    /// Calls f(ix, iy, cell) for every modelled cell (state Anchor or Grown, after build()), in a
    /// fixed order (tile by tile, sorted).
    void forEachModelled(const std::function<void(std::int32_t ix, std::int32_t iy, const TerrainCell& cell)>& f) const;

    /// Drops the tiles lying wholly farther than `radius` (horizontally) from (x, y), with their
    /// evidence: a stream's rolling model (DriveTerrain) keeps memory to the area around the sensor.
    /// Returns the tiles dropped.
    std::size_t forgetFartherThan(double x, double y, double radius);

    std::size_t cells() const { return cells_; }           ///< cells with evidence
    std::size_t anchors() const { return anchors_; }       ///< after build()
    std::size_t grown() const { return grown_; }           ///< after build(): candidates that joined
    std::size_t tiles() const { return tiles_.size(); }
    std::size_t bytes() const;                             ///< memory of the tiles
    std::size_t scans() const { return scans_; }           ///< add() calls

    static constexpr int kTileBits = 5;  ///< tiles of 2^5 x 2^5 cells

private:
    struct Tile;
    TerrainCell* findMutable(std::int32_t ix, std::int32_t iy);
    template <class F>
    void forEachCell(F&& f);

    TerrainOptions options_;
    std::unordered_map<std::uint64_t, std::unique_ptr<Tile>> tiles_;
    std::size_t cells_ = 0, anchors_ = 0, grown_ = 0, scans_ = 0;
};

}  // namespace gseg
