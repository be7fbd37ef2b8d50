// The one KITTI sequence reader (gseg/eval/kitti_sequence.hpp) that gseg eval, gseg eval-map and
// kitti2rawlog share: what it lists, in which order, and the frame numbers of names.
#include <gseg/eval/kitti_sequence.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace fs = std::filesystem;

namespace {
/// An empty folder `<build>/tests/kitti_sequence/<name>`.
fs::path freshDir(const std::string& name) {
    const fs::path dir = fs::path(GSEG_BINARY_DIR) / "tests" / "kitti_sequence" / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}
}  // namespace

using gseg::eval::kittiFrameNumber;
using gseg::eval::listKittiScans;

TEST(KittiSequence, ListsTheBinFilesSortedByNameWithTheirLabelPaths) {
    const fs::path seq = freshDir("kitti_sequence_list");
    fs::create_directories(seq / "velodyne");
    for (const char* f : {"000010.bin", "000002.bin", "notes.txt", "000001.bin.gz", "x.bin"}) std::ofstream(seq / "velodyne" / f) << "x";
    fs::create_directories(seq / "velodyne" / "sub.bin");  // a folder named like a scan is listed too (as before)
    const auto scans = listKittiScans(seq.string());
    ASSERT_EQ(scans.size(), 4u);
    EXPECT_EQ(scans[0].name, "000002");
    EXPECT_EQ(scans[1].name, "000010");
    EXPECT_EQ(scans[2].name, "sub");
    EXPECT_EQ(scans[3].name, "x");
    EXPECT_EQ(scans[0].scan, (seq / "velodyne" / "000002.bin").string());
    EXPECT_EQ(scans[0].label, (seq / "labels" / "000002.label").string());
}

TEST(KittiSequence, AFolderThatCannotBeListedIsNamed) {
    const fs::path seq = freshDir("kitti_sequence_missing");
    try {
        listKittiScans(seq.string());
        FAIL() << "no error";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find((seq / "velodyne").string() + ": cannot list the scans ("), std::string::npos) << e.what();
    }
}

TEST(KittiSequence, FrameNumbersAreDigitsOnlyWithinTheLimit) {
    EXPECT_EQ(kittiFrameNumber("000042"), 42u);
    EXPECT_EQ(kittiFrameNumber("0"), 0u);
    EXPECT_FALSE(kittiFrameNumber(""));
    EXPECT_FALSE(kittiFrameNumber("12a"));
    EXPECT_FALSE(kittiFrameNumber("-1"));
    EXPECT_FALSE(kittiFrameNumber(" 1"));
    EXPECT_EQ(kittiFrameNumber("123456789", 9), 123456789u);
    EXPECT_FALSE(kittiFrameNumber("1234567890", 9));
    EXPECT_EQ(kittiFrameNumber("999999999999999999"), 999999999999999999u);  // 18 digits
    EXPECT_FALSE(kittiFrameNumber("1000000000000000000"));                 // 19: never a frame
}
