// Scoring a 2D map against a labelled KITTI drive: the rules of ../shared/tools/score_map.py
// (gseg/eval/map_score.hpp), and the picture of the scored cells.
#include <gseg/eval/kitti_sequence.hpp>
#include <gseg/io/kitti.hpp>
#include <gseg/eval/map_score.hpp>
#include <gseg/map/poses.hpp>
#include <gseg/map/map_colours.hpp>  // backgroundColour(): the page around every map picture
#include <gseg/map/map_page.hpp>
#include <gseg/mrpt/picture.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <stdexcept>

namespace fs = std::filesystem;

namespace gseg::map {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kBandBase = -1.73;   ///< [m] the baseline's ground: the HDL-64's height on the KITTI car
constexpr double kObstacleLow = 0.3;  ///< [m] the obstacle band starts this far above the ground
constexpr double kFallbackRadius = 1.0;  ///< [m] neighbourhood of a cell without ground of its own

/// score_map.py's median: the element n / 2 of the sorted values.
double upperMedian(std::vector<double>& v) {
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
    return v[v.size() / 2];
}

double percent(std::size_t n, std::size_t of) { return of ? 100.0 * double(n) / double(of) : kNaN; }

/// The scans of `velodyne/` (gseg::eval::listKittiScans), sorted by name, each with its frame number.
std::vector<std::pair<std::string, std::size_t>> driveFrames(const fs::path& seq) {
    const fs::path velodyne = seq / "velodyne";
    std::error_code ec;
    if (!fs::is_directory(velodyne, ec)) throw std::runtime_error(velodyne.string() + ": no such folder (the drive's scans)");
    std::vector<std::pair<std::string, std::size_t>> frames;
    for (const eval::KittiScan& s : eval::listKittiScans(seq.string())) {
        const std::optional<std::size_t> number = eval::kittiFrameNumber(s.name, 9);
        if (!number) throw std::runtime_error(s.scan + ": the scan's name is not a frame number (NNNNNN.bin)");
        frames.emplace_back(s.name, *number);
    }
    if (frames.empty()) throw std::runtime_error(velodyne.string() + ": no scans (*.bin)");
    return frames;
}

}  // namespace

bool ignoredClass(std::uint32_t label) { return label == 0 || label == 1 || label >= 252; }

bool groundClass(std::uint32_t label) {
    return label == 40 || label == 44 || label == 48 || label == 49 || label == 60 || label == 72;
}

LabelledDrive readLabelledDrive(const std::string& sequenceDir, const std::function<void(std::size_t, std::size_t)>& progress) {
    const fs::path seq(sequenceDir);
    const auto frames = driveFrames(seq);
    const Eigen::Isometry3d tr = readKittiCalibTr((seq / "calib.txt").string());
    const std::string posesPath = (seq / "poses.txt").string();
    const std::vector<Eigen::Isometry3d> poses = kittiToVelodyneFrame(readKittiPoses(posesPath), tr);
    LabelledDrive drive;
    for (const auto& [name, number] : frames) {
        if (number >= poses.size())
            throw std::runtime_error(posesPath + ": " + std::to_string(poses.size()) + " poses, but scan " + name +
                                     ".bin needs line " + std::to_string(number + 1));
        const std::string scanPath = (seq / "velodyne" / (name + ".bin")).string();
        const std::vector<float> pts = io::readKittiBin(scanPath);
        const std::vector<std::uint32_t> labels = io::readKittiLabels((seq / "labels" / (name + ".label")).string(), pts.size() / 4);
        const Eigen::Matrix4d t = poses[number].matrix();
        for (std::size_t n = 0; n < labels.size(); ++n) {
            const double x = pts[4 * n], y = pts[4 * n + 1], z = pts[4 * n + 2];
            if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
                throw std::runtime_error(scanPath + ": point " + std::to_string(n) + " has a coordinate that is not a finite number");
            const std::uint32_t label = labels[n] & 0xFFFFu;
            if (ignoredClass(label)) continue;
            // The order of score_map.py's sums (a*x + b*y + c*z + d), for the same cells to the last bit.
            drive.points.push_back({t(0, 0) * x + t(0, 1) * y + t(0, 2) * z + t(0, 3), t(1, 0) * x + t(1, 1) * y + t(1, 2) * z + t(1, 3),
                                    t(2, 0) * x + t(2, 1) * y + t(2, 2) * z + t(2, 3), std::uint16_t(label)});
        }
        drive.pointsRead += labels.size();
        ++drive.frames;
        if (progress) progress(drive.frames, frames.size());
    }
    return drive;
}

