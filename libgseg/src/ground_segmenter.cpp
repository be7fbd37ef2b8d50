#include <gseg/below_ground.hpp>
#include <gseg/cell_classifier.hpp>
#include <gseg/grid.hpp>
#include <gseg/ground_segmenter.hpp>
#include <gseg/plane_fit.hpp>
#include <gseg/region_growing.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <tuple>
#include <utility>
#include <stdexcept>

namespace gseg {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point& t) {
    const auto now = Clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - t).count();
    t = now;
    return ms;
}

void checkCloud(const PointCloudView& cloud) {
    if (cloud.empty()) throw std::invalid_argument("gseg: the point cloud is empty");
    if (cloud.strideBytes() < 3 * sizeof(float))
        throw std::invalid_argument("gseg: point stride must be at least 12 bytes (x, y, z floats)");
    if (cloud.size() > std::numeric_limits<std::uint32_t>::max())
        throw std::invalid_argument("gseg: more than 2^32-1 points in one cloud");
}

bool finitePoint(const float* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

// Writes the indices of the points of `cloud` whose x, y and z are finite, ascending, into
// out[0..), which has room for every point; returns how many. (Written unconditionally, kept where
// finite: no branch per point; in SSE2 four points are tested at once where a point follows the
// fourth (each read as 16 bytes: x * 0 is NaN exactly where x is not finite), and only a group
// holding a point that is not finite is tested point by point.)
std::size_t finiteIndices(const PointCloudView& cloud, std::uint32_t* out) {
    const std::uint32_t n = std::uint32_t(cloud.size());
    std::size_t count = 0;
    std::uint32_t i = 0;
#if defined(__SSE2__)
    const __m128 zero = _mm_setzero_ps();
    const __m128i step = _mm_setr_epi32(0, 1, 2, 3);
    for (; i + 4 < n; i += 4) {
        const __m128 a = _mm_mul_ps(_mm_loadu_ps(cloud.point(i)), zero);
        const __m128 b = _mm_mul_ps(_mm_loadu_ps(cloud.point(i + 1)), zero);
        const __m128 c = _mm_mul_ps(_mm_loadu_ps(cloud.point(i + 2)), zero);
        const __m128 d = _mm_mul_ps(_mm_loadu_ps(cloud.point(i + 3)), zero);
        const __m128 any = _mm_add_ps(_mm_add_ps(a, b), _mm_add_ps(c, d));  // NaN in lane k: some point's coordinate k
        if ((_mm_movemask_ps(_mm_cmpunord_ps(any, any)) & 7) == 0) {
            _mm_storeu_si128(reinterpret_cast<__m128i*>(out + count), _mm_add_epi32(_mm_set1_epi32(int(i)), step));
            count += 4;
            continue;
        }
        for (std::uint32_t k = i; k < i + 4; ++k) {
            out[count] = k;
            count += finitePoint(cloud.point(k)) ? 1 : 0;
        }
    }
#endif
    for (; i < n; ++i) {
        out[count] = i;
        count += finitePoint(cloud.point(i)) ? 1 : 0;
    }
    return count;
}

std::uint64_t cellSeed(std::uint64_t base, const GridCell& c, int phase) {
    std::uint64_t s = base ^ (std::uint64_t(std::uint32_t(c.ix)) * 0x9E3779B97F4A7C15ull);
    s ^= std::uint64_t(std::uint32_t(c.iy)) * 0xC2B2AE3D27D4EB4Full;
    s ^= std::uint64_t(std::uint32_t(c.iz)) * 0x165667B19E3779F9ull;
    s ^= std::uint64_t(phase) << 61;
    return splitmix64(s);
}

// Bounding-box volume per point [m^3] of the masked points (mask 1: first) and of the unmasked
// ones (mask 0: second), in one pass.
// (The boxes' corners in registers, each updated or kept without a branch: AlignedBox::extend's
// min and max, the same values.)
std::pair<double, double> volumesPerPoint(const Eigen::Vector3f* pts, const std::uint8_t* mask, std::size_t n) {
    constexpr float hi = std::numeric_limits<float>::max(), lo = std::numeric_limits<float>::lowest();  // an empty box
    float inMin[3] = {hi, hi, hi}, inMax[3] = {lo, lo, lo}, outMin[3] = {hi, hi, hi}, outMax[3] = {lo, lo, lo};
    std::size_t mIn = 0, mOut = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const bool in = mask[i] == 1, out = mask[i] == 0;
        for (int a = 0; a < 3; ++a) {
            const float v = pts[i][a];
            inMin[a] = in ? std::min(inMin[a], v) : inMin[a];
            inMax[a] = in ? std::max(inMax[a], v) : inMax[a];
            outMin[a] = out ? std::min(outMin[a], v) : outMin[a];
            outMax[a] = out ? std::max(outMax[a], v) : outMax[a];
        }
        mIn += in, mOut += out;
    }
    const auto perPoint = [](const float* mn, const float* mx, std::size_t m) {
        const Eigen::AlignedBox3f box(Eigen::Vector3f(mn[0], mn[1], mn[2]), Eigen::Vector3f(mx[0], mx[1], mx[2]));
        return m == 0 ? 0.0 : double(box.volume()) / double(m);
    };
    return {perPoint(inMin, inMax, mIn), perPoint(outMin, outMax, mOut)};
}

