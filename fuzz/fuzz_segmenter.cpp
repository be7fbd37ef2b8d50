// libFuzzer target: the segmenter fed arbitrary points and parameters, as the tools run it
// (gseg::mrpt::ScanSegmenter: non-finite points non-ground, distToGround: auto never refusing). Parameters come
// from the fuzzer as a YAML file, so the loader's validation and bounds apply as for a user.
// Properties: one label (0 or 1) per point, non-finite points non-ground, counters that add up,
// and determinism: the same labels again from the same segmenter and from a new one.
#include "fuzz_input.hpp"

#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/segment_scan.hpp>

#include <stdexcept>
#include <vector>

namespace {

struct Key {
    const char* name;
    double lo, hi;
    bool logScale, integer;
};

// Ranges a little wider than the loader accepts, so that its refusals are exercised too.
const Key kKeys[] = {
    {"distToGround", -120, 120, false, false},    {"robotRadius", 0, 120, false, false},
    {"cellSizeX", 0.01, 150, true, false},         {"cellSizeY", 0.01, 150, true, false},
    {"cellSizeZPhase1", 0.005, 1200, true, false}, {"cellSizeZPhase2", 0.005, 1200, true, false},
    {"gridGroundLevel", 0, 1, false, false},       {"minPointsPerCell", 2, 60, false, true},
    {"minPointsForPca", 2, 80, false, true},       {"lineRatioThreshold", 0.3, 1, false, false},
    {"planeRatioThreshold", 0.3, 1, false, false}, {"slopeThresholdDegrees", 0, 95, false, false},
    {"groundInlierThreshold", 0.001, 10, true, false}, {"minGroundInlierRatio", 0, 1, false, false},
    {"ransacMaxIterations", 1, 12000, true, true}, {"ransacConfidence", 0.01, 0.99999, false, false},
    {"ransacSeed", 0, 1e9, false, true},           {"centroidSearchRadius", 0.01, 120, true, false},
    {"heightGate", 0.001, 50, true, false},        {"sparsityLow", 0, 1, false, false},
    {"sparsityMedium", 0, 2, false, false},        {"maxGroundHeightDeviation", 0, 10, false, false},
    {"stripMinSpread", 0, 2, false, false},        {"seedHeightTolerance", 0.001, 20, true, false},
    {"recoveryThreshold", 0, 5, false, false},     {"belowGroundMargin", 0, 20, false, false},
    {"checkPlaneNormal", 0, 1, false, true},       {"recoverNearGround", 0, 1, false, true},
    {"sparseRecoveryThreshold", 0, 5, false, false},
    {"floatingMinHeight", 0, 5, false, false},     {"floatingMaxDepth", 0, 20, false, false},
    {"floatingIgnoresLowOutliers", 0, 1, false, true},
    {"bridgeRadius", 0.001, 1e13, true, false},    {"bridgeGate", 0, 5, false, false},
    {"bridgeGapGate", 0, 5, false, false},         {"bridgeMaxDrop", 0, 20, false, false},
    {"bridgeMaxAngleDegrees", -1, 95, false, false},
};

std::string parametersYaml(gseg::fuzz::FuzzInput& in) {
    std::string yaml;
    for (const Key& k : kKeys) {
        if (!in.flag()) continue;
        if (std::string(k.name) == "distToGround" && in.flag()) {
            yaml += "distToGround: auto\n";
            continue;
        }
        const double v = k.logScale ? in.logUniform(k.lo, k.hi) : in.uniform(k.lo, k.hi);
        yaml += std::string(k.name) + ": " + (k.integer ? std::to_string(std::llround(v)) : std::to_string(v)) + "\n";
    }
    return yaml;
}

// Points: raw float bit patterns, centimetre grids, or a noisy ground plane with clutter.
std::vector<float> points(gseg::fuzz::FuzzInput& in) {
    const int mode = in.take<std::uint8_t>() % 3;
    const double ground = -in.uniform(0, 3);
    std::vector<float> xyz;
    while (in.remaining() > 0 && xyz.size() < 3 * 30000) {
        if (mode == 0) {
            xyz.insert(xyz.end(), {in.anyFloat(), in.anyFloat(), in.anyFloat()});
        } else if (mode == 1) {
            xyz.insert(xyz.end(), {0.01f * in.take<std::int16_t>(), 0.01f * in.take<std::int16_t>(),
                                   0.01f * in.take<std::int16_t>()});
        } else {
            const float x = 0.01f * in.take<std::int16_t>(), y = 0.01f * in.take<std::int16_t>();
            const std::uint8_t z = in.take<std::uint8_t>();
            xyz.insert(xyz.end(), {x, y, float(ground) + (z < 200 ? 0.002f * z : 0.05f * (z - 200))});
        }
    }
    return xyz;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    gseg::fuzz::FuzzInput in(data, size);
    gseg::mrpt::LoadedConfig cfg;
    try {
        cfg = gseg::mrpt::loadConfigFromText(parametersYaml(in), gseg::mrpt::ConfigFormat::Yaml, "fuzz.yaml");
    } catch (const std::runtime_error&) {
        return 0;  // refused like a user's file
    }
    const std::vector<float> xyz = points(in);
    const gseg::PointCloudView cloud(xyz.data(), xyz.size() / 3);
    gseg::mrpt::ScanSegmenter segmenter(cfg);
    gseg::mrpt::ScanSegmentation first;
    first = segmenter.segment(cloud);  // never refuses a scan (auto falls back to a height)
    const gseg::Result& r = first.result;
    GSEG_FUZZ_CHECK(r.labels.size() == cloud.size());
    GSEG_FUZZ_CHECK(r.numGround + r.numNonGround == cloud.size());
    std::size_t ground = 0, nonFinite = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        GSEG_FUZZ_CHECK(r.labels[i] <= 1);
        ground += r.labels[i];
        const bool finite = std::isfinite(cloud.x(i)) && std::isfinite(cloud.y(i)) && std::isfinite(cloud.z(i));
        nonFinite += !finite;
        if (!finite) GSEG_FUZZ_CHECK(r.labels[i] == 0);
    }
    GSEG_FUZZ_CHECK(ground == r.numGround);
    GSEG_FUZZ_CHECK(nonFinite == r.numNonFinite);
    for (std::uint32_t i : r.belowGround) GSEG_FUZZ_CHECK(i < cloud.size() && r.labels[i] == 0);
    GSEG_FUZZ_CHECK(segmenter.segment(cloud).result.labels == r.labels);                   // the same object again
    GSEG_FUZZ_CHECK(gseg::mrpt::ScanSegmenter(cfg).segment(cloud).result.labels == r.labels);  // a new one
    return 0;
}
