#include <gseg/below_ground.hpp>
#include <gseg/grid.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace gseg {

std::vector<std::uint32_t> flagBelowGround(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                                           const Params& params, BelowGroundScratch& scratch) {
    std::vector<std::uint32_t> finitePoints;
    std::vector<GroundColumn> columns;
    for (std::uint32_t i = 0; i < std::uint32_t(cloud.size()); ++i) {
        if (!std::isfinite(cloud.x(i)) || !std::isfinite(cloud.y(i)) || !std::isfinite(cloud.z(i))) continue;
        finitePoints.push_back(i);
        if (labels[i])
            columns.push_back({cellCoord(cloud.x(i), params.cellSizeX), cellCoord(cloud.y(i), params.cellSizeY), cloud.z(i)});
    }
    return flagBelowGround(cloud, finitePoints, labels, columns, params, scratch);
}

// A dense map of the ground's columns: the lowest ground point per column, then spread to the
// columns without ground one ring out, then two rings out.
std::vector<std::uint32_t> flagBelowGround(const PointCloudView& cloud, const std::vector<std::uint32_t>& finitePoints,
                                           const std::vector<std::uint8_t>& labels, const std::vector<GroundColumn>& groundColumns,
                                           const Params& params, BelowGroundScratch& scratch) {
    std::vector<std::uint32_t> flagged;
    if (!(params.belowGroundMargin > 0) || groundColumns.empty()) return flagged;
    constexpr float kNone = std::numeric_limits<float>::infinity();
    constexpr int kPad = 2;
    std::int32_t lo[2] = {std::numeric_limits<std::int32_t>::max(), std::numeric_limits<std::int32_t>::max()};
    std::int32_t hi[2] = {std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::min()};
    for (const GroundColumn& c : groundColumns) {
        lo[0] = std::min(lo[0], c.ix), hi[0] = std::max(hi[0], c.ix);
        lo[1] = std::min(lo[1], c.iy), hi[1] = std::max(hi[1], c.iy);
    }
    const std::int64_t w = std::int64_t(hi[0]) - lo[0] + 1 + 2 * kPad, h = std::int64_t(hi[1]) - lo[1] + 1 + 2 * kPad;
    if (w * h > std::int64_t(16) << 20) return flagged;  // absurdly spread ground: no reference worth a map
    auto& ground = scratch.ground;
    ground.assign(std::size_t(w * h), kNone);
    auto at = [&](std::int64_t ix, std::int64_t iy) { return std::size_t((ix - lo[0] + kPad) * h + (iy - lo[1] + kPad)); };
    for (const GroundColumn& c : groundColumns) {
        float& g = ground[at(c.ix, c.iy)];
        g = std::min(g, c.lowest);
    }
    float highest = -kNone;  // no point above the highest ground minus the margin can be flagged
    for (float g : ground)
        if (g != kNone) highest = std::max(highest, g);
    // Columns without ground take the lowest ground one ring out, then two rings out.
    auto& next = scratch.next;
    for (int ring = 0; ring < kPad; ++ring) {
        next = ground;
        for (std::int64_t x = 1; x + 1 < w; ++x)
            for (std::int64_t y = 1; y + 1 < h; ++y) {
                float& v = next[std::size_t(x * h + y)];
                if (v != kNone) continue;
                for (int dx = -1; dx <= 1; ++dx)
                    for (int dy = -1; dy <= 1; ++dy) v = std::min(v, ground[std::size_t((x + dx) * h + y + dy)]);
            }
        ground.swap(next);
    }
    const double below = double(highest) - params.belowGroundMargin;
    for (std::uint32_t i : finitePoints) {
        if (labels[i] || double(cloud.z(i)) >= below) continue;
        const std::int64_t ix = cellCoord(cloud.x(i), params.cellSizeX), iy = cellCoord(cloud.y(i), params.cellSizeY);
        if (ix < lo[0] - kPad || ix > hi[0] + kPad || iy < lo[1] - kPad || iy > hi[1] + kPad) continue;
        const float g = ground[at(ix, iy)];
        if (g != kNone && double(cloud.z(i)) < double(g) - params.belowGroundMargin) flagged.push_back(i);
    }
    return flagged;
}

}  // namespace gseg
