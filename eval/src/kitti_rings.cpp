#include <gseg/eval/kitti_rings.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace gseg::eval {

std::vector<std::uint32_t> kittiRings(const float* xyzi, std::size_t points, std::size_t minRingPoints) {
    std::vector<std::uint32_t> ring(points, 0);
    constexpr float kHalfTurn = 3.14159265358979f;
    std::uint32_t current = 0;
    std::size_t begun = 0;  // where the current ring began
    float before = 0.f;     // the azimuth of the point before [rad]
    for (std::size_t i = 0; i < points; ++i) {
        const float azimuth = std::atan2(xyzi[4 * i + 1], xyzi[4 * i]);
        if (i > 0 && azimuth - before < -kHalfTurn && i - begun > minRingPoints) ++current, begun = i;
        before = azimuth;
        ring[i] = current;
    }
    return ring;
}

std::vector<std::size_t> kittiThinned(const float* xyzi, std::size_t points, unsigned ringStep, unsigned pointStep) {
    if (ringStep == 0 || pointStep == 0) throw std::invalid_argument("kittiThinned: the ring and point steps must be at least 1");
    std::vector<std::size_t> kept;
    if (ringStep == 1 && pointStep == 1) {
        kept.resize(points);
        for (std::size_t i = 0; i < points; ++i) kept[i] = i;
        return kept;
    }
    const std::vector<std::uint32_t> ring = kittiRings(xyzi, points);
    for (std::size_t i = 0; i < points; i += pointStep)
        if (ring[i] % ringStep == 0) kept.push_back(i);
    return kept;
}

void thinKittiScan(std::vector<float>& xyzi, std::vector<std::uint32_t>& labels, unsigned ringStep, unsigned pointStep) {
    if (xyzi.size() != 4 * labels.size())
        throw std::invalid_argument("thinKittiScan: " + std::to_string(labels.size()) + " labels for " +
                                    std::to_string(xyzi.size() / 4) + " points");
    if (ringStep == 1 && pointStep == 1) return;  // every point kept (0 is refused below)
    const std::vector<std::size_t> kept = kittiThinned(xyzi.data(), labels.size(), ringStep, pointStep);
    for (std::size_t k = 0; k < kept.size(); ++k) {
        for (std::size_t c = 0; c < 4; ++c) xyzi[4 * k + c] = xyzi[4 * kept[k] + c];
        labels[k] = labels[kept[k]];
    }
    xyzi.resize(4 * kept.size()), labels.resize(kept.size());
}

}  // namespace gseg::eval
