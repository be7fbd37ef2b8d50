#include <gseg/mrpt/render.hpp>

#include <mrpt/img/CImage.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <unistd.h>

namespace gseg::mrpt {
namespace {

double fitRange(const PointCloudView& cloud) {
    std::vector<float> r(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) r[i] = std::hypot(cloud.x(i), cloud.y(i));
    if (r.empty()) return 10.0;
    const std::size_t k = std::min(r.size() - 1, std::size_t(0.98 * double(r.size())));
    std::nth_element(r.begin(), r.begin() + long(k), r.end());
    return std::clamp(double(r[k]) * 1.05, 5.0, 80.0);
}

}  // namespace

void writeTopDownPng(const std::string& path, const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                     const RenderOptions& opt) {
    if (labels.size() != cloud.size())
        throw std::invalid_argument("writeTopDownPng: " + std::to_string(labels.size()) + " labels for " +
                                    std::to_string(cloud.size()) + " points");
    const int size = std::max(100, opt.sizePx);
    const double range = opt.rangeM > 0 ? opt.rangeM : fitRange(cloud);
    const double scale = 0.5 * size / range;  // px per metre
    const int c = size / 2;
    ::mrpt::img::CImage img(size, size, ::mrpt::img::CH_RGB);
    img.filledRectangle(0, 0, size - 1, size - 1, ::mrpt::img::TColor(20, 20, 28));
    for (double ring = opt.ringStepM; opt.ringStepM > 0 && ring <= range * 1.5; ring += opt.ringStepM)
        img.drawCircle(c, c, int(ring * scale), ::mrpt::img::TColor(70, 70, 80));

    std::size_t ground = 0;
    auto draw = [&](std::uint8_t label, const ::mrpt::img::TColor& colour) {
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (labels[i] != label) continue;
            const int u = c - int(std::lround(cloud.y(i) * scale));  // y (left) to the left
            const int v = c - int(std::lround(cloud.x(i) * scale));  // x (forward) up
            if (u < 0 || v < 0 || u >= size - 1 || v >= size - 1) continue;
            img.filledRectangle(u, v, u + 1, v + 1, colour);
        }
    };
    for (std::uint8_t l : labels) ground += l;
    draw(1, ::mrpt::img::TColor(40, 200, 60));
    draw(0, ::mrpt::img::TColor(235, 60, 40));
    img.line(c - 6, c, c + 6, c, ::mrpt::img::TColor(255, 255, 255), 2);
    img.line(c, c - 6, c, c + 6, ::mrpt::img::TColor(255, 255, 255), 2);

    char legend[160];
    std::snprintf(legend, sizeof legend, "ground %zu (green)  non-ground %zu (red)  circles every %.0f m",
                  ground, cloud.size() - ground, opt.ringStepM);
    if (!opt.title.empty()) img.textOut(8, 8, opt.title, ::mrpt::img::TColor(230, 230, 230));
    img.textOut(8, size - 20, legend, ::mrpt::img::TColor(230, 230, 230));

    // Atomic: CImage picks the format from the extension, so the temporary keeps ".png".
    const std::string tmp = path + ".tmp" + std::to_string(::getpid()) + ".png";
    if (!img.saveToFile(tmp)) {
        std::remove(tmp.c_str());
        throw std::runtime_error(path + ": cannot write the PNG");
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        std::remove(tmp.c_str());
        throw std::runtime_error(path + ": cannot move the PNG into place");
    }
}

}  // namespace gseg::mrpt
