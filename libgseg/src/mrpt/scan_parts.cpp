#include <gseg/mrpt/scan_parts.hpp>

#include <cstring>

namespace gseg::mrpt {

bool endsWith(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

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
