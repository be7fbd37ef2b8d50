// YAML and INI configuration files, PLY reading/writing.
#include <gseg/io/ply.hpp>
#include <gseg/mrpt/config.hpp>

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

namespace {

std::string writeTemp(const std::string& name, const std::string& text) {
    const std::string path = std::string(GSEG_BINARY_DIR) + "/tests/" + name;
    std::ofstream(path, std::ios::binary) << text;
    return path;
}

std::string errorOf(const std::string& path) {
    try {
        gseg::mrpt::loadConfig(path);
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(Config, ShippedKittiFileIsTheLibraryDefaultsWithEveryKey) {
    const std::string path = std::string(GSEG_SOURCE_DIR) + "/config/kitti_hdl64.yaml";
    const auto cfg = gseg::mrpt::loadConfig(path);
    EXPECT_FALSE(cfg.distToGroundAuto);
    EXPECT_DOUBLE_EQ(cfg.params.distToGround, 1.723);
    EXPECT_DOUBLE_EQ(cfg.params.robotRadius, 2.7);
    EXPECT_DOUBLE_EQ(cfg.params.cellSizeX, 1.5);
    EXPECT_DOUBLE_EQ(cfg.params.cellSizeY, 1.0);
    EXPECT_DOUBLE_EQ(cfg.params.cellSizeZPhase1, 1.5);
    EXPECT_DOUBLE_EQ(cfg.params.cellSizeZPhase2, 0.2);
    EXPECT_DOUBLE_EQ(cfg.params.slopeThresholdDegrees, 30.0);
    EXPECT_DOUBLE_EQ(cfg.params.groundInlierThreshold, 0.125);
    EXPECT_DOUBLE_EQ(cfg.params.centroidSearchRadius, 5.0);
    // One source of truth: every key of the file is the library default.
    const gseg::Params defaults;
    for (const auto& key : gseg::Params::keys()) EXPECT_EQ(cfg.params.get(key), defaults.get(key)) << key;
    std::ifstream in(path);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (const auto& key : gseg::Params::keys())
        EXPECT_NE(text.find("\n" + key + ":"), std::string::npos) << key << " missing from " << path;
    // config/auto_height.yaml: the same with distToGround: auto (the numeric value is the fallback).
    const auto autoCfg = gseg::mrpt::loadConfig(std::string(GSEG_SOURCE_DIR) + "/config/auto_height.yaml");
    EXPECT_TRUE(autoCfg.distToGroundAuto);
    for (const auto& key : gseg::Params::keys()) EXPECT_EQ(autoCfg.params.get(key), defaults.get(key)) << key;
}

TEST(Config, ShippedVlp16File) {
    const auto cfg = gseg::mrpt::loadConfig(std::string(GSEG_SOURCE_DIR) + "/config/vlp16.yaml");
    EXPECT_TRUE(cfg.distToGroundAuto);
    EXPECT_DOUBLE_EQ(cfg.params.cellSizeX, gseg::Params().cellSizeX);  // not given: default
}

TEST(Config, YamlAndIniGiveIdenticalParams) {
    const auto y = gseg::mrpt::loadConfig(
        writeTemp("same.yaml", "distToGround: 0.9\ncellSizeX: 1.25\nransacSeed: 7\nminPointsForPca: 8\n"));
    const auto i = gseg::mrpt::loadConfig(
        writeTemp("same.ini", "[gseg]\ndistToGround = 0.9 ; metres\ncellSizeX = 1.25\nransacSeed = 7\nminPointsForPca = 8\n"));
    for (const auto& key : gseg::Params::keys()) EXPECT_EQ(y.params.get(key), i.params.get(key)) << key;
    EXPECT_DOUBLE_EQ(y.params.cellSizeX, 1.25);
    EXPECT_EQ(y.params.minPointsForPca, 8);
}

TEST(Config, NestedUnderGsegAndAuto) {
    const auto cfg = gseg::mrpt::loadConfig(writeTemp("nested.yaml", "gseg:\n  distToGround: auto\n  heightGate: 0.4\n"));
    EXPECT_TRUE(cfg.distToGroundAuto);
    EXPECT_DOUBLE_EQ(cfg.params.heightGate, 0.4);
    EXPECT_NE(gseg::mrpt::toYaml(cfg).find("distToGround: auto"), std::string::npos);
}

TEST(Config, ErrorsNameFileAndKey) {
    const std::string unknown = writeTemp("unknown.yaml", "cellSizeX: 1.5\ncelSizeY: 1.0\n");
    EXPECT_NE(errorOf(unknown).find("celSizeY"), std::string::npos) << errorOf(unknown);
    EXPECT_NE(errorOf(unknown).find(unknown), std::string::npos);
    const std::string negative = writeTemp("negative.yaml", "cellSizeX: -1.5\n");
    EXPECT_NE(errorOf(negative).find("cellSizeX"), std::string::npos) << errorOf(negative);
    const std::string text = writeTemp("text.ini", "[gseg]\nslopeThresholdDegrees = steep\n");
    EXPECT_NE(errorOf(text).find("slopeThresholdDegrees"), std::string::npos) << errorOf(text);
    EXPECT_NE(errorOf("/nonexistent/gseg.yaml").find("cannot open"), std::string::npos);
    EXPECT_NE(errorOf(writeTemp("nosection.ini", "[other]\na = 1\n")).find("[gseg]"), std::string::npos);
    EXPECT_NE(errorOf(writeTemp("x.toml", "a = 1\n")).find("unknown configuration format"), std::string::npos);
}

TEST(Ply, WrittenCloudReadsBackWithColours) {
    const std::vector<float> xyz = {1.5f, -2.f, -1.7f, 3.f, 4.f, 0.5f, -7.25f, 0.f, -1.6f};
    const std::string path = std::string(GSEG_BINARY_DIR) + "/tests/roundtrip.ply";
    gseg::io::writeLabelledPly(path, gseg::PointCloudView(xyz.data(), 3), {1, 0, 1});
    const auto back = gseg::io::readPly(path);
    ASSERT_EQ(back.size(), 12u);
    for (int i = 0; i < 3; ++i)
        for (int a = 0; a < 3; ++a) EXPECT_EQ(back[4 * i + a], xyz[3 * i + a]);
    EXPECT_THROW(gseg::io::writeLabelledPly(path, gseg::PointCloudView(xyz.data(), 3), {1}), std::invalid_argument);
}

TEST(Ply, AsciiWithIntensityAndDoubles) {
    const auto pts = gseg::io::readPly(writeTemp("a.ply",
        "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\n"
        "property float intensity\nproperty uchar red\nend_header\n1 2 3 0.5 255\n-4 -5 -6 7 0\n"));
    EXPECT_EQ(pts, (std::vector<float>{1, 2, 3, 0.5f, -4, -5, -6, 7}));
}

TEST(Ply, TruncatedOrGarbageFilesThrow) {
    const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\n"
                               "property float y\nproperty float z\nend_header\n";
    EXPECT_THROW(gseg::io::readPly(writeTemp("trunc.ply", header + std::string(50, '\0'))), std::runtime_error);
    EXPECT_THROW(gseg::io::readPly(writeTemp("garbage.ply", "this is not a ply\n")), std::runtime_error);
    EXPECT_THROW(gseg::io::readPly(writeTemp("noend.ply", "ply\nformat ascii 1.0\n")), std::runtime_error);
    EXPECT_THROW(gseg::io::readPly(writeTemp("empty.ply", "")), std::runtime_error);
}