// The sum of the points pts[0..n) whose mask is non-zero (mask null: every point), in float, in
// the points' order: Eigen's `sum += p`, each coordinate in an SSE lane (the lane after z holds
// whatever follows a point and is never read).
Eigen::Vector3f floatSum(const Eigen::Vector3f* pts, std::size_t n, const std::uint8_t* mask) {
#if defined(__SSE2__)
    __m128 sum = _mm_setzero_ps();
    for (std::size_t i = 0; i + 1 < n; ++i)  // a point follows: one 16-byte load
        if (!mask || mask[i]) sum = _mm_add_ps(sum, _mm_loadu_ps(pts[i].data()));
    if (n > 0 && (!mask || mask[n - 1])) {  // the last point: nothing past it is read
        const float* p = pts[n - 1].data();
        const __m128 xy = _mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)));
        sum = _mm_add_ps(sum, _mm_movelh_ps(xy, _mm_load_ss(p + 2)));
    }
    alignas(16) float a[4];
    _mm_store_ps(a, sum);
    return Eigen::Vector3f(a[0], a[1], a[2]);
#else
    Eigen::Vector3f sum = Eigen::Vector3f::Zero();
    for (std::size_t i = 0; i < n; ++i)
        if (!mask || mask[i]) sum += pts[i];
    return sum;
#endif
}

// The z range of the points of one Phase I cell that Phase I did not accept.
struct RejectedSpan {
    std::uint32_t column;  // the cell's column id (ColumnIndex: shared by both phases, in (ix, iy) order)
    float low, high;       // [m]
};

// Per-cell working state of one phase.
struct CellState {
    CellClass cellClass = CellClass::TooFewPoints;
    CellOutcome outcome = CellOutcome::TooFewPoints;
    std::uint32_t inliers = 0;
    bool ambiguous = false;
    bool recovered = false;
    bool steepNormal = false;  // planar cell whose PCA normal is steeper than the slope limit
    std::int32_t candidate = -1;  // index among the expansion's candidates (-1: not a candidate)  // Phase I: not ground, but `inliers` of its points lie on a neighbour's ground plane
    Eigen::Vector3f ground = Eigen::Vector3f::Zero();  // centroid of the ground candidates
    Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();  // ground-plane normal (z > 0): the height gate's direction
};

}  // namespace

struct detail::Workspace {
    // One grid per phase (its points(): the points grouped by cell, aligned with order()), so that
    // neither shrinks the other's buffers (a vector grown again is filled again); `grid`: the
    // current phase's (after run(): Phase II's).
    Grid phaseGrids[2];
    Grid* grid = &phaseGrids[0];
    ColumnIndex columns;                  // the columns (ix, iy) of the finite points, shared by both phases
    std::vector<std::uint32_t> input, phase1Ground, phase2Ground;
    std::vector<std::uint32_t> inputColumns;          // the column id of each point of input, in its order
    std::vector<Eigen::Vector3f> phase1GroundPoints;  // the points of phase1Ground (Phase II's input), in its order
    std::vector<std::uint32_t> phase1GroundColumns;   // their column ids
    std::vector<std::uint8_t> inlier;  // plane inlier flag, aligned with grid.order()
    std::vector<std::uint8_t> cellMask;  // the plane fit's scratch: a cell's inlier mask
    PlaneFitScratch planeFit;
    std::vector<CellState> cells;
    std::vector<PointMoments> moments;  // per cell that the plane fit takes: its points' mean and scatter matrix (the classification's)
    std::vector<std::uint32_t> candidateCell;  // candidate -> cell
    std::vector<Eigen::Vector3f> centroids;    // candidate ground centroids (the expansion's points)
    // Per Phase I cell, in the grid's order (so by column id): the z range of its points Phase I
    // called non-ground (cells too small to classify excepted). Phase II sees only Phase I's
    // ground, so this is how it knows what stands below its cells.
    std::vector<RejectedSpan> rejected;
    std::vector<std::uint32_t> rejectedStart;  // per column id c: the spans of c are rejected[rejectedStart[c] .. rejectedStart[c + 1])
    std::vector<Eigen::Vector3f> normals;  // per candidate (aligned with centroids)
    std::vector<std::int32_t> parents;     // per candidate: the candidate it was reached from (expandRegion)
    BelowGroundScratch belowGround;
    std::vector<std::uint8_t> groundInColumn;  // per column id: it holds a ground cell (Phase I's recovery)
    std::vector<GroundColumn> groundColumns;  // flagBelowGround: the lowest ground of each Phase II ground cell
};

GroundSegmenter::GroundSegmenter(const Params& params) : params_(params), ws_(std::make_unique<detail::Workspace>()) {
    params_.validate();
}
GroundSegmenter::~GroundSegmenter() = default;
GroundSegmenter::GroundSegmenter(GroundSegmenter&&) noexcept = default;
GroundSegmenter& GroundSegmenter::operator=(GroundSegmenter&&) noexcept = default;

