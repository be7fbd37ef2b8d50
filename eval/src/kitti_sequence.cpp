#include <gseg/eval/kitti_sequence.hpp>

#include <algorithm>
#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;

namespace gseg::eval {

std::optional<std::size_t> kittiFrameNumber(const std::string& name, std::size_t maxDigits) {
    if (name.empty() || name.size() > std::min<std::size_t>(maxDigits, 18) ||
        name.find_first_not_of("0123456789") != std::string::npos)
        return std::nullopt;
    return std::size_t(std::stoull(name));
}

std::vector<KittiScan> listKittiScans(const std::string& sequenceDir) {
    const fs::path seq(sequenceDir), velodyne = seq / "velodyne";
    std::vector<KittiScan> scans;
    try {
        for (const auto& bin : fs::directory_iterator(velodyne))
            if (bin.path().extension() == ".bin") {
                const std::string name = bin.path().stem().string();
                scans.push_back({name, bin.path().string(), (seq / "labels" / (name + ".label")).string()});
            }
    } catch (const fs::filesystem_error& e) {
        throw std::runtime_error(velodyne.string() + ": cannot list the scans (" + e.code().message() + ")");
    }
    std::sort(scans.begin(), scans.end(), [](const KittiScan& a, const KittiScan& b) { return a.name < b.name; });
    return scans;
}

}  // namespace gseg::eval
