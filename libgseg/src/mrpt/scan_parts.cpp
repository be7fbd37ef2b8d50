#include <gseg/mrpt/scan_parts.hpp>
#include <gseg/text.hpp>

#include <cstring>

namespace gseg::mrpt {

ScanPart scanPartOfLabel(const std::string& label) {
    if (endsWith(label, kGroundSuffix)) return ScanPart::Ground;
    if (endsWith(label, kObstaclesSuffix)) return ScanPart::Obstacles;
    return ScanPart::Raw;
}

std::string baseLabelOf(const std::string& label) {
    const ScanPart part = scanPartOfLabel(label);
    const std::size_t cut = part == ScanPart::Ground ? std::strlen(kGroundSuffix) : part == ScanPart::Obstacles ? std::strlen(kObstaclesSuffix) : 0;
    return label.substr(0, label.size() - cut);
}

std::string partLabel(const std::string& base, ScanPart part) {
    return part == ScanPart::Ground ? base + kGroundSuffix : part == ScanPart::Obstacles ? base + kObstaclesSuffix : base;
}

}  // namespace gseg::mrpt