namespace {

/// What differs between the two phases, built once per scan from Params.
struct PhaseSettings {
    int number = 1;            ///< 1 or 2: mixed into the per-cell RANSAC seeds
    double cellSizeZ = 0;      ///< [m] cell height
    double heightGate = 0;     ///< [m] expansion's height gate (tau; infinite: none)
    bool recover = false;      ///< recover the points of non-ground cells on a ground neighbour's plane (ours, after the authors' implementation)
    bool recoverSparseOnly = false;  ///< recover only the points of cells too small to classify
    double recoveryThreshold = 0;    ///< [m] point-to-plane distance of a recovered point
    bool bridges = false;      ///< the expansion builds bridges (Params::bridgeRadius and its keys)
    bool recordRejected = false;  ///< record per cell the z range of the points this phase rejected (for the next phase)
    bool belowRejected = false;   ///< a cell above a point the previous phase rejected is floating

    /// Phase I: tall cells over the whole cloud, no height gate.
    static PhaseSettings first(const Params& p) {
        PhaseSettings s;
        s.number = 1;
        s.cellSizeZ = p.cellSizeZPhase1;
        s.heightGate = std::numeric_limits<double>::infinity();
        s.recover = p.recoverNearGround;
        s.recoveryThreshold = p.recoveryThreshold;
        s.recordRejected = true;
        return s;
    }
    /// Phase II: thin cells over Phase I's ground, with the height gate.
    static PhaseSettings second(const Params& p) {
        PhaseSettings s;
        s.number = 2;
        s.cellSizeZ = p.cellSizeZPhase2;
        s.heightGate = p.heightGate;
        s.belowRejected = true;
        s.recover = p.sparseRecoveryThreshold > 0;  // their points are final ground
        s.recoverSparseOnly = true;
        s.recoveryThreshold = p.sparseRecoveryThreshold;
        s.bridges = true;
        return s;
    }
};

/// What a phase reads: the points it works on, with what the step before it already knows of them.
struct PhaseInput {
    const std::vector<std::uint32_t>& points;  ///< indices into the cloud
    const std::uint32_t* columns;              ///< each point's column (detail::Workspace::columns)
    const Eigen::Vector3f* xyz = nullptr;      ///< optional: the points' coordinates in this order (Phase II: Phase I's)
    const float* z = nullptr;                  ///< optional: their z likewise (Phase I: as the columns gathered them)
};

/// What a phase writes.
struct PhaseOutput {
    std::vector<std::uint32_t>& ground;                    ///< replaced by the indices the phase calls ground
    PhaseReport& report;                                   ///< the phase's counters, times and (optionally) cells
    std::vector<std::uint32_t>* groundColumns = nullptr;  ///< optional: the ground points' columns likewise
    std::vector<Eigen::Vector3f>* groundPoints = nullptr;  ///< optional: their coordinates likewise (for Phase II)
};

/// One phase of GSeg3D over the points `in.points`; replaces the contents of `out.ground` with the indices it calls ground.
///
/// Which steps are the paper's (Lodhi and Hertzberg, ICRCV 2025), which the authors' public
/// implementation's (dfki-ric/ground_segmentation, where the paper is vague) and which our own:
/// - Step 1, grid [paper]. Ours: the vertical grid aligned on the expected ground (gridGroundLevel).
/// - Step 2, local eigen classification [paper; constants and the variance rule of small cells:
///   authors']. The PCA normal check of planar cells (checkPlaneNormal) is the authors'; upright
///   strips among line cells (stripMinSpread) and the least tilted plane of a line cell are ours.
/// - Step 3, surface gradient analysis (RANSAC plane fit) [paper]. Ours: the best plane within the
///   slope limit must hold more than minGroundInlierRatio of the cell.
/// - Algorithm 1 sparsity buckets and the ambiguous-cell rule [paper; bucket limits: authors']. Ours: only
///   a population of at least minPointsPerCell outliers can make a cell ambiguous.
/// - Step 4, region expansion over the centroids within a radius [paper: a KD-tree; ours: columns of
///   centroids, the same neighbours, region_growing.cpp]. Ours: the seed is the candidates
///   near the robot at ground level (seedHeightTolerance) instead of synthetic points, with the
///   few-seeds disc (fewer than 4 seeds: also those just beyond the nearest candidate) and the
///   tolerance widening with the slope; the height gate measured along the fitted planes.
/// - Floating-cell rejection [paper]. Ours: Phase II also looks below a cell for points Phase I
///   rejected (PhaseSettings::belowRejected).
/// - Recovery of points on a ground neighbour's plane in Phase I [authors' implementation, not the
///   paper] (recoverNearGround).
/// Around the phases (GroundSegmenter::run), ours: non-finite points labelled non-ground without
/// taking part, and reflections below the ground flagged (below_ground.hpp).
class Phase {
public:
    Phase(const Params& p, const PhaseSettings& settings) : p_(p), set_(settings), slope_(p) {}