long long ScoreGrid::cellX(double x) const { return (long long)std::floor((x - originX) / resolution); }
long long ScoreGrid::cellY(double y) const { return (long long)std::floor((y - originY) / resolution); }

std::uint64_t DriveTruth::cellKey(long long cx, long long cy) {
    return (std::uint64_t(std::uint32_t(std::int32_t(cx))) << 32) | std::uint64_t(std::uint32_t(std::int32_t(cy)));
}

ScoreGrid gridOf(const io::RosMap& map) { return {map.resolution, map.originX, map.originY}; }

DriveTruth computeTruth(const LabelledDrive& drive, const ScoreGrid& grid, double clearance,
                        const std::function<void(std::size_t, std::size_t)>& progress) {
    if (!(std::isfinite(grid.resolution) && grid.resolution > 0) || !std::isfinite(grid.originX) || !std::isfinite(grid.originY))
        throw std::invalid_argument("map score: the grid needs a positive resolution and a finite origin");
    if (!(std::isfinite(clearance) && clearance > kObstacleLow))
        throw std::invalid_argument("map score: clearance must be above 0.3 m (the obstacle band's bottom), got " +
                                    std::to_string(clearance));
    DriveTruth out;
    out.grid = grid, out.clearance = clearance;
    // The points of each cell, by cell.
    struct Ref {
        std::uint64_t key;
        long long cx, cy;
        std::size_t point;
    };
    std::vector<Ref> refs;
    refs.reserve(drive.points.size());
    const double limit = 2147483647.0;
    for (std::size_t i = 0; i < drive.points.size(); ++i) {
        const LabelledPoint& p = drive.points[i];
        const double fx = std::floor((p.x - grid.originX) / grid.resolution), fy = std::floor((p.y - grid.originY) / grid.resolution);
        if (!(std::abs(fx) < limit && std::abs(fy) < limit))
            throw std::invalid_argument("map score: a point lies more than 2^31 cells from the map's origin");
        refs.push_back({DriveTruth::cellKey((long long)fx, (long long)fy), (long long)fx, (long long)fy, i});
    }
    std::sort(refs.begin(), refs.end(), [](const Ref& a, const Ref& b) { return a.cx != b.cx ? a.cx < b.cx : a.cy != b.cy ? a.cy < b.cy : a.point < b.point; });
    struct Span {
        std::size_t begin, end;
    };
    std::vector<Span> spans;
    for (std::size_t b = 0; b < refs.size();) {
        std::size_t e = b + 1;
        while (e < refs.size() && refs[e].key == refs[b].key) ++e;
        spans.push_back({b, e});
        b = e;
    }
    // Ground height (>= 3 ground points) and the baseline's counts, per cell.
    std::vector<double> z;
    for (const Span& s : spans) {
        z.clear();
        DriveTruth::Seen seen;
        for (std::size_t i = s.begin; i < s.end; ++i) {
            const LabelledPoint& p = drive.points[refs[i].point];
            ++seen.points;
            if (kBandBase + kObstacleLow < p.z && p.z < kBandBase + clearance) ++seen.inBand;
            if (groundClass(p.label)) z.push_back(p.z);
        }
        out.seen[refs[s.begin].key] = seen;
        if (z.size() >= 3) out.groundHeight[refs[s.begin].key] = upperMedian(z);
    }
    // Truth per cell.
    const long long r = std::max(1LL, (long long)std::nearbyint(kFallbackRadius / grid.resolution));  // Python's round: half to even
    std::vector<double> near;
    std::size_t done = 0;
    for (const Span& s : spans) {
        if (progress && ++done % 4096 == 0) progress(done, spans.size());
        const long long cx = refs[s.begin].cx, cy = refs[s.begin].cy;
        const auto own = out.groundHeight.find(refs[s.begin].key);
        double ref;
        if (own != out.groundHeight.end()) {
            ref = own->second;
        } else {
            near.clear();
            for (long long a = -r; a <= r; ++a)
                for (long long b = -r; b <= r; ++b)
                    if (const auto it = out.groundHeight.find(DriveTruth::cellKey(cx + a, cy + b)); it != out.groundHeight.end())
                        near.push_back(it->second);
            if (!near.empty()) {
                ref = upperMedian(near);
            } else {
                ref = std::numeric_limits<double>::infinity();
                for (std::size_t i = s.begin; i < s.end; ++i) ref = std::min(ref, drive.points[refs[i].point].z);
            }
        }
        int obstacles = 0;
        for (std::size_t i = s.begin; i < s.end; ++i) {
            const LabelledPoint& p = drive.points[refs[i].point];
            if (!groundClass(p.label) && ref + kObstacleLow < p.z && p.z < ref + clearance) ++obstacles;
        }
        if (obstacles >= 2) out.cells.push_back({cx, cy, TruthClass::Obstacle});
        else if (own != out.groundHeight.end()) out.cells.push_back({cx, cy, TruthClass::Traversable});
    }
    if (progress) progress(spans.size(), spans.size());
    return out;
}

