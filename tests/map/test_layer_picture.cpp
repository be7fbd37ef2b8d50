// The picture of one map layer (gseg/map/layer_picture.hpp): its size, every text inside the
// canvas (long titles too), colours at known cells, x right and y up (as the costmap), unknown cells in
// their own colour.
#include <gseg/map/layer_picture.hpp>
#include <gseg/map/map_colours.hpp>

#include <support/child.hpp>
#include <support/output_files.hpp>

#include <mrpt/img/CImage.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

namespace {

using gseg::map::LayerGrid;
using gseg::map::LayerPictureLayout;
using gseg::mrpt::Colour;

constexpr int kCharWidth = gseg::mrpt::Picture::kCharWidth, kFontHeight = 15;

/// A slope layer rising with x (slope = cx degrees) and a class layer (1 where cx < width / 2,
/// else 2), with the cells of column cy = 0 unknown.
LayerGrid rampGrid(int w, int h, double res = 0.2, double ox = -3.3, double oy = -1.1) {
    LayerGrid g(w, h, res, ox, oy);
    auto& slope = g.add("slope", "deg", "ground inclination against the horizontal");
    auto& cls = g.add("class", "-", "1 traversable, 2 not traversable, NaN unknown");
    for (int cy = 0; cy < h; ++cy)
        for (int cx = 0; cx < w; ++cx) {
            const bool unknown = cy == 0;
            slope.values[g.index(cx, cy)] = unknown ? NAN : float(cx);
            cls.values[g.index(cx, cy)] = unknown ? NAN : cx < w / 2 ? 1.0f : 2.0f;
        }
    return g;
}

/// The PNG read back (MRPT's decoder).
mrpt::img::CImage decode(const std::string& png, const std::string& name) {
    const std::string path = (gseg::test::freshDir("layer_picture", name) / "picture.png").string();
    std::FILE* f = std::fopen(path.c_str(), "wb");
    EXPECT_NE(f, nullptr);
    std::fwrite(png.data(), 1, png.size(), f);
    std::fclose(f);
    mrpt::img::CImage img;
    EXPECT_TRUE(img.loadFromFile(path));
    return img;
}

Colour at(const mrpt::img::CImage& img, int x, int y) {
    const std::uint8_t* p = img.ptrLine<std::uint8_t>(unsigned(y)) + 3 * x;
    const bool bgr = img.getChannelsOrder() == "BGR";
    return {bgr ? p[2] : p[0], p[1], bgr ? p[0] : p[2]};
}

::testing::AssertionResult sameColour(Colour a, Colour b) {
    if (a.r == b.r && a.g == b.g && a.b == b.b) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << "(" << int(a.r) << ", " << int(a.g) << ", " << int(a.b) << ") != (" << int(b.r) << ", "
                                         << int(b.g) << ", " << int(b.b) << ")";
}

/// Every text inside the canvas and no two texts overlapping.
void expectTextsFit(const LayerPictureLayout& l) {
    ASSERT_FALSE(l.texts.empty());
    for (const auto& t : l.texts) {
        EXPECT_GE(t.x, 0) << t.text;
        EXPECT_GE(t.y, 0) << t.text;
        EXPECT_LE(t.x + int(t.text.size()) * kCharWidth, l.width) << t.text << " (width " << l.width << ")";
        EXPECT_LE(t.y + kFontHeight, l.height) << t.text;
    }
    for (std::size_t i = 0; i < l.texts.size(); ++i)
        for (std::size_t j = i + 1; j < l.texts.size(); ++j) {
            const auto &a = l.texts[i], &b = l.texts[j];
            const bool apart = a.x + int(a.text.size()) * kCharWidth <= b.x || b.x + int(b.text.size()) * kCharWidth <= a.x ||
                               a.y + kFontHeight <= b.y || b.y + kFontHeight <= a.y;
            EXPECT_TRUE(apart) << "'" << a.text << "' overlaps '" << b.text << "'";
        }
    // The legend band's texts stay left of the axes and scale bar (the right 240 pixels).
    for (const auto& t : l.texts)
        if (t.y >= l.legendTop) {
            EXPECT_LE(t.x + int(t.text.size()) * kCharWidth, l.width - 240) << t.text;
        }
}

TEST(LayerPicture, SizeMatchesTheLayoutAndEveryTextFits) {
    for (const auto& size : {std::pair<int, int>{1, 1}, {7, 3}, {40, 90}, {333, 41}}) {
        const LayerGrid g = rampGrid(size.first, size.second);
        for (const char* layer : {"slope", "class"}) {
            SCOPED_TRACE(std::string(layer) + " " + std::to_string(size.first) + " x " + std::to_string(size.second));
            const LayerPictureLayout l = gseg::map::layerPictureLayout(g, layer);
            expectTextsFit(l);
            EXPECT_GE(l.mapWidth, size.first);    // x across
            EXPECT_GE(l.mapHeight, size.second);  // y down
            const mrpt::img::CImage img = decode(gseg::map::encodeLayerPng(g, layer), "size");
            EXPECT_EQ(int(img.getWidth()), l.width);
            EXPECT_EQ(int(img.getHeight()), l.height);
        }
    }
}

TEST(LayerPicture, LongTitlesAndMeaningsAreWrappedInsideTheCanvas) {
    LayerGrid g = rampGrid(20, 10);
    g.add("elevation", "m", std::string(300, 'm') + " " + "ground height from the ground points, median per cell, " + std::string(40, 'w'));
    gseg::map::LayerPictureOptions o;
    o.title = "a drive with a very long name: " + std::string(500, 'x') + " and words after it to wrap at spaces where it can";
    const LayerPictureLayout l = gseg::map::layerPictureLayout(g, "elevation", o);
    expectTextsFit(l);
    EXPECT_GE(l.texts.size(), 8u);
    EXPECT_EQ(l.texts[0].text.rfind("gseg map layer: elevation [m]: a drive", 0), 0u) << l.texts[0].text;
    const mrpt::img::CImage img = decode(gseg::map::encodeLayerPng(g, "elevation", o), "long");
    EXPECT_EQ(int(img.getWidth()), l.width);
    EXPECT_EQ(int(img.getHeight()), l.height);
    // A user range given: the bar says values beyond it take its end colours; still inside.
    o.min = -1000.123456;
    o.max = 12345.5;
    expectTextsFit(gseg::map::layerPictureLayout(g, "elevation", o));
}

TEST(LayerPicture, ColoursAtKnownCellsWithXRightAndYUpAsTheCostmap) {
    const LayerGrid g = rampGrid(30, 12);
    const LayerPictureLayout l = gseg::map::layerPictureLayout(g, "class");
    ASSERT_GT(l.pixelsPerCell, 1);
    const mrpt::img::CImage img = decode(gseg::map::encodeLayerPng(g, "class"), "class");
    const int c = l.pixelsPerCell / 2;
    int col = 0, row = 0;
    // Class 1 at small x (left of the map), class 2 at large x (right), unknown at cy 0 (bottom):
    // the costmap PGM's orientation (column = x, row 0 = the largest y).
    ASSERT_TRUE(l.toPixel(0, 5, col, row));
    EXPECT_TRUE(sameColour(at(img, col + c, row + c), gseg::map::colourOf(gseg::map::ColumnClass::Traversable)));
    EXPECT_EQ(col, l.mapLeft);  // x = smallest: the left column
    ASSERT_TRUE(l.toPixel(29, 5, col, row));
    EXPECT_TRUE(sameColour(at(img, col + c, row + c), gseg::map::colourOf(gseg::map::ColumnClass::Obstacle)));
    EXPECT_EQ(col, l.mapLeft + l.mapWidth - l.pixelsPerCell);  // x = largest: the right column
    ASSERT_TRUE(l.toPixel(29, 0, col, row));
    EXPECT_TRUE(sameColour(at(img, col + c, row + c), gseg::map::colourOf(gseg::map::ColumnClass::Unknown)));
    EXPECT_EQ(row, l.mapTop + l.mapHeight - l.pixelsPerCell);  // y = smallest: the bottom row
    ASSERT_TRUE(l.toPixel(10, 11, col, row));
    EXPECT_EQ(row, l.mapTop);  // y = largest: the top row
    EXPECT_FALSE(l.toPixel(30, 0, col, row));
    EXPECT_EQ(l.barHeight, 0);  // classes: a legend, no colour bar

    // The slope: viridis from its smallest (0 deg, x = 0) to its largest (29 deg) value.
    const LayerPictureLayout s = gseg::map::layerPictureLayout(g, "slope");
    const mrpt::img::CImage simg = decode(gseg::map::encodeLayerPng(g, "slope"), "slope");
    EXPECT_DOUBLE_EQ(s.low, 0.0);
    EXPECT_DOUBLE_EQ(s.high, 29.0);
    ASSERT_TRUE(s.toPixel(0, 5, col, row));
    EXPECT_TRUE(sameColour(at(simg, col + c, row + c), gseg::map::viridis(0)));
    ASSERT_TRUE(s.toPixel(29, 5, col, row));
    EXPECT_TRUE(sameColour(at(simg, col + c, row + c), gseg::map::viridis(1)));
    ASSERT_TRUE(s.toPixel(29, 0, col, row));
    EXPECT_TRUE(sameColour(at(simg, col + c, row + c), gseg::map::colourOf(gseg::map::ColumnClass::Unknown)));
    // The colour bar: high (yellow) at the top, low (dark blue) at the bottom.
    ASSERT_GT(s.barHeight, 0);
    EXPECT_TRUE(sameColour(at(simg, s.barLeft + 5, s.barTop), gseg::map::viridis(1)));
    EXPECT_TRUE(sameColour(at(simg, s.barLeft + 5, s.barTop + s.barHeight - 1), gseg::map::viridis(0)));
    // The page outside the map area.
    EXPECT_TRUE(sameColour(at(simg, s.mapLeft - 2, s.mapTop + 2), gseg::map::backgroundColour()));
}

/// Whether a text of the layout contains `part`.
::testing::AssertionResult hasText(const LayerPictureLayout& l, const std::string& part) {
    std::string all;
    for (const auto& t : l.texts) {
        if (t.text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
        all += "\n  " + t.text;
    }
    return ::testing::AssertionFailure() << "'" << part << "' in none of:" << all;
}

TEST(LayerPicture, TheColourRangeIsThe2ndTo98thPercentileWithTheClippedEndsSaid) {
    // #33: a slope up to 63.6 deg at a few walls left the rest of the map one dark colour.
    LayerGrid g(50, 20, 0.2, 0, 0);
    auto& slope = g.add("slope", "deg", "ground inclination against the horizontal");
    for (int cy = 0; cy < 20; ++cy)
        for (int cx = 0; cx < 50; ++cx) slope.values[g.index(cx, cy)] = float(cx) * 0.2f;  // 0 to 9.8 deg
    for (int cy = 0; cy < 5; ++cy) slope.values[g.index(49, cy)] = 63.6f;               // 0.5 %: walls
    slope.values[g.index(0, 0)] = -5.0f;                                                 // one below
    const LayerPictureLayout l = gseg::map::layerPictureLayout(g, "slope");
    EXPECT_DOUBLE_EQ(l.low, 0.0);
    EXPECT_NEAR(l.high, 9.8, 1e-5) << "the walls beyond the 98th percentile";
    EXPECT_TRUE(l.clippedLow);
    EXPECT_TRUE(l.clippedHigh);
    EXPECT_TRUE(hasText(l, ">= 9.80 deg")) << "the bar's high end says values beyond take its colour";
    EXPECT_TRUE(hasText(l, "<= 0.00 deg"));
    EXPECT_TRUE(hasText(l, "(2nd-98th percentile; beyond: end colours)"));
    EXPECT_TRUE(hasText(l, "values -5.0 deg to 63.6 deg")) << "the title keeps the whole range";
    expectTextsFit(l);
    const mrpt::img::CImage img = decode(gseg::map::encodeLayerPng(g, "slope"), "percentile");
    const int c = l.pixelsPerCell / 2;
    int col = 0, row = 0;
    ASSERT_TRUE(l.toPixel(25, 10, col, row));  // 5 deg: the middle of the bar, not its dark end
    EXPECT_TRUE(sameColour(at(img, col + c, row + c), gseg::map::viridis((25 * 0.2f - l.low) / (l.high - l.low))));
    ASSERT_TRUE(l.toPixel(49, 0, col, row));
    EXPECT_TRUE(sameColour(at(img, col + c, row + c), gseg::map::viridis(1)));
    // Nothing clipped: plain end labels, no note.
    LayerGrid ramp(30, 4, 0.2, 0, 0);
    auto& r = ramp.add("step", "m", "");
    for (int cy = 0; cy < 4; ++cy)
        for (int cx = 0; cx < 30; ++cx) r.values[ramp.index(cx, cy)] = float(cx);
    const LayerPictureLayout plain = gseg::map::layerPictureLayout(ramp, "step");
    EXPECT_FALSE(plain.clippedLow || plain.clippedHigh);
    EXPECT_FALSE(hasText(plain, ">="));
    EXPECT_FALSE(hasText(plain, "percentile"));
}

TEST(LayerPicture, InfinityIsShownAndNamedNotPaintedAsTheMaximum) {
    // #33: the clearance's +inf (no obstacle above) was painted as its largest value, unnamed.
    LayerGrid g(20, 10, 0.2, 0, 0);
    auto& clearance = g.add("clearance", "m", "free height above the ground up to the lowest obstacle (inf: none)");
    for (int cy = 0; cy < 10; ++cy)
        for (int cx = 0; cx < 20; ++cx)
            clearance.values[g.index(cx, cy)] = cx < 10 ? std::numeric_limits<float>::infinity() : cy == 0 ? NAN : 0.2f * float(cx);
    const LayerPictureLayout l = gseg::map::layerPictureLayout(g, "clearance");
    EXPECT_EQ(l.positiveInfinite, 100u);
    EXPECT_EQ(l.negativeInfinite, 0u);
    EXPECT_TRUE(hasText(l, "+inf: no obstacle above the ground (no limit)"));
    EXPECT_TRUE(hasText(l, "unknown (NaN): no data for clearance"));
    EXPECT_TRUE(hasText(l, "190 known; values 2.00 m to 3.80 m, 100 +inf")) << "100 +inf, 90 finite, 10 NaN";
    expectTextsFit(l);
    const mrpt::img::CImage img = decode(gseg::map::encodeLayerPng(g, "clearance"), "infinity");
    const int c = l.pixelsPerCell / 2;
    int col = 0, row = 0;
    ASSERT_TRUE(l.toPixel(3, 5, col, row));
    EXPECT_TRUE(sameColour(at(img, col + c, row + c), gseg::map::positiveInfinityColour()));
    ASSERT_TRUE(l.toPixel(19, 5, col, row));
    EXPECT_TRUE(sameColour(at(img, col + c, row + c), gseg::map::viridis(1)));
    ASSERT_TRUE(l.toPixel(15, 0, col, row));
    EXPECT_TRUE(sameColour(at(img, col + c, row + c), gseg::map::colourOf(gseg::map::ColumnClass::Unknown)));
    const Colour white = gseg::map::positiveInfinityColour(), top = gseg::map::viridis(1);
    EXPECT_FALSE(white.r == top.r && white.g == top.g && white.b == top.b);
}

TEST(LayerPicture, ViridisRunsFromDarkBlueToYellowAndIsMonotoneInLightness) {
    EXPECT_TRUE(sameColour(gseg::map::viridis(0), Colour{68, 1, 84}));
    EXPECT_TRUE(sameColour(gseg::map::viridis(1), Colour{253, 231, 37}));
    EXPECT_TRUE(sameColour(gseg::map::viridis(-3), gseg::map::viridis(0)));
    EXPECT_TRUE(sameColour(gseg::map::viridis(NAN), gseg::map::viridis(0)));
    EXPECT_TRUE(sameColour(gseg::map::viridis(7), gseg::map::viridis(1)));
    double last = -1;
    for (int i = 0; i <= 100; ++i) {
        const Colour c = gseg::map::viridis(i / 100.0);
        const double luma = 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
        EXPECT_GT(luma, last) << i;
        last = luma;
    }
}

TEST(LayerPicture, LargeGridsAreReducedShowingTheLargestValue) {
    LayerGrid g(5000, 300, 0.2, 0, 0);
    auto& step = g.add("step", "m", "largest height jump to a neighbour");
    std::fill(step.values.begin(), step.values.end(), 0.0f);
    step.values[g.index(4999, 299)] = 1.0f;  // one high cell in the top-right block (largest x and y)
    gseg::map::LayerPictureOptions o;
    o.maxSide = 1000;
    const LayerPictureLayout l = gseg::map::layerPictureLayout(g, "step", o);
    EXPECT_EQ(l.cellsPerPixel, 5);
    EXPECT_EQ(l.mapWidth, 1000);
    EXPECT_EQ(l.mapHeight, 60);
    expectTextsFit(l);
    const mrpt::img::CImage img = decode(gseg::map::encodeLayerPng(g, "step", o), "reduced");
    EXPECT_TRUE(sameColour(at(img, l.mapLeft + l.mapWidth - 1, l.mapTop), gseg::map::viridis(1)));
    EXPECT_TRUE(sameColour(at(img, l.mapLeft + l.mapWidth - 2, l.mapTop), gseg::map::viridis(0)));
    EXPECT_TRUE(sameColour(at(img, l.mapLeft + l.mapWidth - 1, l.mapTop + 1), gseg::map::viridis(0)));
}

TEST(LayerPicture, AllUnknownAndConstantLayersDraw) {
    LayerGrid g(6, 4, 0.2, 0, 0);
    g.add("roughness", "m", "spread of the ground heights");
    auto& flat = g.add("elevation", "m", "");
    std::fill(flat.values.begin(), flat.values.end(), 2.5f);
    for (const char* layer : {"roughness", "elevation"}) {
        const LayerPictureLayout l = gseg::map::layerPictureLayout(g, layer);
        expectTextsFit(l);
        EXPECT_FALSE(gseg::map::encodeLayerPng(g, layer).empty());
    }
    EXPECT_DOUBLE_EQ(gseg::map::layerPictureLayout(g, "elevation").low, 2.5);
}

TEST(LayerPicture, BadRequestsAreRefusedAndNothingIsWritten) {
    const LayerGrid g = rampGrid(4, 4);
    EXPECT_THROW(gseg::map::encodeLayerPng(g, "cost"), std::out_of_range);
    gseg::map::LayerPictureOptions o;
    o.min = 5, o.max = 1;
    EXPECT_THROW(gseg::map::encodeLayerPng(g, "slope", o), std::invalid_argument);
    o = {};
    o.max = INFINITY;
    EXPECT_THROW(gseg::map::encodeLayerPng(g, "slope", o), std::invalid_argument);
    const std::string path = (gseg::test::freshDir("layer_picture", "refused") / "cost.png").string();
    try {
        gseg::test::writeBytes(path, gseg::map::encodeLayerPng(g, "cost"));
        ADD_FAILURE() << "a missing layer was drawn";
    } catch (const std::out_of_range& e) {
        EXPECT_NE(std::string(e.what()).find("'cost'"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(LayerPicture, SameLayerGivesTheSameBytes) {
    const LayerGrid g = rampGrid(17, 9);
    EXPECT_EQ(gseg::map::encodeLayerPng(g, "slope"), gseg::map::encodeLayerPng(rampGrid(17, 9), "slope"));
}

}  // namespace
