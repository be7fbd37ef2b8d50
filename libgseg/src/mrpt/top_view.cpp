// The top view of one scan: its points by class, range circles, the sensor and its direction.
#include <gseg/mrpt/top_view.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace gseg::mrpt {
namespace {

double fitRange(const PointCloudView& cloud) {
    std::vector<float> r;
    r.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (const float d = std::hypot(cloud.x(i), cloud.y(i)); std::isfinite(d)) r.push_back(d);
    if (r.empty()) return 10.0;
    const std::size_t k = std::min(r.size() - 1, std::size_t(0.98 * double(r.size())));
    std::nth_element(r.begin(), r.begin() + long(k), r.end());
    return std::clamp(double(r[k]) * 1.05, 5.0, 80.0);
}

}  // namespace

const char* const kTopViewOrientation = "top view: x (forward) up, y (left) to the left";

Picture drawTopView(const PointCloudView& cloud, const std::vector<std::uint8_t>& classOf,
                    const std::vector<PointClass>& classes, const TopViewOptions& opt) {
    if (classOf.size() != cloud.size())
        throw std::invalid_argument("drawTopView: " + std::to_string(classOf.size()) + " classes for " +
                                    std::to_string(cloud.size()) + " points");
    const int size = std::max(300, opt.sizePx), c = size / 2;
    const double range = opt.rangeM > 0 ? opt.rangeM : fitRange(cloud);
    const double scale = 0.5 * size / range;  // px per metre
    Picture pic(size, size, {24, 24, 30});
    const Colour ringColour{70, 70, 82}, white{255, 255, 255};
    const bool rings = opt.ringStepM > 0 && opt.ringStepM >= range / 100;
    for (double ring = opt.ringStepM; rings && ring <= range * 1.5; ring += opt.ringStepM)
        pic.circle(c, c, int(ring * scale), ringColour);

    std::vector<std::size_t> counts(classes.size(), 0);
    for (std::uint8_t k : classOf)
        if (k < classes.size()) ++counts[k];
    std::vector<std::size_t> order(classes.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return classes[a].layer < classes[b].layer; });
    for (const std::size_t k : order) {
        const int lo = (std::max(1, classes[k].sizePx) - 1) / 2, hi = std::max(1, classes[k].sizePx) - 1 - lo;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (classOf[i] != k) continue;
            const double u = c - std::round(cloud.y(i) * scale);  // y (left) to the left
            const double v = c - std::round(cloud.x(i) * scale);  // x (forward) up
            if (!(u >= lo && v >= lo && u < size - hi && v < size - hi)) continue;  // also NaN
            pic.fill(int(u) - lo, int(v) - lo, int(u) + hi, int(v) + hi, classes[k].colour);
        }
    }
    // The sensor and its forward direction.
    pic.line(c - 6, c, c + 6, c, white, 2);
    pic.arrow(c, c + 6, 0, -46, "x (forward)");

    char subtitle[160];
    std::snprintf(subtitle, sizeof subtitle, "%s; sensor at the centre, %.0f m each side", kTopViewOrientation, range);
    pic.title(opt.title, subtitle);
    std::vector<LegendEntry> legend;
    for (std::size_t k = 0; k < classes.size(); ++k) legend.push_back({classes[k].colour, classes[k].name + ": " + std::to_string(counts[k])});
    if (rings) legend.push_back({ringColour, "range circles every " + metresLabel(opt.ringStepM)});
    legend.push_back({white, "sensor (+) and its forward direction (arrow)"});
    pic.legend(12, size - 12 - Picture::legendHeight(legend.size()), legend);
    pic.scaleBar(size - 24, size - 24, scale);
    return pic;
}

}  // namespace gseg::mrpt