MapScore scorePredictions(const DriveTruth& truth, const std::function<Prediction(long long, long long)>& predict,
                          CellOutcomes* outcomes) {
    MapScore s;
    std::size_t tp = 0, fn = 0, obstacles = 0, hit = 0, unsafe = 0, unsafe1 = 0;
    if (outcomes) outcomes->assign(truth.cells.size(), CellOutcome::TraversableUnknown);
    for (std::size_t i = 0; i < truth.cells.size(); ++i) {
        const DriveTruth::Cell& c = truth.cells[i];
        const Prediction p = predict(c.cx, c.cy);
        if (p != Prediction::Unknown) ++s.cellsSeen;
        CellOutcome o;
        if (c.truth == TruthClass::Traversable) {
            if (p == Prediction::Free) ++tp, o = CellOutcome::TraversableFound;
            else ++fn, o = p == Prediction::Occupied ? CellOutcome::TraversableBlocked : CellOutcome::TraversableUnknown;
        } else {
            ++obstacles;
            if (p == Prediction::Occupied) {
                ++hit, o = CellOutcome::ObstacleFound;
            } else if (p == Prediction::Free) {
                ++unsafe, o = CellOutcome::FalseTraversable;
                bool occupiedNear = false;  // what an obstacle inflation of one cell would still let a planner drive into
                for (long long a = -1; a <= 1 && !occupiedNear; ++a)
                    for (long long b = -1; b <= 1 && !occupiedNear; ++b) occupiedNear = predict(c.cx + a, c.cy + b) == Prediction::Occupied;
                if (!occupiedNear) ++unsafe1, o = CellOutcome::FalseTraversableBeyond;
            } else {
                o = CellOutcome::ObstacleUnknown;
            }
        }
        ++s.outcomes[int(o)];
        if (outcomes) (*outcomes)[i] = o;
    }
    const std::size_t fp = unsafe;
    s.travPrecision = percent(tp, tp + fp);
    s.travRecall = percent(tp, tp + fn);
    const double sum = s.travPrecision + s.travRecall;  // NaN stays NaN, as in score_map.py
    s.travF1 = sum != 0 ? 2 * s.travPrecision * s.travRecall / sum : 0.0;
    s.obstacleRecall = percent(hit, obstacles);
    s.unsafe = percent(unsafe, obstacles);
    s.unsafeBeyondCell = percent(unsafe1, obstacles);
    s.cellsScored = truth.cells.size();
    return s;
}

MapScore scoreMap(const DriveTruth& truth, const io::RosMap& map, CellOutcomes* outcomes) {
    const ScoreGrid g = gridOf(map);
    if (g.resolution != truth.grid.resolution || g.originX != truth.grid.originX || g.originY != truth.grid.originY)
        throw std::invalid_argument("map score: the truth was computed on another grid than the map's");
    return scorePredictions(truth, [&](long long cx, long long cy) { return Prediction(map.at(cx, cy)); }, outcomes);
}

MapScore scoreHeightBand(const DriveTruth& truth, CellOutcomes* outcomes) {
    return scorePredictions(
        truth,
        [&](long long cx, long long cy) {
            const auto it = truth.seen.find(DriveTruth::cellKey(cx, cy));
            if (it == truth.seen.end()) return Prediction::Unknown;
            return it->second.inBand >= 2 ? Prediction::Occupied : Prediction::Free;
        },
        outcomes);
}

const LayerGrid::Layer& elevationLayer(const LayerGrid& layers) {
    if (const LayerGrid::Layer* l = layers.find("elevation")) return *l;
    for (const LayerGrid::Layer& l : layers.layers()) {
        std::string lower = l.name;
        for (char& c : lower) c = char(std::tolower((unsigned char)c));
        if (lower.find("elev") != std::string::npos) return l;
    }
    throw std::runtime_error("no layer whose name names the elevation");
}