    /// The phase's steps over `in`, into `out`; `keepCells`: every cell's diagnostics in out.report.
    void run(const PointCloudView& cloud, const PhaseInput& in, const PhaseOutput& out, detail::Workspace& ws, bool keepCells) {
        PhaseReport& report = out.report;
        report.inputPoints = in.points.size();
        auto t = Clock::now();
        // Step 1: grid representation. The vertical grid is aligned on the expected ground under the
        // robot, so that the ground and what sits a little above it (curbs, sidewalks) share a cell
        // instead of straddling a border wherever the sensor height happens to put one.
        ws.grid = &ws.phaseGrids[set_.number - 1];
        ws.grid->build(cloud, in.points, ws.columns, in.columns, set_.cellSizeZ, originZ(), in.xyz, in.z);
        report.ms.grid = msSince(t);
        classifyCells(ws);  // Step 2: local eigen classification
        report.ms.classification = msSince(t);
        fitPlanes(ws);  // Step 3: surface gradient analysis
        report.ms.planeFit = msSince(t);
        markAmbiguous(ws);  // Algorithm 1: sparsity buckets of inliers vs outliers
        report.ms.refinement = msSince(t);
        expand(ws);  // Step 4: ground region expansion with per-cell checks
        report.ms.expansion = msSince(t);
        collect(ws, out.ground, out.groundColumns, out.groundPoints, report, keepCells);
        report.ms.refinement += msSince(t);
    }

private:
    void classifyCells(detail::Workspace& ws) const {
        const auto& pts = ws.grid->points();
        ws.inlier.assign(pts.size(), 0);
        ws.cells.assign(ws.grid->cells().size(), CellState());
        ws.moments.resize(ws.cells.size());  // written for the cells the plane fit takes, read for those only
        // Cells are independent: each writes its own state and its own points' flags.
        for (std::size_t c = 0; c < ws.cells.size(); ++c) classifyOne(ws, c);
    }

    void classifyOne(detail::Workspace& ws, std::size_t c) const {
        const auto& pts = ws.grid->points();
        const GridCell& g = ws.grid->cells()[c];
        PointMoments moments;
        const CellClassification cls = classifyCell(&pts[g.begin], g.size(), p_, slope_, &moments);
        if (cls.cellClass == CellClass::Plane && !cls.steepNormal) ws.moments[c] = moments;  // fitOne() takes them
        CellState& s = ws.cells[c];
        s.cellClass = cls.cellClass;
        s.outcome = cls.groundCandidate ? CellOutcome::NotReached : cls.rejection;
        s.steepNormal = cls.steepNormal;
        if (cls.groundCandidate && cls.cellClass != CellClass::Plane) {
            // Line and small cells have no plane: all their points are ground candidates.
            std::fill(ws.inlier.begin() + g.begin, ws.inlier.begin() + g.end, 1);
            s.inliers = g.size();
            s.ground = cls.mean;
            s.normal = cls.normal;
        }
    }

    // Planar cells: the best plane within the slope limit must hold most of the cell's points;
    // otherwise the cell is dominated by something steeper (a wall, a car side) and is not ground.
    // Each cell's RANSAC generator is seeded from the cell's index, so the fits are independent.
    void fitPlanes(detail::Workspace& ws) const {
        for (std::size_t c = 0; c < ws.cells.size(); ++c) fitOne(ws, c);
    }

    void fitOne(detail::Workspace& ws, std::size_t c) const {
        CellState& s = ws.cells[c];
        if (s.cellClass != CellClass::Plane) return;
        const GridCell& g = ws.grid->cells()[c];
        if (s.steepNormal) {  // a wall, a car side or a hedge face: no plane fit can make it ground
            s.outcome = CellOutcome::Steep;
            return;
        }
        const PlaneFitResult fit = fitPlane(&ws.grid->points()[g.begin], g.size(), p_, cellSeed(p_.ransacSeed, g, set_.number),
                                            ws.cellMask, ws.planeFit, p_.slopeThresholdDegrees, p_.minGroundInlierRatio,
                                            &ws.moments[c]);
        if (!fit.valid || double(fit.numInliers) <= p_.minGroundInlierRatio * double(g.size())) {
            s.outcome = CellOutcome::Steep;
            return;
        }
        // (Pointers at hand: a byte store may alias anything, and would have them reloaded per point.)
        const std::uint8_t* const mask = ws.cellMask.data();
        const Eigen::Vector3f* const pts = ws.grid->points().data() + g.begin;
        std::copy(mask, mask + g.size(), ws.inlier.begin() + g.begin);
        const Eigen::Vector3f sum = fit.numInliers == g.size() ? floatSum(pts, g.size(), nullptr) : floatSum(pts, g.size(), mask);
        s.inliers = std::uint32_t(fit.numInliers);
        s.ground = sum / float(fit.numInliers);
        s.normal = fit.normal;
    }

    void markAmbiguous(detail::Workspace& ws) const {
        ws.candidateCell.clear();
        ws.centroids.clear();
        ws.normals.clear();
        for (std::size_t c = 0; c < ws.cells.size(); ++c) {
            CellState& s = ws.cells[c];
            if (s.outcome != CellOutcome::NotReached) continue;
            const GridCell& g = ws.grid->cells()[c];
            // A handful of outliers has no meaningful bounding box: only a population of at least
            // minPointsPerCell outliers can compete with the inliers.
            if (g.size() - s.inliers >= std::uint32_t(p_.minPointsPerCell)) {
                const auto volumes = volumesPerPoint(&ws.grid->points()[g.begin], &ws.inlier[g.begin], g.size());
                const Sparsity in = sparsityBucket(volumes.first, p_);
                const Sparsity out = sparsityBucket(volumes.second, p_);
                s.ambiguous = in == out;
            }
            s.candidate = std::int32_t(ws.candidateCell.size());
            ws.candidateCell.push_back(std::uint32_t(c));
            ws.centroids.push_back(s.ground);
            // The gate follows fitted planes only: a line cell is gated by height (a ring on a wall
            // near the sensor is a tilted line, and its least tilted plane would lead up the wall).
            ws.normals.push_back(s.cellClass == CellClass::Plane ? s.normal : Eigen::Vector3f::UnitZ());
        }
    }

