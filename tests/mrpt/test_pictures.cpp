// The shared picture conventions (gseg/mrpt/picture.hpp): titles name files, legends name every
// colour, the scale bar has the length it says, x forward is up with an arrow.
#include <gseg/mrpt/picture.hpp>
#include <gseg/mrpt/png.hpp>
#include <gseg/mrpt/top_view.hpp>
#include <gseg/mrpt/render.hpp>
#include <support/output_files.hpp>

#include <mrpt/img/CImage.h>
#include <mrpt/math/CMatrixF.h>

#include <cmath>

#include <gtest/gtest.h>

#include <stdexcept>

namespace {

using gseg::mrpt::Colour;

/// Pixel (x, y) of a picture, as RGB.
Colour at(const gseg::mrpt::Picture& pic, int x, int y) {
    const std::uint8_t* p = pic.image().ptrLine<std::uint8_t>(unsigned(y)) + 3 * x;
    const bool bgr = pic.image().getChannelsOrder() == "BGR";
    return {bgr ? p[2] : p[0], p[1], bgr ? p[0] : p[2]};
}

bool same(Colour a, Colour b) { return a.r == b.r && a.g == b.g && a.b == b.b; }

bool anyIn(const gseg::mrpt::Picture& pic, int x0, int y0, int x1, int y1, Colour c) {
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x)
            if (same(at(pic, x, y), c)) return true;
    return false;
}

}  // namespace

TEST(Pictures, TitlesShowFileNamesNotPaths) {
    EXPECT_EQ(gseg::mrpt::displayName("/work/main/../shared/data/semantickitti/sequences/08/velodyne/000000.bin"),
              "08/velodyne/000000.bin");
    EXPECT_EQ(gseg::mrpt::displayName("/usr/share/mrpt/datasets/test_velodyne_VLP16.rawlog"), "test_velodyne_VLP16.rawlog");
    EXPECT_EQ(gseg::mrpt::displayName("scan.ply"), "scan.ply");
    EXPECT_EQ(gseg::mrpt::displayName("velodyne/000001.bin"), "000001.bin");
    EXPECT_EQ(gseg::mrpt::displayName(""), "");
}

TEST(Pictures, TopViewHasLegendScaleBarArrowAndXForwardUp) {
    // Two points ahead (x = +20 m, class 0) and two to the left (y = +20 m, class 1).
    const float xyz[] = {20, 0, -1.7f, 20, 0.2f, -1.7f, 0, 20, -1.7f, 0.2f, 20, -1.7f};
    const std::vector<std::uint8_t> classOf = {0, 0, 1, 1};
    const Colour ahead{10, 200, 30}, left{200, 30, 10};
    gseg::mrpt::TopViewOptions o;
    o.sizePx = 800;
    o.rangeM = 50;  // 8 px per metre
    o.title = "scene.bin";
    const gseg::mrpt::Picture pic =
        gseg::mrpt::drawTopView(gseg::PointCloudView(xyz, 4), classOf, {{ahead, "ahead", 0, 2}, {left, "left", 0, 2}}, o);
    const int c = 400;
    // x forward up, y left to the left.
    EXPECT_TRUE(anyIn(pic, c - 2, c - 160 - 2, c + 2, c - 160 + 2, ahead));
    EXPECT_TRUE(anyIn(pic, c - 160 - 2, c - 2, c - 160 + 2, c + 2, left));
    // The forward arrow: a shaft of text colour straight up from the sensor.
    const Colour text = pic.textColour();
    for (int y = c - 30; y <= c; y += 5) EXPECT_TRUE(anyIn(pic, c - 1, y, c + 1, y, text)) << y;
    // Legend at the bottom left with a swatch of every class.
    EXPECT_TRUE(anyIn(pic, 0, 650, 60, 799, ahead));
    EXPECT_TRUE(anyIn(pic, 0, 650, 60, 799, left));
    // Scale bar at the bottom right: 10 m (the longest round length within 150 px) = 80 px.
    const int y = 800 - 24 + 2, right = 800 - 24;
    int run = 0;
    for (int x = right; x >= 0 && same(at(pic, x, y), text); --x) ++run;
    EXPECT_EQ(run, 81);
    // A title in the top-left corner.
    EXPECT_TRUE(anyIn(pic, 8, 8, 90, 22, text));
    EXPECT_THROW(gseg::mrpt::drawTopView(gseg::PointCloudView(xyz, 4), {0}, {{ahead, "a"}}, o), std::invalid_argument);
}

