// The 2D layer grid of the map layer (gseg/map/layer_grid.hpp): cell indices and layers.
#include <gseg/map/layer_grid.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace {

using gseg::map::LayerGrid;

TEST(LayerGrid, CellIndicesUseFloorOnNegativeCoordinatesAndBorders) {
    const LayerGrid g(10, 5, 0.5, -2.0, -1.0);
    struct Case { double v; long long x, y; };
    for (const Case c : {Case{-2.0, 0, -2}, Case{-2.0001, -1, -3}, Case{-1.5, 1, -1}, Case{0.0, 4, 2}, Case{2.999, 9, 7}, Case{3.0, 10, 8}}) {
        EXPECT_EQ(g.cellX(c.v), c.x) << c.v;
        EXPECT_EQ(g.cellY(c.v), c.y) << c.v;
    }
    EXPECT_TRUE(g.inside(0, 0));
    EXPECT_TRUE(g.inside(9, 4));
    EXPECT_FALSE(g.inside(10, 4));
    EXPECT_FALSE(g.inside(-1, 0));
    EXPECT_DOUBLE_EQ(g.centreX(0), -1.75);
    EXPECT_DOUBLE_EQ(g.centreY(4), 1.25);
    EXPECT_EQ(g.index(3, 2), 23u);
}

TEST(LayerGrid, LayersStartUnknownAndAreFoundByName) {
    LayerGrid g(3, 2, 0.2, 0, 0);
    auto& e = g.add("elevation", "m", "ground height");
    ASSERT_EQ(e.values.size(), 6u);
    for (float v : e.values) EXPECT_TRUE(std::isnan(v));
    e.values[g.index(2, 1)] = 1.5f;
    EXPECT_EQ(&g.add("elevation", "x", "y"), &g.layer("elevation"));  // the same layer, unchanged
    EXPECT_EQ(g.layer("elevation").unit, "m");
    EXPECT_FLOAT_EQ(g.layer("elevation").values[5], 1.5f);
    EXPECT_EQ(g.find("slope"), nullptr);
    EXPECT_THROW(g.layer("slope"), std::out_of_range);
}

TEST(LayerGrid, ALayerStaysWhereItIsWhileMoreAreAdded) {
    LayerGrid g(4, 4, 0.2, 0, 0);
    auto& first = g.add("elevation", "m", "ground height").values;  // as the map layer fills them
    const float* data = first.data();
    for (int k = 0; k < 20; ++k) g.add("layer" + std::to_string(k), "-", "more");
    first[3] = 2.5f;  // still the grid's own layer
    EXPECT_EQ(&first, &g.layer("elevation").values);
    EXPECT_EQ(first.data(), data);
    EXPECT_FLOAT_EQ(g.layer("elevation").values[3], 2.5f);
    EXPECT_EQ(g.layers().size(), 21u);
}

TEST(LayerGrid, AbsurdSizesAreRefused) {
    EXPECT_THROW(LayerGrid(0, 3, 0.2, 0, 0), std::invalid_argument);
    EXPECT_THROW(LayerGrid(3, 3, 0, 0, 0), std::invalid_argument);
    EXPECT_THROW(LayerGrid(3, 3, NAN, 0, 0), std::invalid_argument);
    EXPECT_THROW(LayerGrid(3, 3, 0.2, INFINITY, 0), std::invalid_argument);
}

}  // namespace