    // An occupied cell classified non-ground lies directly below cell c (same column, lower z); in
    // Phase II also any point Phase I called non-ground below the cell's bottom.
    bool floating(const detail::Workspace& ws, std::size_t c) const {
        const auto& g = ws.grid->cells();
        for (std::size_t b = c; b-- > 0 && g[b].ix == g[c].ix && g[b].iy == g[c].iy;) {
            const CellOutcome o = ws.cells[b].outcome;
            if (o == CellOutcome::Steep || o == CellOutcome::NonPlanar) return true;
        }
        if (!set_.belowRejected) return false;
        // Only points between floatingMinHeight and floatingMaxDepth below the cell's bottom count:
        // closer, a step of the ground; deeper, a reflection under it.
        const std::uint32_t column = ws.grid->cellColumns()[c];
        const double bottom = originZ() + double(g[c].iz) * set_.cellSizeZ;
        const double top = bottom - p_.floatingMinHeight, deep = bottom - p_.floatingMaxDepth;
        for (std::uint32_t k = ws.rejectedStart[column], e = ws.rejectedStart[column + 1]; k < e; ++k)
            if (double(ws.rejected[k].low) < top && double(ws.rejected[k].high) >= deep) return true;
        return false;
    }

    double originZ() const { return -p_.distToGround - p_.gridGroundLevel * set_.cellSizeZ; }

    void expand(detail::Workspace& ws) const {
        ExpansionSettings es;
        es.seed = Eigen::Vector3f(0.f, 0.f, float(-p_.distToGround));
        es.seedRadius = p_.robotRadius + p_.centroidSearchRadius;
        es.radius = p_.centroidSearchRadius;
        es.heightGate = set_.heightGate;
        if (set_.bridges) {
            es.bridgeRadius = p_.bridgeRadius;
            es.bridgeGate = p_.bridgeGate;
            es.bridgeGapGate = p_.bridgeGapGate;
            es.bridgeMaxDrop = p_.bridgeMaxDrop;
            es.bridgeMinNormalCos = std::cos(p_.bridgeMaxAngleDegrees * M_PI / 180.0);
        }
        es.normals = &ws.normals;
        es.seedGate = p_.seedHeightTolerance;  // both phases: the seed is ground level with the robot
        es.seedSlope = std::tan(p_.slopeThresholdDegrees * M_PI / 180.0);
        es.fewSeeds = 4;  // real scans give dozens (KITTI: 85-169); one or two may be a car's wheels
        // Only the ambiguous-cell rule reads the neighbours (the lowest of them).
        es.needsNeighbours = [&](std::uint32_t cand) { return ws.cells[ws.candidateCell[cand]].ambiguous; };
        const auto accept = [&](std::uint32_t cand, const std::vector<std::uint32_t>& nb) {
            const std::size_t c = ws.candidateCell[cand];
            CellState& s = ws.cells[c];
            if (s.ambiguous) {
                float lowest = std::numeric_limits<float>::infinity();
                for (std::uint32_t j : nb) lowest = std::min(lowest, ws.centroids[j].z());
                if (nb.empty() || s.ground.z() - lowest > p_.maxGroundHeightDeviation) {
                    s.outcome = CellOutcome::RejectedAmbiguous;
                    return false;
                }
            }
            if (floating(ws, c)) {
                s.outcome = CellOutcome::RejectedFloating;
                return false;
            }
            s.outcome = CellOutcome::Ground;
            return true;
        };
        expandRegion(ws.centroids, es, accept, &ws.parents);
    }

