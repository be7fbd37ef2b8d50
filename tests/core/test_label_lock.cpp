// The label lock (issue #21): the segmenter's labels, byte for byte, on every shared labelled scan
// (semantickitti, semantickitti-extra, the 40 frames of semantickitti-drives), on mrpt-common's
// VLP-16 rawlog scan and on every simulated scene of tests/support/scenes.cpp, each with a fixed
// and with an estimated (`distToGround: auto`) sensor height, against the golden FNV-1a 64 hashes
// in tests/label_hashes.txt (how to regenerate them: see that file's header). A speed-up must not
// change a label; a deliberate change of the rules regenerates the file and says why in its commit.
#include <gseg/ground_segmenter.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/scan_source.hpp>
#include <gseg/mrpt/segment_scan.hpp>
#include <gseg/sensor_height.hpp>
#include <support/paths.hpp>
#include <support/scenes.hpp>

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

const std::string kGolden = std::string(GSEG_SOURCE_DIR) + "/tests/label_hashes.txt";
const std::string kVlp16 = "/usr/share/mrpt/datasets/test_velodyne_VLP16.rawlog";

/// FNV-1a 64 of the label bytes.
std::uint64_t fnv1a64(const std::vector<std::uint8_t>& bytes) {
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (std::uint8_t b : bytes) h = (h ^ b) * 0x100000001b3ull;
    return h;
}

std::string hex(std::uint64_t h) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
}

/// name -> "points hash", from the golden file (comment lines start with #).
std::map<std::string, std::string> readGolden() {
    std::map<std::string, std::string> out;
    std::istringstream in(gseg::test::readText(kGolden));
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream l(line);
        std::string name, points, hash;
        l >> name >> points >> hash;
        out[name] = points + " " + hash;
    }
    return out;
}

/// Computes the labels' hash of one case; `segment()` segments.
template <class Segment>
void check(const std::string& name, const std::map<std::string, std::string>& golden, std::ostream* write,
           Segment segment) {
    const std::vector<std::uint8_t> labels = segment();
    const std::string got = std::to_string(labels.size()) + " " + hex(fnv1a64(labels));
    if (write) {
        *write << name << " " << got << "\n";
        return;
    }
    const auto it = golden.find(name);
    ASSERT_NE(it, golden.end()) << name << ": no golden hash in " << kGolden << " (regenerate it, see its header)";
    EXPECT_EQ(got, it->second) << name << ": the labels changed";
}

/// The labelled scans of the shared data (KITTI .bin with a .label beside), sorted.
std::vector<std::string> sharedScans() {
    std::vector<std::string> scans;
    for (const char* root : {"semantickitti", "semantickitti-extra", "semantickitti-drives"}) {
        const std::string top = gseg::test::sharedData(std::string(root) + "/sequences");
        if (top.empty()) continue;
        for (const auto& seq : fs::directory_iterator(top)) {
            if (!fs::is_directory(seq.path() / "labels")) continue;
            for (const auto& label : fs::directory_iterator(seq.path() / "labels")) {
                if (label.path().extension() != ".label") continue;
                const fs::path bin = seq.path() / "velodyne" / (label.path().stem().string() + ".bin");
                if (fs::exists(bin)) scans.push_back(bin.string());
            }
        }
    }
    std::sort(scans.begin(), scans.end());
    return scans;
}

/// "semantickitti-extra/02/000009" for .../semantickitti-extra/sequences/02/velodyne/000009.bin.
std::string scanName(const std::string& bin) {
    const fs::path p(bin);
    const fs::path seq = p.parent_path().parent_path();
    return seq.parent_path().parent_path().filename().string() + "/" + seq.filename().string() + "/" + p.stem().string();
}

/// Segments a real scan as the tools do (gseg::mrpt::ScanSegmenter) with `config`.
std::vector<std::uint8_t> segmentReal(const gseg::mrpt::Scan& scan, const gseg::mrpt::LoadedConfig& config) {
    gseg::mrpt::ScanSegmenter seg(config);
    return seg.segment(gseg::PointCloudView(scan.xyzi.data(), scan.size(), 16), false, gseg::mrpt::HeightCheck::Never)
        .result.labels;
}

std::ostream* writeTarget(std::ofstream& file) {
    const char* out = std::getenv("GSEG_LABEL_HASHES_OUT");
    if (!out || !*out) return nullptr;
    file.open(out, std::ios::app);
    return &file;
}

}  // namespace

TEST(LabelLock, SharedLabelledScansFixedAndAutoHeight) {
    const auto scans = sharedScans();
    if (scans.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences");
    EXPECT_EQ(scans.size(), 60u) << "the shared data holds 60 labelled scans (4 + 16 + 40: four drives of 10)";
    const auto golden = readGolden();
    std::ofstream file;
    std::ostream* write = writeTarget(file);
    const auto fixed = gseg::mrpt::loadConfig(std::string(GSEG_SOURCE_DIR) + "/config/kitti_hdl64.yaml");
    const auto autoHeight = gseg::mrpt::loadConfig(std::string(GSEG_SOURCE_DIR) + "/config/auto_height.yaml");
    ASSERT_TRUE(autoHeight.distToGroundAuto);
    for (const auto& bin : scans) {
        const gseg::mrpt::Scan scan = gseg::mrpt::loadScan(bin);
        check("kitti/" + scanName(bin) + "/fixed", golden, write, [&] { return segmentReal(scan, fixed); });
        check("kitti/" + scanName(bin) + "/auto", golden, write, [&] { return segmentReal(scan, autoHeight); });
    }
}

TEST(LabelLock, MrptCommonVlp16ScanFixedAndAutoHeight) {
    if (!fs::exists(kVlp16)) GTEST_SKIP() << kVlp16 << " is absent (Debian package mrpt-common): skipped";
    const auto golden = readGolden();
    std::ofstream file;
    std::ostream* write = writeTarget(file);
    const gseg::mrpt::Scan scan = gseg::mrpt::loadScan(kVlp16);
    const auto fixed = gseg::mrpt::loadConfig(std::string(GSEG_SOURCE_DIR) + "/config/kitti_hdl64.yaml");
    const auto vlp16 = gseg::mrpt::loadConfig(std::string(GSEG_SOURCE_DIR) + "/config/vlp16.yaml");
    check("vlp16/kitti_hdl64/fixed", golden, write, [&] { return segmentReal(scan, fixed); });
    check("vlp16/vlp16/auto", golden, write, [&] { return segmentReal(scan, vlp16); });
}

TEST(LabelLock, SimulatedScenesFixedAndAutoHeight) {
    const auto golden = readGolden();
    std::ofstream file;
    std::ostream* write = writeTarget(file);
    const auto scenes = gseg::test::allScenes();
    EXPECT_GE(scenes.size(), 20u);
    for (const auto& n : scenes) {
        const gseg::PointCloudView view(n.scan.xyz.data(), n.scan.size());
        check("scene/" + n.name + "/fixed", golden, write, [&] {
            gseg::Params p;
            p.distToGround = n.sensorHeight;
            p.centroidSearchRadius = n.searchRadius;
            return gseg::GroundSegmenter(p).segment(view).labels;
        });
        check("scene/" + n.name + "/auto", golden, write, [&] {
            gseg::Params p;
            p.centroidSearchRadius = n.searchRadius;
            return gseg::AutoHeightSegmenter(p).segment(view).result.labels;
        });
    }
}
