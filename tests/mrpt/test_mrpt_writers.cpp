// Writers of the MRPT layer on a full disk and after interruption: PNG (gseg's own encoder) and
// the gzip rawlog writer, both through gseg::io::AtomicFile.
#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/rawlog_io.hpp>
#include <gseg/mrpt/render.hpp>
#include <support/child.hpp>
#include <support/output_files.hpp>

#include <mrpt/img/CImage.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservationPointCloud.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <sys/resource.h>

namespace fs = std::filesystem;

namespace {


fs::path freshDir(const std::string& name) { return gseg::test::freshDir("writers", name); }

/// Runs `body` in a child whose files may not exceed `bytes` (a full disk for write()). The child
/// returns 7 if `body` threw std::runtime_error naming the limit's errno text, 0 if it did not throw.
int withFileSizeLimit(std::size_t bytes, const std::function<void()>& body) {
    return gseg::test::runInChild([&] {
               gseg::io::installTemporaryCleanup("test");
               const rlimit lim{bytes, bytes};
               ::setrlimit(RLIMIT_FSIZE, &lim);
               try {
                   body();
               } catch (const std::runtime_error& e) {
                   return std::string(e.what()).find("File too large") != std::string::npos ? 7 : 8;
               }
               return 0;
           }).code;
}

mrpt::obs::CObservationPointCloud::Ptr cloudObservation(std::size_t n, const std::string& label) {
    auto pts = mrpt::maps::CSimplePointsMap::Create();
    for (std::size_t i = 0; i < n; ++i) pts->insertPoint(float(i % 97), float(i % 89) * 0.37f, -1.7f + float(i % 7) * 0.01f);
    auto obs = mrpt::obs::CObservationPointCloud::Create();
    obs->pointcloud = pts;
    obs->sensorLabel = label;
    return obs;
}

}  // namespace

TEST(PngWriter, PixelsReadBackExactly) {
    const fs::path dir = freshDir("png");
    mrpt::img::CImage img(7, 5, mrpt::img::CH_RGB);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 7; ++x) img.setPixel(x, y, mrpt::img::TColor(std::uint8_t(30 * x), std::uint8_t(50 * y), 200));
    const std::string path = (dir / "p.png").string();
    gseg::test::writeBytes(path, gseg::mrpt::encodePng(img));
    mrpt::img::CImage back;
    ASSERT_TRUE(back.loadFromFile(path));
    ASSERT_EQ(back.getWidth(), 7u);
    ASSERT_EQ(back.getHeight(), 5u);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 7; ++x)
            for (int ch = 0; ch < 3; ++ch)
                ASSERT_EQ(*back.ptr<std::uint8_t>(unsigned(x), unsigned(y), unsigned(ch)),
                          *img.ptr<std::uint8_t>(unsigned(x), unsigned(y), unsigned(ch)))
                    << x << "," << y << " channel " << ch;
}

TEST(PngWriter, FullDiskIsAnErrorAndLeavesNothing) {
    const fs::path dir = freshDir("pngfull");
    const std::string path = (dir / "top.png").string();
    std::vector<float> xyz;
    for (int i = 0; i < 20000; ++i) xyz.insert(xyz.end(), {float(i % 200) * 0.3f - 30, float(i / 200) * 0.6f - 30, -1.7f});
    std::vector<std::uint8_t> labels(20000);
    for (std::size_t i = 0; i < labels.size(); ++i) labels[i] = std::uint8_t(i % 3 == 0);
    EXPECT_EQ(withFileSizeLimit(2000, [&] {
                  gseg::test::writeBytes(path, gseg::mrpt::topDownPng(gseg::PointCloudView(xyz.data(), 20000), labels));
              }),
              7);
    EXPECT_FALSE(fs::exists(path));
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ""), "");
    // Without the limit it is written, and NaN points are simply not drawn.
    xyz[0] = std::numeric_limits<float>::quiet_NaN();
    gseg::test::writeBytes(path, gseg::mrpt::topDownPng(gseg::PointCloudView(xyz.data(), 20000), labels));
    EXPECT_GT(fs::file_size(path), 2000u);
}

TEST(RawlogWriter, RoundTripAndNothingWithoutCommit) {
    const fs::path dir = freshDir("rawlog");
    const std::string path = (dir / "out.rawlog").string();
    {
        gseg::mrpt::RawlogWriter w(path);
        w.write(*cloudObservation(10, "A"));
    }
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ""), "");
    gseg::mrpt::RawlogWriter w(path);
    for (int i = 0; i < 3; ++i) w.write(*cloudObservation(1000 + i, "L" + std::to_string(i)));
    w.commit();
    std::vector<std::string> labels;
    gseg::mrpt::forEachRawlogEntry(path, [&](std::size_t, const auto& obj) {
        labels.push_back(std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj)->sensorLabel);
        return true;
    });
    EXPECT_EQ(labels, (std::vector<std::string>{"L0", "L1", "L2"}));
}

TEST(RawlogWriter, FullDiskIsAnErrorAndLeavesNothing) {
    // MRPT's CFileGZOutputStream reports nothing when its final flush fails: truncated gzip, exit 0.
    const fs::path dir = freshDir("rawlogfull");
    const std::string path = (dir / "out.rawlog").string();
    EXPECT_EQ(withFileSizeLimit(20000, [&] {
                  gseg::mrpt::RawlogWriter w(path);
                  for (int i = 0; i < 30; ++i) w.write(*cloudObservation(5000, "L"));
                  w.commit();
              }),
              7);
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ""), "");
}