    void collect(detail::Workspace& ws, std::vector<std::uint32_t>& ground, std::vector<std::uint32_t>* groundColumns,
                 std::vector<Eigen::Vector3f>* groundPoints, PhaseReport& r, bool keepCells) const {
        const auto& grid = ws.grid->cells();
        r.occupiedCells = grid.size();
        r.candidateCells = ws.candidateCell.size();
        if (keepCells) r.cells.reserve(grid.size());
        if (set_.recordRejected) ws.rejected.clear();
        // recover() reads only the ground cells, which it never changes: every cell on its own.
        if (set_.recover) {
            // The columns holding a ground cell (recover() looks into no other).
            ws.groundInColumn.assign(ws.columns.size(), 0);
            for (std::size_t c = 0; c < grid.size(); ++c)
                if (ws.cells[c].outcome == CellOutcome::Ground) ws.groundInColumn[ws.grid->cellColumns()[c]] = 1;
            for (std::size_t c = 0; c < grid.size(); ++c)
                if (ws.cells[c].outcome != CellOutcome::Ground &&
                    (!set_.recoverSparseOnly || ws.cells[c].outcome == CellOutcome::TooFewPoints))
                    recover(ws, c);
        }
        // The accepted points replace the outputs' contents, written in place without a check per
        // point: room for every point of the ground and recovered cells (and one more: the
        // branch-free compaction writes one past its last point), cut to what was written at the
        // end. (The outputs keep their size from the previous scan until then: resizing within it
        // fills nothing.)
        std::size_t room = 1;
        for (std::size_t c = 0; c < grid.size(); ++c)
            if (ws.cells[c].outcome == CellOutcome::Ground || ws.cells[c].recovered) room += grid[c].size();
        ground.resize(room);
        if (groundPoints) groundPoints->resize(room);
        if (groundColumns) groundColumns->resize(room);
        std::size_t written = 0;
        for (std::size_t c = 0; c < grid.size(); ++c) {
            const GridCell& g = grid[c];
            const CellState& s = ws.cells[c];
            if (set_.recordRejected && s.outcome != CellOutcome::TooFewPoints) recordRejected(ws, c);
            if (s.outcome == CellOutcome::Ground || s.recovered) {
                if (s.outcome == CellOutcome::Ground)
                    ++r.groundCells;
                else
                    r.recoveredPoints += s.inliers;
                written = groundPoints ? appendInliers<true>(ws, c, written, ground, groundColumns, groundPoints)
                                       : appendInliers<false>(ws, c, written, ground, groundColumns, groundPoints);
            } else if (s.outcome == CellOutcome::TooFewPoints) {
                r.unlabelledCellPoints += g.size();
            } else if (s.outcome == CellOutcome::NotReached) {
                r.unreachedCellPoints += g.size();
            }
            if (keepCells)
                r.cells.push_back({g.ix, g.iy, g.iz, g.size(), s.inliers, s.cellClass, s.outcome, s.ground.z(),
                                   s.candidate < 0 ? -2 : reachedFromCell(ws, std::size_t(s.candidate))});
        }
        ground.resize(written);
        if (groundPoints) groundPoints->resize(written);
        if (groundColumns) groundColumns->resize(written);
        r.groundPoints = ground.size();
        if (set_.recordRejected) {
            // Where each column's spans begin (they come by column id): no search per cell later.
            ws.rejectedStart.assign(std::size_t(ws.columns.size()) + 1, 0);
            for (const RejectedSpan& span : ws.rejected) ++ws.rejectedStart[span.column + 1];
            for (std::size_t k = 1; k < ws.rejectedStart.size(); ++k) ws.rejectedStart[k] += ws.rejectedStart[k - 1];
        }
    }

    // Writes the inliers of cell c (their indices, and with kPoints their points and column ids
    // too) from position `at` of the outputs, which have room for all the cell's points and one
    // more; returns the position after the last one written. (Every point is written, and the
    // position advances past the inliers only: no branch per point.)
    template <bool kPoints>
    static std::size_t appendInliers(const detail::Workspace& ws, std::size_t c, std::size_t at,
                                     std::vector<std::uint32_t>& ground, std::vector<std::uint32_t>* groundColumns,
                                     std::vector<Eigen::Vector3f>* groundPoints) {
        const GridCell& g = ws.grid->cells()[c];
        const std::uint32_t* const order = ws.grid->order().data();
        const Eigen::Vector3f* const pts = ws.grid->points().data();
        const std::uint8_t* const inlier = ws.inlier.data();
        std::uint32_t* const outIdx = ground.data();
        Eigen::Vector3f* const outPts = kPoints ? groundPoints->data() : nullptr;
        std::uint32_t* const outCol = kPoints && groundColumns ? groundColumns->data() : nullptr;
        const std::uint32_t column = ws.grid->cellColumns()[c];
        if (ws.cells[c].inliers == g.size()) {  // every point (s.inliers: the cell's inlier flags)
            std::copy(order + g.begin, order + g.end, outIdx + at);
            if (kPoints) {
                std::copy(pts + g.begin, pts + g.end, outPts + at);
                if (outCol) std::fill(outCol + at, outCol + at + g.size(), column);
            }
            return at + g.size();
        }
        for (std::uint32_t k = g.begin; k < g.end; ++k) {
            outIdx[at] = order[k];
            if (kPoints) {
                outPts[at] = pts[k];
                if (outCol) outCol[at] = column;
            }
            at += inlier[k];
        }
        return at;
    }

    // Phase I, a cell that is not ground: its points that lie on the ground plane of a ground cell
    // beside it or one level below (within recoveryThreshold) go on to Phase II after all, as in
    // the authors' implementation: the road at the foot of a wall, the grass between bushes, the
    // sidewalk in a cell that a pedestrian made steep. Phase II judges them like any other point.
    void recover(detail::Workspace& ws, std::size_t c) const {
        const auto& cells = ws.grid->cells();
        const auto& columnCells = ws.grid->columnCells();
        const GridCell& g = cells[c];
        std::uint32_t nb[17];
        int count = 0;
        // The occupied cells (ix + dx, iy + dy, iz + dz), dz = -1 then 0 (not the cell itself), in
        // (dx, dy, dz) order, found in their column's cells (sorted by iz).
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy) {
                const std::int64_t column = ws.columns.find(g.ix + dx, g.iy + dy);
                if (column < 0 || !ws.groundInColumn[std::size_t(column)]) continue;
                for (std::uint32_t b = columnCells[std::size_t(column)], e = columnCells[std::size_t(column) + 1]; b < e; ++b) {
                    if (cells[b].iz > g.iz) break;
                    if (cells[b].iz < g.iz - 1 || b == c) continue;
                    if (ws.cells[b].outcome == CellOutcome::Ground) nb[count++] = b;
                }
            }
        CellState& s = ws.cells[c];
        std::fill(ws.inlier.begin() + g.begin, ws.inlier.begin() + g.end, 0);
        s.inliers = 0;
        if (count == 0) return;
        const float thr = float(set_.recoveryThreshold);
        // The neighbours' ground centroids (x, y) at hand.
        const CellState* nbs[17];
        float gx[17], gy[17];
        for (int j = 0; j < count; ++j) {
            nbs[j] = &ws.cells[nb[j]];
            gx[j] = nbs[j]->ground.x(), gy[j] = nbs[j]->ground.y();
        }
        const Eigen::Vector3f* const pts = ws.grid->points().data();
        std::uint8_t* const inlier = ws.inlier.data();
        // Without a branch per point; the cell's state written once at the end: its count, and the
        // plane and the point of the last point recovered.
        std::uint32_t inliers = 0, last = 0;
        int lastBest = 0;
        for (std::uint32_t k = g.begin; k < g.end;) {
            // The plane of the neighbour whose ground centroid is horizontally nearest (up to four
            // points at a time).
            int best[4];
            const std::uint32_t m = nearestCentroids(pts + k, std::min<std::uint32_t>(4, g.end - k), gx, gy, count, best);
            for (std::uint32_t i = 0; i < m; ++i, ++k) {
                const Eigen::Vector3f& q = pts[k];
                const CellState& n = *nbs[best[i]];
                const bool on = std::abs(n.normal.dot(q - n.ground)) <= thr;
                inlier[k] = on;
                inliers += on;
                last = on ? k : last;
                lastBest = on ? best[i] : lastBest;
            }
        }
        s.inliers = inliers;
        if (inliers > 0) s.normal = nbs[lastBest]->normal, s.ground = pts[last];
        s.recovered = inliers > 0;
    }