ElevationError elevationError(const LayerGrid& layers, const DriveTruth& truth) {
    const LayerGrid::Layer& elev = elevationLayer(layers);
    double sum2 = 0;
    std::size_t n = 0, within = 0;
    for (int cy = 0; cy < layers.height(); ++cy)
        for (int cx = 0; cx < layers.width(); ++cx) {
            const float v = elev.values[layers.index(cx, cy)];
            if (!std::isfinite(v)) continue;
            const auto it = truth.groundHeight.find(
                DriveTruth::cellKey(truth.grid.cellX(layers.centreX(cx)), truth.grid.cellY(layers.centreY(cy))));
            if (it == truth.groundHeight.end()) continue;
            const double e = double(v) - it->second;
            sum2 += e * e, ++n;
            if (std::abs(e) <= 0.1) ++within;
        }
    if (n == 0) throw std::runtime_error("no elevation cell over labelled ground");
    return {std::sqrt(sum2 / double(n)), 100.0 * double(within) / double(n), n};
}

OutcomeStyle outcomeStyle(CellOutcome c) {
    switch (c) {
        case CellOutcome::TraversableFound: return {60, 170, 75, "traversable, found (map: free)"};
        case CellOutcome::TraversableUnknown: return {150, 225, 160, "traversable, missed: unknown in the map"};
        case CellOutcome::TraversableBlocked: return {240, 170, 40, "traversable, missed: blocked in the map"};
        case CellOutcome::ObstacleFound: return {200, 40, 40, "obstacle, found (map: occupied)"};
        case CellOutcome::ObstacleUnknown: return {240, 150, 150, "obstacle, unknown in the map"};
        case CellOutcome::FalseTraversable: return {150, 60, 220, "unsafe: obstacle called free, occupied within 1 cell"};
        case CellOutcome::FalseTraversableBeyond: return {40, 120, 255, "unsafe beyond 1 cell: no occupied cell around"};
    }
    return {0, 0, 0, ""};
}

std::string encodeMapScorePng(const DriveTruth& truth, const CellOutcomes& outcomes, const std::string& title) {
    if (outcomes.size() != truth.cells.size()) throw std::invalid_argument("map score picture: one outcome per truth cell needed");
    if (truth.cells.empty()) throw std::runtime_error("no scored cell: no picture to draw");
    long long loX = truth.cells.front().cx, hiX = loX, loY = truth.cells.front().cy, hiY = loY;
    for (const auto& c : truth.cells)
        loX = std::min(loX, c.cx), hiX = std::max(hiX, c.cx), loY = std::min(loY, c.cy), hiY = std::max(hiY, c.cy);
    const long long margin = 5;  // [cells] around the scored ones
    MapPageOptions o;
    o.maxSide = 2000, o.enlargeTo = 1200, o.maxEnlarge = 8;
    for (int k = 0; k < kCellOutcomes; ++k) {
        const OutcomeStyle st = outcomeStyle(CellOutcome(k));
        o.legend.push_back({{st.r, st.g, st.b}, st.text});
    }
    o.legend.push_back({{}, "page: cells not scored (no truth)", false});
    o.legend.push_back({{}, "(KITTI drives: x = forward at the first scan)", false});
    const MapPage probe = mapPage(loX - margin, loY - margin, hiX + margin, hiY + margin, truth.grid.resolution, o);
    char sub[160];
    std::snprintf(sub, sizeof sub, "%zu scored cells of %.2f m%s", truth.cells.size(), truth.grid.resolution,
                  probe.cellsPerPixel > 1 ? (", " + std::to_string(probe.cellsPerPixel) + " x " + std::to_string(probe.cellsPerPixel) +
                                             " cells a pixel (the most severe shown)").c_str()
                                          : "");
    o.title = {title, sub};
    const MapPage page = mapPage(loX - margin, loY - margin, hiX + margin, hiY + margin, truth.grid.resolution, o);
    // A block shows the outcome of its cells that is worst for a planner (the highest enum value
    // among the obstacle outcomes first): the order of CellOutcome is the order of severity.
    std::vector<int> block(std::size_t(page.blocksWide()) * std::size_t(page.blocksHigh()), -1);
    for (std::size_t i = 0; i < truth.cells.size(); ++i) {
        int col = 0, row = 0;
        if (!page.blockOf(truth.cells[i].cx, truth.cells[i].cy, col, row)) continue;
        int& b = block[std::size_t(row) * std::size_t(page.blocksWide()) + std::size_t(col)];
        b = std::max(b, int(outcomes[i]));
    }
    std::vector<gseg::mrpt::Colour> colours(block.size(), backgroundColour());
    for (std::size_t i = 0; i < block.size(); ++i)
        if (block[i] >= 0) {
            const OutcomeStyle st = outcomeStyle(CellOutcome(block[i]));
            colours[i] = {st.r, st.g, st.b};
        }
    gseg::mrpt::Picture pic = pageCanvas(page);
    paintBlocks(pic, page, colours);
    drawPageFrame(pic, page);
    return pic.png();
}

}  // namespace gseg::map
