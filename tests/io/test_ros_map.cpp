// The ROS map_server file format (gseg/io/ros_map.hpp): round trips, MRPT's own reader, bad files.
#include <gseg/io/ros_map.hpp>

#include <support/child.hpp>
#include <support/output_files.hpp>
#include <support/paths.hpp>

#include <mrpt/maps/COccupancyGridMap2D.h>

#include <gtest/gtest.h>

#include <fstream>
#include <random>

namespace {

using gseg::io::RosCell;
using gseg::io::RosMap;

RosMap randomMap(unsigned seed) {
    std::mt19937 rng(seed);
    RosMap m = RosMap::unknown(37, 23, 0.2, -3.4, -2.2);
    const std::uint8_t values[3] = {RosMap::kFree, RosMap::kOccupied, RosMap::kUnknown};
    for (auto& p : m.pixels) p = values[rng() % 3];
    return m;
}

void writeText(const std::string& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
}

TEST(RosMap, CellIndicesFollowMapServerBottomRowIsCellYZero) {
    RosMap m = RosMap::unknown(4, 3, 0.5, -1.0, 2.0);
    m.value(0, 0) = RosMap::kOccupied;  // bottom-left cell: the image's last row
    EXPECT_EQ(m.pixels[std::size_t(2 * 4 + 0)], RosMap::kOccupied);
    EXPECT_EQ(m.at(0, 0), RosCell::Occupied);
    EXPECT_EQ(m.at(1, 0), RosCell::Unknown);
    EXPECT_EQ(m.at(-1, 0), RosCell::Unknown);  // outside
    EXPECT_EQ(m.at(0, 3), RosCell::Unknown);
    EXPECT_EQ(m.cellX(-1.0), 0);
    EXPECT_EQ(m.cellX(-1.0001), -1);  // floor, not truncation
    EXPECT_EQ(m.cellX(-0.5), 1);      // a border belongs to the cell above it
    EXPECT_EQ(m.cellY(2.49), 0);
    EXPECT_EQ(m.cellY(3.5), 3);
}

TEST(RosMap, TrinaryValuesAreFreeOccupiedUnknownUnderMapServerThresholds) {
    RosMap m = RosMap::unknown(3, 1, 0.2, 0, 0);
    m.value(0, 0) = RosMap::kFree;
    m.value(1, 0) = RosMap::kOccupied;
    EXPECT_EQ(m.at(0, 0), RosCell::Free);
    EXPECT_EQ(m.at(1, 0), RosCell::Occupied);
    EXPECT_EQ(m.at(2, 0), RosCell::Unknown);  // 205: (255 - 205) / 255 = 0.19608 > 0.196
    m.negate = 1;
    EXPECT_EQ(m.at(0, 0), RosCell::Occupied);
    EXPECT_EQ(m.at(1, 0), RosCell::Free);
}

TEST(RosMap, WriteThenReadGivesTheSameMap) {
    const std::string dir = gseg::test::freshDir("ros_map", "ros_map_round_trip").string();
    const RosMap m = randomMap(7);
    gseg::test::writeRosMap(dir + "/m", m);
    const RosMap r = gseg::io::readRosMap(dir + "/m.yaml");
    EXPECT_EQ(r.width, m.width);
    EXPECT_EQ(r.height, m.height);
    EXPECT_DOUBLE_EQ(r.resolution, m.resolution);
    EXPECT_DOUBLE_EQ(r.originX, m.originX);
    EXPECT_DOUBLE_EQ(r.originY, m.originY);
    EXPECT_EQ(r.pixels, m.pixels);
    EXPECT_EQ(r.mode, "trinary");
    EXPECT_NE(gseg::test::readText(dir + "/m.yaml").find("image: m.pgm\n"), std::string::npos);  // relative to the YAML
}

TEST(RosMap, MrptLoadsTheFileCellForCell) {
    const std::string dir = gseg::test::freshDir("ros_map", "ros_map_mrpt").string();
    const RosMap m = randomMap(11);
    gseg::test::writeRosMap(dir + "/m", m);
    mrpt::maps::COccupancyGridMap2D grid;
    ASSERT_TRUE(grid.loadFromROSMapServerYAML(dir + "/m.yaml"));
    ASSERT_EQ(int(grid.getSizeX()), m.width);
    ASSERT_EQ(int(grid.getSizeY()), m.height);
    EXPECT_NEAR(grid.getResolution(), m.resolution, 1e-6);
    EXPECT_NEAR(grid.getXMin(), m.originX, 1e-6);
    EXPECT_NEAR(grid.getYMin(), m.originY, 1e-6);
    for (int cy = 0; cy < m.height; ++cy)
        for (int cx = 0; cx < m.width; ++cx) {
            const float p = grid.getCell(cx, cy);  // MRPT: probability of free space
            switch (m.at(cx, cy)) {
                case RosCell::Free: EXPECT_GT(p, 0.9f) << cx << "," << cy; break;
                case RosCell::Occupied: EXPECT_LT(p, 0.1f) << cx << "," << cy; break;
                case RosCell::Unknown: EXPECT_NEAR(p, 0.5f, 0.05f) << cx << "," << cy; break;
            }
        }
}

TEST(RosMap, BadFilesAreRefusedNamingFileAndReason) {
    const std::string dir = gseg::test::freshDir("ros_map", "ros_map_bad").string();
    const RosMap m = randomMap(3);
    gseg::test::writeRosMap(dir + "/m", m);
    const std::string pgm = gseg::test::readText(dir + "/m.pgm");
    const auto refused = [&](const std::string& yaml, const std::string& image, const std::string& expect) {
        writeText(dir + "/b.yaml", yaml);
        writeText(dir + "/b.pgm", image);
        try {
            gseg::io::readRosMap(dir + "/b.yaml");
            ADD_FAILURE() << "accepted: " << expect;
        } catch (const std::runtime_error& e) {
            EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
        }
    };
    const std::string good = "image: b.pgm\nresolution: 0.2\norigin: [0, 0, 0]\n";
    refused(good, pgm.substr(0, pgm.size() - 5), "truncated");
    refused(good, "", "not a binary PGM");
    refused(good, "P2\n2 2\n255\n0 0 0 0\n", "not a binary PGM");
    refused(good, "P5\n2 2\n65535\n", "maxval");
    refused("image: b.pgm\norigin: [0, 0, 0]\n", pgm, "no 'resolution'");
    refused("image: b.pgm\nresolution: nan\norigin: [0, 0, 0]\n", pgm, "not a finite number");
    refused("image: b.pgm\nresolution: -1\norigin: [0, 0, 0]\n", pgm, "resolution: -1 m is outside 0.0001 to 1000");
    refused("image: b.pgm\nresolution: 0.2\norigin: [0, 0]\n", pgm, "three values");
    refused("image: b.pgm\nresolution: 0.2\norigin: [0, 0, 0.5]\n", pgm, "rotated");
    refused("image: b.pgm\nresolution: 0.2\nresolution: 0.3\norigin: [0, 0, 0]\n", pgm, "b.yaml:3: key 'resolution' repeated");
    refused("image: nothere.pgm\nresolution: 0.2\norigin: [0, 0, 0]\n", pgm, "nothere.pgm: cannot open");
    refused(good + "free_thresh: 0.9\n", pgm, "thresholds");
    EXPECT_THROW(gseg::io::readRosMap(dir + "/absent.yaml"), std::runtime_error);
}

TEST(RosMap, AnInconsistentMapIsRefusedAndTheExistingFilesStay) {
    const std::string dir = gseg::test::freshDir("ros_map", "ros_map_keep").string();
    gseg::test::writeRosMap(dir + "/m", randomMap(5));
    const std::string before = gseg::test::readText(dir + "/m.pgm");
    RosMap bad = randomMap(6);
    bad.pixels.pop_back();
    EXPECT_THROW(gseg::test::writeRosMap(dir + "/m", bad), std::invalid_argument);
    bad = randomMap(6);
    bad.resolution = 0;
    EXPECT_THROW(gseg::test::writeRosMap(dir + "/m", bad), std::invalid_argument);
    EXPECT_EQ(gseg::test::readText(dir + "/m.pgm"), before);
}

}  // namespace