    // For each of the m (1 to 4) points q[0..m): the index j < count of the centroid (gx[j],
    // gy[j]) horizontally nearest to it, the first of equals ((g - q).head<2>().squaredNorm() in
    // float, compared strictly in j's order) into best[]; returns m. Four points at a time in
    // SSE2 registers, each lane the scalar form's operations.
    static std::uint32_t nearestCentroids(const Eigen::Vector3f* q, std::uint32_t m, const float* gx, const float* gy,
                                          int count, int* best) {
#if defined(__SSE2__)
        if (m == 4) {
            const __m128 qx = _mm_setr_ps(q[0].x(), q[1].x(), q[2].x(), q[3].x());
            const __m128 qy = _mm_setr_ps(q[0].y(), q[1].y(), q[2].y(), q[3].y());
            __m128 bestD = _mm_set1_ps(std::numeric_limits<float>::infinity());
            __m128i bestJ = _mm_setzero_si128();
            for (int j = 0; j < count; ++j) {
                const __m128 dx = _mm_sub_ps(_mm_set1_ps(gx[j]), qx), dy = _mm_sub_ps(_mm_set1_ps(gy[j]), qy);
                const __m128 d = _mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy));
                const __m128i nearer = _mm_castps_si128(_mm_cmplt_ps(d, bestD));
                bestJ = _mm_or_si128(_mm_and_si128(nearer, _mm_set1_epi32(j)), _mm_andnot_si128(nearer, bestJ));
                bestD = _mm_min_ps(d, bestD);  // d < bestD ? d : bestD
            }
            _mm_storeu_si128(reinterpret_cast<__m128i*>(best), bestJ);
            return 4;
        }
#endif
        for (std::uint32_t i = 0; i < m; ++i) {
            int b = 0;
            float bestD = std::numeric_limits<float>::infinity();
            for (int j = 0; j < count; ++j) {
                const float dx = gx[j] - q[i].x(), dy = gy[j] - q[i].y();
                const float d = dx * dx + dy * dy;
                b = d < bestD ? j : b;
                bestD = d < bestD ? d : bestD;
            }
            best[i] = b;
        }
        return m;
    }

    std::int32_t reachedFromCell(const detail::Workspace& ws, std::size_t candidate) const {
        const std::int32_t parent = ws.parents[candidate];
        return parent < 0 ? parent : std::int32_t(ws.candidateCell[std::size_t(parent)]);
    }

    // Phase I: the z range of the points of cell c that Phase I did not accept (cells arrive column by
    // column, bottom to top). Recovered points count too: they sit in a cell Phase I rejected. Not
    // counted: cells too small to classify; a ground cell's outliers below its plane
    // (floatingIgnoresLowOutliers), which are lower ground (the road beside a sidewalk, a rut), not
    // something standing below the cells above; and in a recovered cell, points more than
    // floatingMaxDepth below the plane it was recovered onto (reflections under the road).
    void recordRejected(detail::Workspace& ws, std::size_t c) const {
        const GridCell& g = ws.grid->cells()[c];
        const CellState& s = ws.cells[c];
        const bool ground = s.outcome == CellOutcome::Ground;
        if (ground && s.inliers == g.size()) return;  // every point accepted (s.inliers: the cell's inlier flags)
        RejectedSpan span{ws.grid->cellColumns()[c], std::numeric_limits<float>::infinity(),
                          -std::numeric_limits<float>::infinity()};
        if (!ground && !s.recovered) {  // every point counts: the z range of the cell
            const Eigen::Vector3f* const pts = ws.grid->points().data();
            for (std::uint32_t k = g.begin; k < g.end; ++k)
                span.low = std::min(span.low, pts[k].z()), span.high = std::max(span.high, pts[k].z());
            ws.rejected.push_back(span);  // a cell holds at least one point
            return;
        }
        for (std::uint32_t k = g.begin; k < g.end; ++k) {
            if (ground && ws.inlier[k]) continue;
            const Eigen::Vector3f& q = ws.grid->points()[k];
            if (ground && p_.floatingIgnoresLowOutliers && s.normal.dot(q - s.ground) < 0) continue;
            if (s.recovered && s.normal.dot(q - s.ground) < -p_.floatingMaxDepth) continue;
            span.low = std::min(span.low, q.z());
            span.high = std::max(span.high, q.z());
        }
        if (span.low <= span.high) ws.rejected.push_back(span);
    }

    const Params& p_;
    const PhaseSettings set_;
    const SlopeLimit slope_;
};

}  // namespace