TEST(Pictures, ScanPictureLegendNamesGroundAndNonGround) {
    std::vector<float> xyz;
    std::vector<std::uint8_t> labels;
    for (int i = 0; i < 100; ++i) {
        xyz.insert(xyz.end(), {float(i % 10), float(i / 10), -1.7f});
        labels.push_back(i % 2);
    }
    const std::string path = std::string(GSEG_BINARY_DIR) + "/tests/pictures_scan.png";
    gseg::test::writeBytes(path, gseg::mrpt::topDownPng(gseg::PointCloudView(xyz.data(), 100), labels));
    mrpt::img::CImage img;
    ASSERT_TRUE(img.loadFromFile(path));
    EXPECT_EQ(img.getWidth(), 800u);
    mrpt::math::CMatrixFloat R, G, B;
    img.getAsRGBMatrices(R, G, B);
    if (img.getChannelsOrder() == "BGR") std::swap(R, B);
    bool ground = false, nonGround = false;  // both swatches in the legend (bottom left)
    for (int y = 650; y < 800; ++y)
        for (int x = 0; x < 60; ++x) {
            const long r = std::lround(255 * R(y, x)), g = std::lround(255 * G(y, x)), b = std::lround(255 * B(y, x));
            ground |= r == gseg::mrpt::kGroundColour.r && g == gseg::mrpt::kGroundColour.g && b == gseg::mrpt::kGroundColour.b;
            nonGround |= r == gseg::mrpt::kNonGroundColour.r && g == gseg::mrpt::kNonGroundColour.g && b == gseg::mrpt::kNonGroundColour.b;
        }
    EXPECT_TRUE(ground && nonGround);
    EXPECT_THROW(gseg::mrpt::topDownPng(gseg::PointCloudView(xyz.data(), 100), {1}), std::invalid_argument);
}

TEST(Pictures, SizesOutsideTheLimitsAreRefused) {
    EXPECT_THROW(gseg::mrpt::Picture(0, 10, {}), std::invalid_argument);
    EXPECT_THROW(gseg::mrpt::Picture(10, 20000, {}), std::invalid_argument);
    gseg::mrpt::Picture light(10, 10, {255, 255, 255}), dark(10, 10, {0, 0, 0});
    EXPECT_TRUE(same(light.textColour(), {0, 0, 0}));
    EXPECT_TRUE(same(dark.textColour(), {235, 235, 235}));
}

namespace {

/// Every recorded text lies inside its canvas (x, y >= 0, right and bottom edges within).
void expectInside(const std::vector<gseg::mrpt::DrawnText>& texts) {
    ASSERT_FALSE(texts.empty());
    for (const auto& t : texts) {
        EXPECT_GE(t.x, 0) << t.text;
        EXPECT_GE(t.y, 0) << t.text;
        EXPECT_LE(t.x + t.width, t.canvasWidth) << "'" << t.text << "' runs off the right edge of a " << t.canvasWidth << " px canvas";
        EXPECT_LE(t.y + t.height, t.canvasHeight) << "'" << t.text << "' runs off the bottom edge";
    }
}

/// The title: the text drawn at the top-left corner (10, 8).
std::string titleOf(const std::vector<gseg::mrpt::DrawnText>& texts) {
    for (const auto& t : texts)
        if (t.x == 10 && t.y == 8) return t.text;
    return "";
}

}  // namespace

TEST(Pictures, EveryTextFitsItsCanvasEvenWithLongFileNames) {
    // A seeded scan, pictured at the sizes the tools use and a small one, under a long file name.
    std::vector<float> xyz;
    std::vector<std::uint8_t> labels;
    for (int i = 0; i < 2000; ++i) {
        const double a = 0.01 * i, r = 3 + 0.02 * i;
        xyz.insert(xyz.end(), {float(r * std::cos(a)), float(r * std::sin(a)), i % 2 ? -1.7f : 0.5f});
        labels.push_back(std::uint8_t(i % 2));
    }
    const gseg::PointCloudView cloud(xyz.data(), labels.size());
    const std::string longName = "a_very_long_recording_name_from_a_field_campaign_" + std::string(120, 'x') + "_000042.rawlog";
    for (const int size : {300, 800, 900}) {
        std::vector<gseg::mrpt::DrawnText> texts;
        {
            const gseg::mrpt::TextRecorder recorder(texts);
            gseg::mrpt::RenderOptions ro;
            ro.sizePx = size;
            ro.title = gseg::mrpt::displayName(longName) + ", entry 0 'Velodyne1_SCAN': ground / non-ground";
            gseg::mrpt::topDownPng(cloud, labels, ro);
        }
        SCOPED_TRACE(size);
        expectInside(texts);
        // The title (at the top-left corner) is shortened in the middle: its start and end are still there.
        const std::string title = titleOf(texts);
        EXPECT_EQ(title.rfind("a_very", 0), 0u) << title;
        EXPECT_NE(title.find("..."), std::string::npos) << title;
        EXPECT_EQ(title.substr(title.size() - 12), "/ non-ground") << title;
    }
    // A title that fits is drawn as it is.
    std::vector<gseg::mrpt::DrawnText> texts;
    {
        const gseg::mrpt::TextRecorder recorder(texts);
        gseg::mrpt::RenderOptions ro;
        ro.sizePx = 800;
        ro.title = "000000.bin: ground / non-ground";
        gseg::mrpt::topDownPng(cloud, labels, ro);
    }
    expectInside(texts);
    EXPECT_EQ(titleOf(texts), "000000.bin: ground / non-ground");
}
