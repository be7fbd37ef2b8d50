#include <gseg/grid.hpp>
#include <gseg/sensor_height.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

namespace gseg {

SensorHeightEstimate estimateSensorHeight(const PointCloudView& cloud, const SensorHeightOptions& o) {
    struct Column {
        float lowest = std::numeric_limits<float>::infinity();
        int count = 0;
    };
    std::unordered_map<std::uint64_t, Column> columns;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const float x = cloud.x(i), y = cloud.y(i), z = cloud.z(i);
        if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) continue;
        const double r = std::hypot(double(x), double(y));
        if (r < o.minRange || r > o.maxRange) continue;
        const std::uint64_t key = (std::uint64_t(std::uint32_t(cellCoord(x, o.columnSize))) << 32) |
                                  std::uint32_t(cellCoord(y, o.columnSize));
        Column& c = columns[key];
        c.lowest = std::min(c.lowest, z);
        ++c.count;
    }
    std::vector<double> votes;
    for (const auto& [key, c] : columns)
        if (c.count >= o.minColumnPoints) votes.push_back(c.lowest);
    SensorHeightEstimate e;
    e.columns = int(votes.size());
    if (e.columns < o.minColumns) return e;
    auto median = [](std::vector<double> v) {
        std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
        return v[v.size() / 2];
    };
    const double ground = median(votes);
    std::vector<double> dev;
    for (double v : votes) dev.push_back(std::abs(v - ground));
    e.valid = ground < 0;  // ground above the sensor: not a ground vehicle's scan
    e.height = -ground;
    e.spread = median(dev);
    return e;
}

}  // namespace gseg
