#include <gseg/mrpt/render.hpp>

#include <stdexcept>

namespace gseg::mrpt {

std::string topDownPng(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels, const RenderOptions& opt) {
    if (labels.size() != cloud.size())
        throw std::invalid_argument("topDownPng: " + std::to_string(labels.size()) + " labels for " +
                                    std::to_string(cloud.size()) + " points");
    // Label 1 is ground (class 0), label 0 non-ground (class 1, drawn over the ground).
    std::vector<std::uint8_t> classOf(labels.size());
    for (std::size_t i = 0; i < labels.size(); ++i) classOf[i] = labels[i] ? 0 : 1;
    return drawTopView(cloud, classOf, {{kGroundColour, "ground", 0}, {kNonGroundColour, "non-ground", 1}}, opt).png();
}

}  // namespace gseg::mrpt