Result GroundSegmenter::segment(const PointCloudView& cloud, bool keepCellDiagnostics) {
    return run(cloud, params_, keepCellDiagnostics);
}

Result GroundSegmenter::segment(const PointCloudView& cloud, double distToGround, bool keepCellDiagnostics) {
    if (!std::isfinite(distToGround))
        throw std::invalid_argument("gseg: distToGround must be finite, not " + std::to_string(distToGround));
    Params p = params_;
    p.distToGround = distToGround;
    return run(cloud, p, keepCellDiagnostics);
}

namespace {

/// Ours: the lowest ground of each ground cell of the last phase into ws.groundColumns, for
/// flagBelowGround (Phase II's grid is still in the workspace; a ground cell holds its inliers).
void collectGroundColumns(detail::Workspace& ws) {
    ws.groundColumns.clear();
    // (Pointers at hand; a cell whose every point is an inlier takes no look at the flags.)
    const auto& cells = ws.grid->cells();
    const Eigen::Vector3f* const pts = ws.grid->points().data();
    const std::uint8_t* const inlier = ws.inlier.data();
    for (std::size_t c = 0; c < cells.size(); ++c) {
        if (ws.cells[c].outcome != CellOutcome::Ground) continue;
        float lowest = std::numeric_limits<float>::infinity();
        if (ws.cells[c].inliers == cells[c].size())
            for (std::uint32_t k = cells[c].begin; k < cells[c].end; ++k) lowest = std::min(lowest, pts[k].z());
        else
            for (std::uint32_t k = cells[c].begin; k < cells[c].end; ++k)
                lowest = inlier[k] ? std::min(lowest, pts[k].z()) : lowest;
        ws.groundColumns.push_back({cells[c].ix, cells[c].iy, lowest});
    }
}

}  // namespace

Result GroundSegmenter::run(const PointCloudView& cloud, const Params& params, bool keepCellDiagnostics) {
    const auto start = Clock::now();
    checkCloud(cloud);
    detail::Workspace& ws = *ws_;
    Result r;

    // Points with a NaN or infinite coordinate (no return) take no part; they are non-ground.
    ws.input.resize(cloud.size());
    ws.input.resize(finiteIndices(cloud, ws.input.data()));
    r.numNonFinite = cloud.size() - ws.input.size();
    ws.columns.build(cloud, ws.input, params.cellSizeX, params.cellSizeY, ws.inputColumns);

    // Phase I: tall cells over the whole cloud, no height gate.
    PhaseInput all{ws.input, ws.inputColumns.data()};
    all.z = ws.columns.z().data();
    PhaseOutput firstGround{ws.phase1Ground, r.phase1};
    firstGround.groundColumns = &ws.phase1GroundColumns, firstGround.groundPoints = &ws.phase1GroundPoints;
    Phase(params, PhaseSettings::first(params)).run(cloud, all, firstGround, ws, keepCellDiagnostics);
    // Phase II: thin cells over Phase I's ground, with the height gate.
    PhaseInput firstGroundIn{ws.phase1Ground, ws.phase1GroundColumns.data()};
    firstGroundIn.xyz = ws.phase1GroundPoints.data();
    Phase(params, PhaseSettings::second(params)).run(cloud, firstGroundIn, PhaseOutput{ws.phase2Ground, r.phase2}, ws, keepCellDiagnostics);

    r.labels.assign(cloud.size(), std::uint8_t(Label::NonGround));
    for (std::uint32_t i : ws.phase2Ground) r.labels[i] = std::uint8_t(Label::Ground);
    r.numGround = ws.phase2Ground.size();
    r.numNonGround = cloud.size() - r.numGround;
    // Ours, not the paper's: reflections far below the ground (below_ground.hpp).
    collectGroundColumns(ws);
    r.belowGround = flagBelowGround(cloud, ws.input, r.labels, ws.groundColumns, params, ws.belowGround);
    r.totalMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    return r;
}

const char* toString(CellClass c) {
    switch (c) {
        case CellClass::TooFewPoints: return "too_few_points";
        case CellClass::Small: return "small";
        case CellClass::Line: return "line";
        case CellClass::Plane: return "plane";
        case CellClass::NonPlanar: return "non_planar";
    }
    return "?";
}

const char* toString(CellOutcome o) {
    switch (o) {
        case CellOutcome::Ground: return "ground";
        case CellOutcome::TooFewPoints: return "too_few_points";
        case CellOutcome::Steep: return "steep";
        case CellOutcome::NonPlanar: return "non_planar";
        case CellOutcome::NotReached: return "not_reached";
        case CellOutcome::RejectedAmbiguous: return "rejected_ambiguous";
        case CellOutcome::RejectedFloating: return "rejected_floating";
    }
    return "?";
}

}  // namespace gseg
