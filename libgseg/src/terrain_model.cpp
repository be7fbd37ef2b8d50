#include <gseg/terrain_model.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

namespace gseg {

namespace {

constexpr std::int32_t kTileSize = 1 << TerrainModel::kTileBits;
constexpr std::int32_t kTileMask = kTileSize - 1;

std::uint64_t tileKey(std::int32_t tx, std::int32_t ty) {
    return (std::uint64_t(std::uint32_t(tx)) << 32) | std::uint32_t(ty);
}

/// Cell index of a coordinate; false where it does not fit an int32 (far beyond any map).
bool cellIndex(double v, double cellSize, std::int32_t& out) {
    const double c = std::floor(v / cellSize);
    if (!(c >= -2147483648.0 && c < 2147483647.0)) return false;
    out = std::int32_t(c);
    return true;
}

}  // namespace

struct TerrainModel::Tile {
    std::array<TerrainCell, std::size_t(kTileSize * kTileSize)> cells;
    std::uint32_t used = 0;  ///< cells with evidence
    /// build()'s working copy of the modelled elevations (NaN: not modelled), dense so that the
    /// least-squares sums over a candidate's disc read 4 bytes a cell, not a whole TerrainCell.
    std::array<float, std::size_t(kTileSize * kTileSize)> modelled;
    std::array<std::uint8_t, std::size_t(kTileSize)> modelledInRow;  ///< build(): modelled cells per row of `modelled` (empty rows skipped)
};

void TerrainOptions::validate() const {
    auto positive = [](double v, const char* name) {
        if (!(std::isfinite(v) && v > 0)) throw std::invalid_argument(std::string("TerrainOptions.") + name + " = " + std::to_string(v) + ": must be > 0");
    };
    positive(cellSize, "cellSize [m]");
    positive(tolerance, "tolerance [m]");
    positive(supportRadius, "supportRadius [m]");
    positive(pointTolerance, "pointTolerance [m]");
    positive(footHeight, "footHeight [m]");
    if (!(standHeight > pointTolerance && std::isfinite(standHeight)))
        throw std::invalid_argument("TerrainOptions.standHeight = " + std::to_string(standHeight) + ": must exceed pointTolerance");
    positive(sparseRadius, "sparseRadius [m]");
    if (sparseRadius / cellSize > 100)
        throw std::invalid_argument("TerrainOptions.sparseRadius = " + std::to_string(sparseRadius) +
                                    " m: at most 100 cells of cellSize (" + std::to_string(cellSize) + " m)");
    if (supportRadius / cellSize > 100)
        throw std::invalid_argument("TerrainOptions.supportRadius = " + std::to_string(supportRadius) +
                                    " m: at most 100 cells of cellSize (" + std::to_string(cellSize) + " m)");
    if (minScans < 1) throw std::invalid_argument("TerrainOptions.minScans = " + std::to_string(minScans) + ": must be >= 1");
    if (minAnchorPoints < 1)
        throw std::invalid_argument("TerrainOptions.minAnchorPoints = " + std::to_string(minAnchorPoints) + ": must be >= 1");
    if (!(maxSlope > 0 && maxSlope < 90)) throw std::invalid_argument("TerrainOptions.maxSlope = " + std::to_string(maxSlope) + ": must lie in (0, 90) deg");
    if (minSupport < 1) throw std::invalid_argument("TerrainOptions.minSupport = " + std::to_string(minSupport) + ": must be >= 1");
}

namespace {

/// The most cells of a scan's box that terrainSamples() indexes directly: 2^20 (4 MB of slots, a
/// 0.2 m grid 200 m across), more for clouds of more than 2^18 points (4 slots a point).
std::size_t denseCellLimit(std::size_t points) { return std::max<std::size_t>(std::size_t(1) << 20, 4 * points); }

/// A point of a scan that adds to a terrain sample: its index, label and cell.
struct SampledPoint {
    std::uint32_t index;
    bool ground;
    std::int32_t ix, iy;
};

/// Adds a point at height `z` to sample `c` (a sample's sums follow the input order of its points).
void addToSample(TerrainSample& c, float z, bool ground) {
    c.lowZ = std::min(c.lowZ, z), c.highZ = std::max(c.highZ, z);
    if (ground) ++c.groundCount, c.groundSumZ += z;
}

TerrainSample newSample(std::int32_t ix, std::int32_t iy, float z) {
    TerrainSample n;
    n.ix = ix, n.iy = iy, n.lowZ = n.highZ = z;
    return n;
}

/// The samples of the points of `ground` that `take(i, true)` accepts, then of those of
/// `nonGround` that `take(i, false)` accepts (see terrainSamples()); at most `most` points are
/// accepted in all. The cells of the accepted points' box are indexed directly where they are at
/// most denseCellLimit(most), else hashed.
template <class Take>
std::vector<TerrainSample> samplesOf(const PointCloudView& ground, const PointCloudView& nonGround, Take&& take,
                                     double cellSize, double maxRange, const Eigen::Vector3d& origin, std::size_t most) {
    if (!(std::isfinite(cellSize) && cellSize > 0)) throw std::invalid_argument("terrainSamples: cell size must be positive");
    if (most >= std::size_t(UINT32_MAX)) throw std::invalid_argument("terrainSamples: " + std::to_string(most) + " points: at most 2^32 - 2");
    // The points that count, in input order (ground first), with their cells and the cells' box.
    // Kept between scans (per thread): a scan's points in fresh pages cost more than sampling them.
    thread_local std::vector<SampledPoint> kept;
    if (kept.size() < most) kept.resize(most);
    SampledPoint* const points = kept.data();
    std::size_t count = 0;
    std::int32_t lo[2] = {INT32_MAX, INT32_MAX}, hi[2] = {INT32_MIN, INT32_MIN};
    auto accept = [&](const PointCloudView& pts, bool isGround) {
        for (std::size_t i = 0; i < pts.size(); ++i) {
            if (!take(i, isGround)) continue;
            const float* p = pts.point(i);
            if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
            const double dx = p[0] - origin.x(), dy = p[1] - origin.y(), dz = p[2] - origin.z();
            if (!(dx * dx + dy * dy + dz * dz <= maxRange * maxRange)) continue;
            std::int32_t ix = 0, iy = 0;
            if (!cellIndex(p[0], cellSize, ix) || !cellIndex(p[1], cellSize, iy)) continue;
            points[count++] = {std::uint32_t(i), isGround, ix, iy};
            lo[0] = std::min(lo[0], ix), hi[0] = std::max(hi[0], ix), lo[1] = std::min(lo[1], iy), hi[1] = std::max(hi[1], iy);
        }
    };
    accept(ground, true);
    accept(nonGround, false);
    std::vector<TerrainSample> out;
    if (count == 0) return out;
    const SampledPoint* const end = points + count;
    auto z = [&](const SampledPoint& s) { return (s.ground ? ground : nonGround).point(s.index)[2]; };
    const std::uint64_t nx = std::uint64_t(std::int64_t(hi[0]) - lo[0]) + 1, ny = std::uint64_t(std::int64_t(hi[1]) - lo[1]) + 1;
    if (nx * ny <= denseCellLimit(most)) {
        // The box's cells indexed directly, x-major: the points of a ring land in neighbouring
        // slots, and reading the slots in order gives the samples sorted by (ix, iy). The slots
        // are kept between scans (per thread), all 0 again on return (dropped if an allocation
        // fails on the way).
        thread_local std::vector<std::uint32_t> slots;  // 0: empty, else index into out + 1
        struct Dropped {
            std::vector<std::uint32_t>& slots;
            bool clean = false;
            ~Dropped() {
                if (!clean) slots = {};
            }
        } dropped{slots};
        if (slots.size() < nx * ny) slots.assign(nx * ny, 0);
        std::uint32_t* slot = slots.data();
        std::size_t last = SIZE_MAX;  // the last point's slot: a scan's next point mostly shares it
        out.reserve(count / 4);
        for (const SampledPoint* it = points; it != end; ++it) {
            const SampledPoint& s = *it;
            const std::size_t k = std::size_t(std::int64_t(s.ix) - lo[0]) * ny + std::size_t(std::int64_t(s.iy) - lo[1]);
            if (k != last) {
                if (!slot[k]) out.push_back(newSample(s.ix, s.iy, z(s))), slot[k] = std::uint32_t(out.size());
                last = k;
            }
            addToSample(out[slot[k] - 1], z(s), s.ground);
        }
        std::vector<TerrainSample> sorted;
        sorted.reserve(out.size());
        for (std::size_t k = 0, n = nx * ny; k < n && sorted.size() < out.size(); ++k)
            if (slot[k]) sorted.push_back(out[slot[k] - 1]), slot[k] = 0;
        dropped.clean = slots.size() <= denseCellLimit(0);  // a big cloud's buffers not kept
        if (kept.size() > denseCellLimit(0)) kept = {};
        return sorted;
    }
    // A box too large to index (points spread over a wide area): an open-addressing table from
    // the cell to its sample, sized by the points.
    std::size_t size = 64;
    while (size < 2 * count) size *= 2;
    std::vector<std::uint32_t> table(size, 0);  // 0: empty, else index into out + 1
    std::size_t last = 0;                        // the last point's sample + 1 (0: none)
    for (const SampledPoint* it = points; it != end; ++it) {
        const SampledPoint& s = *it;
        if (!(last && out[last - 1].ix == s.ix && out[last - 1].iy == s.iy)) {
            const std::uint64_t key = tileKey(s.ix, s.iy);
            std::size_t h = std::size_t((key * 0x9E3779B97F4A7C15ULL) >> 20) & (size - 1);
            while (table[h] && !(out[table[h] - 1].ix == s.ix && out[table[h] - 1].iy == s.iy)) h = (h + 1) & (size - 1);
            if (!table[h]) out.push_back(newSample(s.ix, s.iy, z(s))), table[h] = std::uint32_t(out.size());
            last = table[h];
        }
        addToSample(out[last - 1], z(s), s.ground);
    }
    std::sort(out.begin(), out.end(), [](const TerrainSample& a, const TerrainSample& b) { return a.ix != b.ix ? a.ix < b.ix : a.iy < b.iy; });
    if (kept.size() > denseCellLimit(0)) kept = {};
    return out;
}

}  // namespace

std::vector<TerrainSample> terrainSamples(const PointCloudView& ground, const PointCloudView& nonGround, double cellSize,
                                          double maxRange, const Eigen::Vector3d& origin) {
    return samplesOf(ground, nonGround, [](std::size_t, bool) { return true; }, cellSize, maxRange, origin, ground.size() + nonGround.size());
}

std::vector<TerrainSample> terrainSamples(const PointCloudView& points, const std::vector<std::uint8_t>& labels, double cellSize,
                                          double maxRange, const Eigen::Vector3d& origin) {
    if (labels.size() != points.size())
        throw std::invalid_argument("terrainSamples: " + std::to_string(labels.size()) + " labels for " + std::to_string(points.size()) + " points");
    // A point is taken as ground or as not, never both: at most points.size() in all.
    return samplesOf(points, points, [&](std::size_t i, bool ground) { return labels[i] == (ground ? 1 : 0); }, cellSize, maxRange, origin,
                     points.size());
}

TerrainModel::TerrainModel(const TerrainOptions& options) : options_(options) { options_.validate(); }
TerrainModel::~TerrainModel() = default;
TerrainModel::TerrainModel(TerrainModel&&) noexcept = default;
TerrainModel& TerrainModel::operator=(TerrainModel&&) noexcept = default;

TerrainCell* TerrainModel::findMutable(std::int32_t ix, std::int32_t iy) {
    const auto it = tiles_.find(tileKey(ix >> kTileBits, iy >> kTileBits));
    if (it == tiles_.end()) return nullptr;
    TerrainCell* c = &it->second->cells[std::size_t((iy & kTileMask) * kTileSize + (ix & kTileMask))];
    return c->lowScans == 0 ? nullptr : c;
}

const TerrainCell* TerrainModel::find(std::int32_t ix, std::int32_t iy) const {
    return const_cast<TerrainModel*>(this)->findMutable(ix, iy);
}

std::size_t TerrainModel::bytes() const { return tiles_.size() * (sizeof(Tile) + 4 * sizeof(void*)); }

void TerrainModel::add(const std::vector<TerrainSample>& samples) {
    ++scans_;
    std::uint64_t lastKey = 0;
    Tile* tile = nullptr;  // the last sample's tile: samples sorted by (ix, iy) share it in runs
    for (const TerrainSample& s : samples) {
        const std::uint64_t key = tileKey(s.ix >> kTileBits, s.iy >> kTileBits);
        if (!tile || key != lastKey) {
            auto& t = tiles_[key];
            if (!t) t = std::make_unique<Tile>();
            tile = t.get(), lastKey = key;
        }
        TerrainCell* c = &tile->cells[std::size_t((s.iy & kTileMask) * kTileSize + (s.ix & kTileMask))];
        if (c->lowScans == 0) {
            ++cells_;
            ++tile->used;
        }
        ++c->lowScans;
        c->lowSum += s.lowZ;
        c->lowMin = std::min(c->lowMin, s.lowZ), c->lowMax = std::max(c->lowMax, s.lowZ);
        c->highMax = std::max(c->highMax, s.highZ);
        if (s.groundCount > 0) {
            ++c->groundScans;
            c->groundCount = std::uint32_t(std::min<std::uint64_t>(std::uint64_t(c->groundCount) + s.groundCount, 0xffffffffu));
            c->groundSumZ += s.groundSumZ;
        }
    }
}

void TerrainModel::build() {
    // Every cell with evidence, in a fixed order (tile keys sorted, cells in tile order).
    std::vector<std::pair<std::uint64_t, Tile*>> tiles;
    tiles.reserve(tiles_.size());
    for (auto& [key, tile] : tiles_) tiles.emplace_back(key, tile.get());
    std::sort(tiles.begin(), tiles.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    struct Candidate {
        std::int32_t ix, iy;
        TerrainCell* cell;
        float* modelled;  ///< its slot in the tile's working copy
        std::uint8_t* modelledInRow;  ///< its row's count
        float z;
    };
    std::vector<Candidate> candidates;
    anchors_ = grown_ = 0;
    const float spreadLimit = float(2 * options_.tolerance);
    for (const auto& [key, tile] : tiles) {
        const std::int32_t tx = std::int32_t(std::uint32_t(key >> 32)), ty = std::int32_t(std::uint32_t(key));
        tile->modelled.fill(std::numeric_limits<float>::quiet_NaN());
        tile->modelledInRow.fill(0);
        for (std::int32_t j = 0; j < kTileSize * kTileSize; ++j) {
            TerrainCell& c = tile->cells[std::size_t(j)];
            if (c.lowScans == 0) continue;
            c.state = TerrainCell::None, c.elevation = std::numeric_limits<float>::quiet_NaN();
            if (c.groundScans >= std::uint32_t(options_.minScans) && c.groundCount >= std::uint64_t(options_.minAnchorPoints)) {
                c.state = TerrainCell::Anchor, c.elevation = float(c.groundSumZ / double(c.groundCount));
                tile->modelled[std::size_t(j)] = c.elevation;
                ++tile->modelledInRow[std::size_t(j >> kTileBits)];
                ++anchors_;
            } else if (c.lowScans >= std::uint32_t(options_.minScans) && c.lowMax - c.lowMin <= spreadLimit) {
                const std::int32_t ix = tx * kTileSize + (j & kTileMask), iy = ty * kTileSize + (j >> kTileBits);
                candidates.push_back({ix, iy, &c, &tile->modelled[std::size_t(j)], &tile->modelledInRow[std::size_t(j >> kTileBits)],
                                      float(c.lowSum / double(c.lowScans))});
            }
        }
    }
    // Waves: each judged against the model at its start; only candidates near a new cell again.
    const double cs = options_.cellSize;
    const double neighbourStep = options_.tolerance + cs * std::tan(options_.maxSlope * 3.14159265358979323846 / 180.0);
    // The two discs of support: within supportRadius, and within sparseRadius where the first holds
    // fewer than minSupport modelled cells. A disc row dy spans dx = -w..w (w = -1: no cell).
    struct Disc {
        int r = 0;                   ///< [cells] half the side of its square
        double r2 = 0;               ///< [cells^2] squared radius (with a margin for rounding)
        std::vector<int> halfWidth;  ///< per row dy + r
        bool holds(int dx, int dy) const { return double(dx * dx + dy * dy) <= r2; }
    };
    auto discOf = [&](double radius) {
        Disc d;
        d.r = int(std::ceil(radius / cs - 1e-9)), d.r2 = (radius / cs) * (radius / cs) * (1 + 1e-9);
        d.halfWidth.assign(std::size_t(2 * d.r + 1), -1);
        for (int dy = -d.r; dy <= d.r; ++dy)
            for (int dx = 0; dx <= d.r; ++dx)
                if (d.holds(dx, dy)) d.halfWidth[std::size_t(dy + d.r)] = dx;
        return d;
    };
    const Disc inner = discOf(options_.supportRadius), outer = discOf(std::max(options_.supportRadius, options_.sparseRadius));
    const int r = outer.r;
    // The tiles around a candidate's tile, found once per tile (candidates come tile by tile), so
    // a cell near it is an index, not a hash lookup.
    const int span = (r + kTileSize - 1) / kTileSize, side = 2 * span + 1;
    struct Near {
        const TerrainModel& model;
        int span, side;
        std::int32_t tx = 0, ty = 0;
        bool valid = false;
        std::vector<const Tile*> tiles;
        void centre(std::int32_t ix, std::int32_t iy) {
            const std::int32_t x = ix >> kTileBits, y = iy >> kTileBits;
            if (valid && x == tx && y == ty) return;
            tx = x, ty = y, valid = true;
            tiles.assign(std::size_t(side * side), nullptr);
            for (int j = -span; j <= span; ++j)
                for (int i = -span; i <= span; ++i) {
                    const auto it = model.tiles_.find(tileKey(tx + i, ty + j));
                    if (it != model.tiles_.end()) tiles[std::size_t((j + span) * side + i + span)] = it->second.get();
                }
        }
        /// The modelled elevations from cell (ix, iy) to the end of its tile's row, nullptr where the
        /// tile has no evidence or the row no modelled cell (within the span of the centre's tile).
        const float* row(std::int32_t ix, std::int32_t iy) const {
            const Tile* t = tiles[std::size_t(((iy >> kTileBits) - ty + span) * side + (ix >> kTileBits) - tx + span)];
            return t && t->modelledInRow[std::size_t(iy & kTileMask)] ? &t->modelled[std::size_t((iy & kTileMask) * kTileSize + (ix & kTileMask))]
                                                                       : nullptr;
        }
        /// The modelled elevation of cell (ix, iy) within the span of the centre's tile (NaN: none).
        float operator()(std::int32_t ix, std::int32_t iy) const {
            const Tile* t = tiles[std::size_t(((iy >> kTileBits) - ty + span) * side + (ix >> kTileBits) - tx + span)];
            return t ? t->modelled[std::size_t((iy & kTileMask) * kTileSize + (ix & kTileMask))] : std::numeric_limits<float>::quiet_NaN();
        }
    } near{*this, span, side, 0, 0, false, {}};
    // The highest minus the lowest modelled elevation within the radius of a candidate (only for
    // a support along a line, where the plane is not defined).
    auto spanOfDisc = [&](const Disc& d, std::int32_t cx, std::int32_t cy) {
        float lo = std::numeric_limits<float>::infinity(), hi = -lo;
        for (int dy = -d.r; dy <= d.r; ++dy) {
            const int w = d.halfWidth[std::size_t(dy + d.r)];
            for (int dx = -w; dx <= w; ++dx) {
                const float e = near(cx + dx, cy + dy);
                if (!std::isnan(e)) lo = std::min(lo, e), hi = std::max(hi, e);
            }
        }
        return double(hi) - double(lo);
    };
    // Least squares z = a + b dx + c dy over the modelled cells of a disc around (cx, cy) (centred
    // sums), row by row (dy, then dx), each row's cells read from at most two tiles' contiguous
    // rows; within a row the offsets' sums are integers (exact), the heights' in double. The
    // candidate's own cell is not modelled (NaN) while it is a candidate.
    struct Sums {
        double n = 0, sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, syy = 0, sxz = 0, syz = 0;
        Sums& operator+=(const Sums& o) {
            n += o.n, sx += o.sx, sy += o.sy, sz += o.sz, sxx += o.sxx, sxy += o.sxy, syy += o.syy, sxz += o.sxz, syz += o.syz;
            return *this;
        }
    };
    // `hole`: the sums of a smaller disc already taken (its cells left out here), or nullptr.
    auto sumsOver = [&](const Disc& d, std::int32_t cx, std::int32_t cy, const Disc* hole) {
        Sums s;
        for (int dy = -d.r; dy <= d.r; ++dy) {
            const int w = d.halfWidth[std::size_t(dy + d.r)];
            const int skip = hole && std::abs(dy) <= hole->r ? hole->halfWidth[std::size_t(dy + hole->r)] : -1;  // dx = -skip..skip taken (-1: none)
            const std::int32_t y = cy + dy;
            int rowN = 0, rowX = 0, rowXX = 0;
            double rowZ = 0, rowXZ = 0;
            for (int dx = -w; dx <= w;) {
                if (skip >= 0 && dx == -skip) {
                    dx = skip + 1;
                    continue;
                }
                const std::int32_t x = cx + dx;
                const int end = skip >= 0 && dx < -skip ? -skip - 1 : w;  // the run stops before the hole
                const int run = std::min(end - dx + 1, int(kTileSize - (x & kTileMask)));  // cells left in this tile's row
                const float* row = near.row(x, y);
                if (!row) {
                    dx += run;
                    continue;
                }
                for (int i = 0; i < run; ++i, ++dx) {
                    const float e = row[i];
                    if (std::isnan(e)) continue;
                    rowN += 1, rowX += dx, rowXX += dx * dx, rowZ += e, rowXZ += dx * double(e);
                }
            }
            if (rowN == 0) continue;
            s.n += rowN, s.sx += rowX * cs, s.sy += rowN * dy * cs, s.sz += rowZ;
            s.sxx += rowXX * cs * cs, s.sxy += rowX * dy * cs * cs, s.syy += rowN * dy * dy * cs * cs;
            s.sxz += rowXZ * cs, s.syz += dy * cs * rowZ;
        }
        return s;
    };
    // Candidates by cell (index + 1, 0: none), per tile, for the next wave's neighbourhood search.
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> candidateAt;
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        auto& tile = candidateAt[tileKey(candidates[k].ix >> kTileBits, candidates[k].iy >> kTileBits)];
        if (tile.empty()) tile.assign(std::size_t(kTileSize * kTileSize), 0);
        tile[std::size_t((candidates[k].iy & kTileMask) * kTileSize + (candidates[k].ix & kTileMask))] = std::uint32_t(k + 1);
    }
    std::vector<std::size_t> pending(candidates.size());
    for (std::size_t k = 0; k < pending.size(); ++k) pending[k] = k;
    std::vector<std::size_t> joined;
    std::vector<std::uint8_t> queued(candidates.size(), 0);
    std::vector<std::uint8_t> sparse(candidates.size(), 0);  ///< its inner disc held too few modelled cells (last judged)
    while (!pending.empty()) {
        joined.clear();
        for (const std::size_t k : pending) {
            const Candidate& cand = candidates[k];
            if (cand.cell->state != TerrainCell::None) continue;
            near.centre(cand.ix, cand.iy);
            bool level = true;  // no step to a modelled cell beside it (judged first: 8 cells, not the disc)
            for (int dy = -1; dy <= 1 && level; ++dy)
                for (int dx = -1; dx <= 1 && level; ++dx) {
                    const float e = (dx || dy) ? near(cand.ix + dx, cand.iy + dy) : std::numeric_limits<float>::quiet_NaN();
                    if (!std::isnan(e)) level = std::abs(double(cand.z) - double(e)) <= neighbourStep * std::hypot(double(dx), double(dy));
                }
            if (!level) continue;
            // Least squares z = a + b dx + c dy over the modelled cells of the inner disc, or of the
            // outer one where the inner holds too few.
            Sums s = sumsOver(inner, cand.ix, cand.iy, nullptr);
            const Disc* support = &inner;
            sparse[k] = s.n < options_.minSupport;
            if (sparse[k] && outer.r > inner.r) {  // the ring beyond the inner disc added
                s += sumsOver(outer, cand.ix, cand.iy, &inner);
                support = &outer;
            }
            const double n = s.n, sx = s.sx, sy = s.sy, sz = s.sz, sxx = s.sxx, sxy = s.sxy, syy = s.syy, sxz = s.sxz, syz = s.syz;
            if (n < options_.minSupport) continue;
            double predicted = sz / n;  // the support's mean where its cells do not span a plane
            const double cxx = sxx - sx * sx / n, cxy = sxy - sx * sy / n, cyy = syy - sy * sy / n;
            const double det = cxx * cyy - cxy * cxy, tr = cxx + cyy;
            const double minSpread = (tr - std::sqrt(std::max(0.0, tr * tr - 4 * det))) / (2 * n);  // [m^2] across the support
            if (minSpread > 0.2 * cs * cs) {
                const double cxz = sxz - sx * sz / n, cyz = syz - sy * sz / n;
                const double b = (cxz * cyy - cyz * cxy) / det, c = (cyz * cxx - cxz * cxy) / det;
                predicted = sz / n - b * sx / n - c * sy / n;  // the plane at the candidate (dx = dy = 0)
            } else if (spanOfDisc(*support, cand.ix, cand.iy) > options_.tolerance) {
                continue;  // a line of cells that is not level: no prediction across it
            }
            if (!(std::abs(double(cand.z) - predicted) <= options_.tolerance)) continue;
            joined.push_back(k);
        }
        for (const std::size_t k : joined) {
            candidates[k].cell->state = TerrainCell::Grown, candidates[k].cell->elevation = *candidates[k].modelled = candidates[k].z;
            ++*candidates[k].modelledInRow;
            ++grown_;
        }
        // The next wave: the candidates still out within the radius of a cell that joined.
        pending.clear();
        std::fill(queued.begin(), queued.end(), 0);
        if (joined.empty()) break;
        // A cell that joined may change the candidates within the inner disc around it, and beyond
        // it those whose inner support was too small (`sparse`). The outer disc row by row, each
        // row's candidates read from at most two tiles' rows.
        std::uint64_t lastKey = ~std::uint64_t(0);
        const std::vector<std::uint32_t>* lastTile = nullptr;
        for (const std::size_t k : joined)
            for (int dy = -r; dy <= r; ++dy) {
                const int w = outer.halfWidth[std::size_t(dy + r)];
                const int wi = std::abs(dy) <= inner.r ? inner.halfWidth[std::size_t(dy + inner.r)] : -1;  // within: every candidate
                const std::int32_t iy = candidates[k].iy + dy;
                for (int dx = -w; dx <= w;) {
                    const std::int32_t ix = candidates[k].ix + dx;
                    const int run = std::min(w - dx + 1, int(kTileSize - (ix & kTileMask)));
                    const std::uint64_t key = tileKey(ix >> kTileBits, iy >> kTileBits);
                    if (key != lastKey) {
                        lastKey = key;
                        const auto it = candidateAt.find(key);
                        lastTile = it == candidateAt.end() ? nullptr : &it->second;
                    }
                    if (!lastTile) {
                        dx += run;
                        continue;
                    }
                    const std::uint32_t* row = &(*lastTile)[std::size_t((iy & kTileMask) * kTileSize + (ix & kTileMask))];
                    for (int i = 0; i < run; ++i, ++dx) {
                        const std::uint32_t at = row[i];
                        if (at && !queued[at - 1] && candidates[at - 1].cell->state == TerrainCell::None && (std::abs(dx) <= wi || sparse[at - 1]))
                            queued[at - 1] = 1, pending.push_back(at - 1);
                    }
                }
            }
        std::sort(pending.begin(), pending.end());
    }
}

std::size_t TerrainModel::forgetFartherThan(double x, double y, double radius) {
    const double side = kTileSize * options_.cellSize;
    std::size_t dropped = 0;
    for (auto it = tiles_.begin(); it != tiles_.end();) {
        const double x0 = std::int32_t(std::uint32_t(it->first >> 32)) * side, y0 = std::int32_t(std::uint32_t(it->first)) * side;
        const double dx = std::max({0.0, x0 - x, x - (x0 + side)}), dy = std::max({0.0, y0 - y, y - (y0 + side)});
        if (dx * dx + dy * dy > radius * radius) {
            cells_ -= it->second->used;
            it = tiles_.erase(it);
            ++dropped;
        } else {
            ++it;
        }
    }
    return dropped;
}

void TerrainModel::forEachModelled(const std::function<void(std::int32_t, std::int32_t, const TerrainCell&)>& f) const {
    std::vector<std::uint64_t> keys;
    keys.reserve(tiles_.size());
    for (const auto& kv : tiles_) keys.push_back(kv.first);
    std::sort(keys.begin(), keys.end());
    for (const std::uint64_t key : keys) {
        const Tile& tile = *tiles_.at(key);
        const std::int32_t tx = std::int32_t(std::uint32_t(key >> 32)), ty = std::int32_t(std::uint32_t(key));
        for (std::int32_t j = 0; j < kTileSize * kTileSize; ++j) {
            const TerrainCell& c = tile.cells[std::size_t(j)];
            if (c.lowScans > 0 && c.state != TerrainCell::None) f(tx * kTileSize + (j & kTileMask), ty * kTileSize + (j >> kTileBits), c);
        }
    }
}

std::size_t TerrainModel::relabel(const PointCloudView& points, std::vector<std::uint8_t>& labels, std::size_t* promoted) const {
    if (labels.size() != points.size())
        throw std::invalid_argument("TerrainModel::relabel: " + std::to_string(labels.size()) + " labels for " +
                                    std::to_string(points.size()) + " points");
    std::size_t up = 0, down = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (labels[i] > 1) continue;
        const float* p = points.point(i);
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
        std::int32_t ix = 0, iy = 0;
        if (!cellIndex(p[0], options_.cellSize, ix) || !cellIndex(p[1], options_.cellSize, iy)) continue;
        const TerrainCell* c = find(ix, iy);
        if (!c || c->state == TerrainCell::None) continue;
        const double dz = double(p[2]) - double(c->elevation);
        // Only the two bands the rules act on look at the neighbours.
        if (labels[i] ? !(dz > options_.footHeight) : !(std::abs(dz) <= options_.pointTolerance)) continue;
        bool standing = false;
        for (int dy = -1; dy <= 1 && !standing; ++dy)
            for (int dx = -1; dx <= 1 && !standing; ++dx) {
                const TerrainCell* n = find(ix + dx, iy + dy);
                standing = n && double(n->highMax) > double(c->elevation) + options_.standHeight;
            }
        if (labels[i] && standing) labels[i] = 0, ++down;
        else if (!labels[i] && !standing) labels[i] = 1, ++up;
    }
    if (promoted) *promoted = up;
    return up + down;
}

}  // namespace gseg
