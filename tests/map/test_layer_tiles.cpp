// #35: the 2.5D layers in sparse tiles (gseg/map/layer_tiles.hpp), and the outputs of a big map:
// the costmap as tiles with Autoware's metadata, the layers as one COG with overviews, pictures of
// an overview; memory that follows the ground seen (a pose jump, a 10 km loop, under a limit of
// the address space).
#include <gseg/io/ros_map.hpp>
#include <gseg/io/output_checks.hpp>
#include <gseg/map/layer_file.hpp>
#include <gseg/map/layer_tiles.hpp>
#include <gseg/map/terrain_layers.hpp>
#include <gseg/map/traversability_map.hpp>

#include <support/child.hpp>

#include <mrpt/maps/COccupancyGridMap2D.h>

#include <cpl_vsi.h>
#include <gdal.h>
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using gseg::map::LayerGrid;
using gseg::map::LayerTiles;
using gseg::map::MapOutputOptions;
using gseg::map::TraversabilityMap;

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();

LayerTiles twoLayers(double res = 0.5) { return LayerTiles(res, {{"elevation", "m", "height"}, {"class", "-", "1 free, 2 blocked"}}); }

// --- LayerTiles: cells, tiles, windows, overviews ----------------------------------------------

TEST(LayerTiles, CellsOnNegativeCoordinatesAndTileBordersFindTheirTile) {
    struct Case {
        std::int64_t ix, iy, tx, ty;
    };
    const Case cases[] = {{0, 0, 0, 0}, {63, 63, 0, 0}, {64, 0, 1, 0}, {-1, 0, -1, 0}, {-64, -64, -1, -1}, {-65, 127, -2, 1},
                          {32767, -32768, 511, -512}};
    for (const Case& c : cases) {
        LayerTiles t = twoLayers();
        t.at(0, c.ix, c.iy) = 7.5f;
        EXPECT_EQ(t.tiles(), 1u) << c.ix << ", " << c.iy;
        EXPECT_TRUE(t.hasTile(c.tx, c.ty)) << c.ix << ", " << c.iy;
        EXPECT_EQ(t.get(0, c.ix, c.iy), 7.5f);
        EXPECT_TRUE(std::isnan(t.get(1, c.ix, c.iy))) << "other layers start unknown";
        EXPECT_TRUE(std::isnan(t.get(0, c.ix + 64, c.iy))) << "no tile: unknown";
        LayerTiles::Cursor cursor(t, 0);
        EXPECT_EQ(cursor.get(c.ix, c.iy), 7.5f);
        EXPECT_TRUE(std::isnan(cursor.get(c.ix - 64, c.iy)));
        cursor.at(c.ix, c.iy) = 1.0f;
        EXPECT_EQ(t.get(0, c.ix, c.iy), 1.0f);
    }
    EXPECT_EQ(LayerTiles::floorDiv(-1, 64), -1);
    EXPECT_EQ(LayerTiles::floorDiv(-64, 64), -1);
    EXPECT_EQ(LayerTiles::floorDiv(-65, 64), -2);
    EXPECT_EQ(LayerTiles::floorDiv(63, 64), 0);
}

TEST(LayerTiles, TwoPatchesKilometresApartCostTwoTiles) {
    LayerTiles t = twoLayers(0.2);
    t.at(0, 0, 0) = 1, t.at(0, 21000, 21000) = 2;  // 4.2 km apart in x and y
    t.setBox(0, 0, 21000, 21000);
    EXPECT_EQ(t.tiles(), 2u);
    EXPECT_EQ(t.bytes(), 2.0 * 2 * LayerTiles::kTileBytes);
    EXPECT_THROW(t.dense(), std::length_error) << "a dense grid of the box would take 3.5 GB";
    const auto list = t.tileList();
    ASSERT_EQ(list.size(), 2u);
    EXPECT_EQ(list[0], std::make_pair(std::int64_t(0), std::int64_t(0)));
    EXPECT_EQ(list[1], std::make_pair(std::int64_t(328), std::int64_t(328)));
}

TEST(LayerTiles, AWindowIsTheDenseGridOfItsCellsWithUnknownWhereNoTileIs) {
    LayerTiles t = twoLayers(0.5);
    for (std::int64_t iy = -70; iy < -60; ++iy)
        for (std::int64_t ix = 60; ix < 70; ++ix) t.at(0, ix, iy) = float(100 * ix + iy);
    t.setBox(60, -70, 69, -61);
    const LayerGrid g = t.dense();
    EXPECT_EQ(g.width(), 10);
    EXPECT_EQ(g.height(), 10);
    EXPECT_DOUBLE_EQ(g.originX(), 30.0);
    EXPECT_DOUBLE_EQ(g.originY(), -35.0);
    ASSERT_EQ(g.layers().size(), 2u);
    EXPECT_EQ(g.layers()[1].name, "class");
    for (int cy = 0; cy < 10; ++cy)
        for (int cx = 0; cx < 10; ++cx) {
            EXPECT_EQ(g.layer("elevation").values[g.index(cx, cy)], float(100 * (60 + cx) + (-70 + cy)));
            EXPECT_TRUE(std::isnan(g.layer("class").values[g.index(cx, cy)]));
        }
    // A window reaching beyond the tiles: unknown there.
    const LayerGrid w = t.window(-200, -200, 300, 300);
    EXPECT_EQ(w.layer("elevation").values[w.index(200 + 65, 200 - 65)], float(100 * 65 - 65));
    EXPECT_TRUE(std::isnan(w.layer("elevation").values[w.index(0, 0)]));
    EXPECT_THROW(t.window(0, 0, 0, 5), std::invalid_argument);
}

TEST(LayerTiles, AnOverviewTakesTheMostBlockingClassAndTheMeanOfTheRest) {
    LayerTiles t = twoLayers(0.2);
    // Overview cell (-1, 0) at factor 4 holds cells -4..-1 x 0..3.
    t.at(0, -4, 0) = 1.0f, t.at(0, -1, 3) = 3.0f;  // mean 2
    t.at(1, -4, 0) = 1.0f, t.at(1, -2, 2) = 2.0f;  // most blocking: 2
    t.at(0, 100, 100) = std::numeric_limits<float>::infinity();  // alone: stays infinite
    t.at(0, 101, 100) = std::numeric_limits<float>::infinity();
    t.at(0, 200, 200) = std::numeric_limits<float>::infinity(), t.at(0, 201, 200) = 4.0f;  // finite ones win
    t.setBox(-4, 0, 201, 200);
    const LayerTiles o = t.overview(4);
    EXPECT_DOUBLE_EQ(o.resolution(), 0.8);
    EXPECT_FLOAT_EQ(o.get(0, -1, 0), 2.0f);
    EXPECT_EQ(o.get(1, -1, 0), 2.0f);
    EXPECT_TRUE(std::isinf(o.get(0, 25, 25)));
    EXPECT_FLOAT_EQ(o.get(0, 50, 50), 4.0f);
    EXPECT_TRUE(std::isnan(o.get(0, 0, 0)));
    EXPECT_EQ(o.minX(), -1);
    EXPECT_EQ(o.maxX(), 50);
    EXPECT_THROW(t.overview(0), std::invalid_argument);
}

TEST(LayerTiles, KeepLayersDropsTheScratchLayersAndTheirMemory) {
    LayerTiles t(0.2, {{"a", "", ""}, {"b", "", ""}, {"scratch", "", ""}});
    t.at(2, 5, 5) = 1;
    t.keepLayers(2);
    EXPECT_EQ(t.layers().size(), 2u);
    EXPECT_EQ(t.bytes(), 2.0 * LayerTiles::kTileBytes);
    EXPECT_THROW(t.layerIndex("scratch"), std::out_of_range);
}

// --- a synthetic drive: flat ground around each sensor position, a wall beside it --------------

/// One scan at (x, y): ground points on a polar grid to 20 m, a wall 4 m to the left, 1 m high.
void insertScan(TraversabilityMap& map, double x, double y) {
    std::vector<float> ground, wall;
    for (double r = 2.0; r < 20.0; r += 0.25)
        for (double a = 0; a < 2 * M_PI; a += 0.25 / r)
            ground.insert(ground.end(), {float(x + r * std::cos(a)), float(y + r * std::sin(a)), 0.0f});
    for (double dx = -3; dx < 3; dx += 0.1)
        for (double z = 0.1; z < 1.0; z += 0.1) wall.insert(wall.end(), {float(x + dx), float(y + 4.0), float(z)});
    map.insertScan(gseg::PointCloudView(ground.data(), ground.size() / 3), gseg::PointCloudView(wall.data(), wall.size() / 3),
                   Eigen::Vector3d(x, y, 1.7));
}

/// Parses the costmap metadata: x_resolution, y_resolution and file -> origin.
struct Metadata {
    double xResolution = 0, yResolution = 0;
    std::map<std::string, std::pair<double, double>> tiles;
};
Metadata readMetadata(const std::string& path) {
    Metadata m;
    std::ifstream in(path);
    const std::regex tile(R"(^(\S+\.yaml): \[(\S+), (\S+)\]$)");
    for (std::string line; std::getline(in, line);) {
        std::smatch s;
        if (line.rfind("x_resolution: ", 0) == 0) m.xResolution = std::stod(line.substr(14));
        else if (line.rfind("y_resolution: ", 0) == 0) m.yResolution = std::stod(line.substr(14));
        else if (std::regex_match(line, s, tile)) m.tiles[s[1]] = {std::stod(s[2]), std::stod(s[3])};
        else EXPECT_EQ(line[0], '#') << "only comments besides: " << line;
    }
    return m;
}

/// [kB] the peak resident memory of this process.
long peakKb() {
    rusage u{};
    ::getrusage(RUSAGE_SELF, &u);
    return u.ru_maxrss;
}

TEST(LayerTiles, TheCostmapTilesAndTheirMetadataLoadBackCellForCell) {
    const fs::path dir = gseg::test::freshDir("layer_tiles", "costmap");
    TraversabilityMap map;
    for (int k = 0; k < 4; ++k) insertScan(map, 3.0 * k, -5.0);
    const LayerGrid dense = map.layers();
    MapOutputOptions how;
    how.tiles = true, how.costmapTile = 128;
    const std::string prefix = (dir / "t").string();
    const std::vector<std::string> written = map.write(prefix, how);
    EXPECT_FALSE(fs::exists(prefix + "_costmap.pgm")) << "tiles instead";
    const Metadata m = readMetadata(prefix + "_costmap_metadata.yaml");
    EXPECT_DOUBLE_EQ(m.xResolution, 128 * 0.2);
    EXPECT_DOUBLE_EQ(m.yResolution, 128 * 0.2);
    ASSERT_GE(m.tiles.size(), 4u) << "the drive spans tiles on both sides of x = 0 and y = 0";
    // Every tile loads in MRPT as a map_server map; together they give the dense costmap's cells.
    std::size_t known = 0;
    for (const auto& [file, origin] : m.tiles) {
        EXPECT_NE(std::find(written.begin(), written.end(), (dir / file).string()), written.end()) << file;
        mrpt::maps::COccupancyGridMap2D grid;
        ASSERT_TRUE(grid.loadFromROSMapServerYAML((dir / file).string())) << file;
        ASSERT_EQ(grid.getSizeX(), 128u);
        ASSERT_EQ(grid.getSizeY(), 128u);
        EXPECT_NEAR(grid.getXMin(), origin.first, 1e-4);
        EXPECT_NEAR(grid.getYMin(), origin.second, 1e-4);
        const std::int64_t x0 = std::llround(origin.first / 0.2), y0 = std::llround(origin.second / 0.2);
        for (int cy = 0; cy < 128; ++cy)
            for (int cx = 0; cx < 128; ++cx) {
                const long long dx = x0 + cx - std::llround(dense.originX() / 0.2), dy = y0 + cy - std::llround(dense.originY() / 0.2);
                const float c = dense.inside(dx, dy) ? dense.layer("class").values[dense.index(int(dx), int(dy))] : kNaN;
                const float p = grid.getCell(cx, cy);
                if (c == 1.0f) {
                    EXPECT_GT(p, 0.9f);
                    ++known;
                } else if (c == 2.0f) {
                    EXPECT_LT(p, 0.1f);
                    ++known;
                } else {
                    EXPECT_NEAR(p, 0.5f, 0.05f);
                }
            }
    }
    std::size_t denseKnown = 0;
    for (float c : dense.layer("class").values) denseKnown += !std::isnan(c);
    EXPECT_EQ(known, denseKnown) << "every known cell is in a listed tile";
    EXPECT_GT(known, 1000u);
}

TEST(LayerTiles, TheLayersAreOneCogWhoseCellsAndOverviewsGdalReads) {
    const fs::path dir = gseg::test::freshDir("layer_tiles", "cog");
    TraversabilityMap map;
    for (int k = 0; k < 4; ++k) insertScan(map, 3.0 * k, -5.0);
    const LayerTiles tiles = map.layerTiles();
    const LayerGrid dense = map.layers();
    const std::string bytes = gseg::map::encodeLayersCog(tiles, 64);
    const std::string path = (dir / "layers.tif").string();
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    GDALAllRegister();
    GDALDatasetH ds = GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr);
    ASSERT_NE(ds, nullptr);
    const char* layout = GDALGetMetadataItem(ds, "LAYOUT", "IMAGE_STRUCTURE");
    ASSERT_NE(layout, nullptr);
    EXPECT_STREQ(layout, "COG");
    ASSERT_EQ(GDALGetRasterCount(ds), 8);
    const int levels = gseg::map::cogOverviewCount(tiles.boxWidth(), tiles.boxHeight(), 64);
    EXPECT_GE(levels, 2);
    double gt[6];
    ASSERT_EQ(GDALGetGeoTransform(ds, gt), CE_None);
    const int w = GDALGetRasterXSize(ds), h = GDALGetRasterYSize(ds);
    for (int b = 1; b <= 8; ++b) {
        GDALRasterBandH band = GDALGetRasterBand(ds, b);
        const LayerGrid::Layer& layer = dense.layers()[std::size_t(b - 1)];
        EXPECT_EQ(std::string(GDALGetDescription(band)), layer.name);
        EXPECT_EQ(GDALGetOverviewCount(band), levels);
        std::vector<float> v(std::size_t(w) * std::size_t(h));
        ASSERT_EQ(GDALRasterIO(band, GF_Read, 0, 0, w, h, v.data(), w, h, GDT_Float32, 0, 0), CE_None);
        // Every cell of the dense grid, at its map position in the COG (+inf written as kNoLimit).
        std::size_t differ = 0;
        for (int cy = 0; cy < dense.height(); ++cy)
            for (int cx = 0; cx < dense.width(); ++cx) {
                const int col = int(std::lround((dense.centreX(cx) - gt[0]) / gt[1] - 0.5));
                const int row = int(std::lround((dense.centreY(cy) - gt[3]) / gt[5] - 0.5));
                ASSERT_TRUE(col >= 0 && row >= 0 && col < w && row < h);
                float want = layer.values[dense.index(cx, cy)];
                if (std::isinf(want)) want = want > 0 ? gseg::map::kNoLimit : -gseg::map::kNoLimit;
                const float got = v[std::size_t(row) * std::size_t(w) + std::size_t(col)];
                differ += std::isnan(want) ? !std::isnan(got) : got != want;
            }
        EXPECT_EQ(differ, 0u) << layer.name;
        // The coarsest overview: readable, a pixel of 2^levels cells, the classes where there is ground.
        GDALRasterBandH ov = GDALGetOverview(band, levels - 1);
        ASSERT_NE(ov, nullptr);
        const int ow = GDALGetRasterBandXSize(ov), oh = GDALGetRasterBandYSize(ov);
        EXPECT_EQ(ow, (w + (1 << levels) - 1) >> levels);
        std::vector<float> o(std::size_t(ow) * std::size_t(oh));
        ASSERT_EQ(GDALRasterIO(ov, GF_Read, 0, 0, ow, oh, o.data(), ow, oh, GDT_Float32, 0, 0), CE_None);
        if (layer.name == "class") {
            std::size_t known = 0;
            for (float c : o) known += c == 1.0f || c == 2.0f;
            EXPECT_GT(known, 0u);
        }
    }
    GDALClose(ds);
}

/// Two layers with a patch of cells around (0, 0) and one around (far, far): a box of far + 1
/// cells a side, empty between them.
LayerTiles twoPatches(std::int64_t far) {
    LayerTiles t = twoLayers(0.2);
    for (std::int64_t i = 0; i < 100; ++i) {
        t.at(0, i, 2 * i) = float(i) * 0.25f, t.at(1, i, 2 * i) = 1;
        t.at(0, far - i, far - 3 * i) = -float(i), t.at(1, far - i, far - 3 * i) = 2;
    }
    t.at(0, 5, 0) = std::numeric_limits<float>::infinity();
    t.setBox(0, 0, far, far);
    return t;
}

/// The value of layer band `b` at cell (ix, iy) of the COG at `path` (gt: its geotransform).
float cogCell(GDALDatasetH ds, int b, std::int64_t ix, std::int64_t iy, double res) {
    double gt[6];
    EXPECT_EQ(GDALGetGeoTransform(ds, gt), CE_None);
    const int col = int(std::lround(((double(ix) + 0.5) * res - gt[0]) / gt[1] - 0.5));
    const int row = int(std::lround(((double(iy) + 0.5) * res - gt[3]) / gt[5] - 0.5));
    float v = 0;
    EXPECT_EQ(GDALRasterIO(GDALGetRasterBand(ds, b), GF_Read, col, row, 1, 1, &v, 1, 1, GDT_Float32, 0, 0), CE_None);
    return v;
}

/// `bytes` opened by GDAL as the in-memory file `name` (not copied: `bytes` must outlive it), or
/// nullptr.
GDALDatasetH openInMemory(const std::string& bytes, const std::string& name) {
    GDALAllRegister();
    VSILFILE* f = VSIFileFromMemBuffer(name.c_str(), reinterpret_cast<GByte*>(const_cast<char*>(bytes.data())), vsi_l_offset(bytes.size()), FALSE);
    if (!f) return nullptr;
    VSIFCloseL(f);
    return GDALOpenEx(name.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr);
}

// #35: the COG of a sparse box (a pose jump) has the blocks with cells and nothing else: the
// empty blocks are absent from the file (GDAL reports them empty) and read as nodata (NaN), at
// full resolution and in the overviews; and the file is exactly what GDAL's COG driver writes
// from it (the driver that wrote the layers before, reading every block of the box: 15 s for a
// pose jump of 6 km, where gseg now copies the compressed blocks it wrote).
TEST(LayerTiles, TheCogOfASparseBoxLeavesItsEmptyBlocksOutAndIsWhatGdalsCogDriverWrites) {
    const LayerTiles t = twoPatches(3000);
    const std::string bytes = gseg::map::encodeLayersCog(t, 256);
    const std::string name = "/vsimem/test_layer_tiles_sparse.tif";
    GDALDatasetH ds = openInMemory(bytes, name);
    ASSERT_NE(ds, nullptr);
    EXPECT_STREQ(GDALGetMetadataItem(ds, "LAYOUT", "IMAGE_STRUCTURE"), "COG");
    EXPECT_EQ(bytes.substr(0, 4), std::string("II*\0", 4)) << "a classic TIFF: under 2 GB of values";
    const int levels = gseg::map::cogOverviewCount(t.boxWidth(), t.boxHeight(), 256);
    EXPECT_EQ(levels, 4);
    const int w = GDALGetRasterXSize(ds), h = GDALGetRasterYSize(ds);
    EXPECT_EQ(w, 3008);  // 3001 cells widened to whole cells of the coarsest overview (16)
    EXPECT_EQ(h, 3008);
    // The cells read back, +inf as kNoLimit; a cell between the patches is nodata.
    EXPECT_EQ(cogCell(ds, 1, 40, 80, 0.2), 10.0f);
    EXPECT_EQ(cogCell(ds, 2, 40, 80, 0.2), 1.0f);
    EXPECT_EQ(cogCell(ds, 1, 3000 - 7, 3000 - 21, 0.2), -7.0f);
    EXPECT_EQ(cogCell(ds, 2, 3000 - 7, 3000 - 21, 0.2), 2.0f);
    EXPECT_EQ(cogCell(ds, 1, 5, 0, 0.2), gseg::map::kNoLimit);
    EXPECT_TRUE(std::isnan(cogCell(ds, 1, 1500, 1500, 0.2)));
    for (int b = 1; b <= 2; ++b) {
        GDALRasterBandH band = GDALGetRasterBand(ds, b);
        int hasNodata = 0;
        EXPECT_TRUE(std::isnan(GDALGetRasterNoDataValue(band, &hasNodata)));
        EXPECT_TRUE(hasNodata);
        ASSERT_EQ(GDALGetOverviewCount(band), levels);
        for (int k = -1; k < levels; ++k) {
            GDALRasterBandH level = k < 0 ? band : GDALGetOverview(band, k);
            const int lw = GDALGetRasterBandXSize(level), lh = GDALGetRasterBandYSize(level);
            int bx = 0, by = 0;
            GDALGetBlockSize(level, &bx, &by);
            EXPECT_EQ(bx, 256);
            EXPECT_EQ(by, 256);
            int empty = 0, withData = 0;
            std::vector<float> v(256 * 256);
            for (int r = 0; r < lh; r += 256)
                for (int c = 0; c < lw; c += 256) {
                    const int bw = std::min(256, lw - c), bh = std::min(256, lh - r);
                    if (GDALGetDataCoverageStatus(level, c, r, bw, bh, 0, nullptr) != GDAL_DATA_COVERAGE_STATUS_EMPTY) {
                        ++withData;
                        continue;
                    }
                    ++empty;
                    ASSERT_EQ(GDALRasterIO(level, GF_Read, c, r, bw, bh, v.data(), bw, bh, GDT_Float32, 0, 0), CE_None);
                    EXPECT_TRUE(std::all_of(v.begin(), v.begin() + bw * bh, [](float x) { return std::isnan(x); }));
                }
            if (k < 0) {
                EXPECT_GE(withData, 2) << "the blocks of the tiles around each patch";
                EXPECT_LE(withData, 6);
                EXPECT_EQ(empty + withData, 12 * 12);
            } else {
                EXPECT_GE(withData, 1);
            }
        }
    }
    GDALClose(ds);
    // GDAL's COG driver, given this COG with its overviews, writes the same bytes.
    const char* options[] = {"COMPRESS=DEFLATE", "PREDICTOR=YES", "BLOCKSIZE=256", "OVERVIEWS=FORCE_USE_EXISTING", "SPARSE_OK=TRUE",
                             "BIGTIFF=IF_SAFER", nullptr};
    ds = GDALOpenEx(name.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr);
    ASSERT_NE(ds, nullptr);
    const std::string copy = "/vsimem/test_layer_tiles_sparse_copy.tif";
    GDALDatasetH c = GDALCreateCopy(GDALGetDriverByName("COG"), copy.c_str(), ds, FALSE, const_cast<char**>(options), nullptr, nullptr);
    ASSERT_NE(c, nullptr);
    GDALClose(c);
    GDALClose(ds);
    vsi_l_offset size = 0;
    const GByte* data = VSIGetMemFileBuffer(copy.c_str(), &size, FALSE);
    ASSERT_NE(data, nullptr);
    const std::string gdalBytes(reinterpret_cast<const char*>(data), std::size_t(size));
    VSIUnlink(copy.c_str());
    VSIUnlink(name.c_str());
    EXPECT_EQ(gdalBytes.size(), bytes.size());
    EXPECT_TRUE(gdalBytes == bytes) << "byte for byte";
}

// #35: a pose jump's box (21760 cells a side, 3.8 GB of two float layers): a BigTIFF COG of a
// few blocks, the rest absent and read as nodata.
TEST(LayerTiles, ThePoseJumpCogIsABigTiffOfTheBlocksSeen) {
    const LayerTiles t = twoPatches(21700);
    const std::string bytes = gseg::map::encodeLayersCog(t);
    EXPECT_EQ(bytes.substr(0, 4), std::string("II+\0", 4)) << "BigTIFF: over 2 GB of values, as GDAL's BIGTIFF=IF_SAFER";
    EXPECT_LT(bytes.size(), 200000u) << "the blocks seen";
    const std::string name = "/vsimem/test_layer_tiles_jump.tif";
    GDALDatasetH ds = openInMemory(bytes, name);
    ASSERT_NE(ds, nullptr);
    EXPECT_STREQ(GDALGetMetadataItem(ds, "LAYOUT", "IMAGE_STRUCTURE"), "COG");
    EXPECT_EQ(GDALGetRasterXSize(ds), 21760);
    EXPECT_EQ(cogCell(ds, 1, 40, 80, 0.2), 10.0f);
    EXPECT_EQ(cogCell(ds, 2, 21700 - 7, 21700 - 21, 0.2), 2.0f);
    EXPECT_TRUE(std::isnan(cogCell(ds, 1, 10000, 10000, 0.2)));
    GDALRasterBandH band = GDALGetRasterBand(ds, 1);
    EXPECT_EQ(GDALGetOverviewCount(band), 6);
    double percent = 0;
    EXPECT_EQ(GDALGetDataCoverageStatus(band, 0, 0, 21760, 21760, 0, &percent) & GDAL_DATA_COVERAGE_STATUS_EMPTY, GDAL_DATA_COVERAGE_STATUS_EMPTY);
    EXPECT_LT(percent, 1.0) << "2 blocks of 1849";
    GDALRasterBandH coarsest = GDALGetOverview(band, 5);
    std::vector<float> v(std::size_t(GDALGetRasterBandXSize(coarsest)) * std::size_t(GDALGetRasterBandYSize(coarsest)));
    ASSERT_EQ(GDALRasterIO(coarsest, GF_Read, 0, 0, GDALGetRasterBandXSize(coarsest), GDALGetRasterBandYSize(coarsest), v.data(),
                           GDALGetRasterBandXSize(coarsest), GDALGetRasterBandYSize(coarsest), GDT_Float32, 0, 0),
              CE_None);
    EXPECT_GT(std::count_if(v.begin(), v.end(), [](float x) { return !std::isnan(x); }), 0);
    EXPECT_GT(std::count_if(v.begin(), v.end(), [](float x) { return std::isnan(x); }), 1000);
    GDALClose(ds);
    VSIUnlink(name.c_str());
}

/// The bytes of the file at `path`.
std::string fileBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Two writers (the pictures encoded on a second thread while the other files are written, as
// rawlog-octomap does with two or more threads): the same files, byte for byte, as one writer,
// for a map written as one grid and as tiles.
TEST(LayerTiles, TwoWritersWriteTheSameFilesAsOne) {
    const fs::path dir = gseg::test::freshDir("layer_tiles", "writers");
    TraversabilityMap map;
    insertScan(map, 0, 0);
    insertScan(map, 30, 0);
    for (const int tiledAbove : {4096, 100}) {
        MapOutputOptions how;
        how.tiledAbove = tiledAbove;
        const std::string suffix = std::to_string(tiledAbove);
        fs::create_directories(dir / ("one" + suffix));
        fs::create_directories(dir / ("two" + suffix));
        how.writers = 1;
        const std::vector<std::string> one = map.write((dir / ("one" + suffix) / "m").string(), how);
        how.writers = 2;
        const std::vector<std::string> two = map.write((dir / ("two" + suffix) / "m").string(), how);
        ASSERT_EQ(one.size(), two.size());
        EXPECT_GE(one.size(), 17u);
        for (std::size_t i = 0; i < one.size(); ++i) {
            EXPECT_EQ(fs::path(one[i]).filename(), fs::path(two[i]).filename());
            const std::string a = fileBytes(one[i]);
            EXPECT_FALSE(a.empty()) << one[i];
            EXPECT_TRUE(a == fileBytes(two[i])) << two[i];
        }
    }
    MapOutputOptions bad;
    bad.writers = 3;
    EXPECT_THROW(bad.validate(), std::invalid_argument);
    bad.writers = 0;
    EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(LayerTiles, ABigMapIsWrittenAsTilesWithPicturesOfAnOverviewASmallOneAsBefore) {
    const fs::path dir = gseg::test::freshDir("layer_tiles", "switch");
    TraversabilityMap map;
    insertScan(map, 0, 0);
    insertScan(map, 30, 0);
    MapOutputOptions how;
    how.tiledAbove = 100;  // the box is about 250 cells wide
    const std::string big = (dir / "big").string(), small = (dir / "small").string();
    map.write(big, how);
    EXPECT_TRUE(fs::exists(big + "_costmap_metadata.yaml"));
    EXPECT_FALSE(fs::exists(big + "_costmap.pgm"));
    how.tiledAbove = 4096;
    const std::vector<std::string> paths = map.write(small, how);
    EXPECT_EQ(paths, TraversabilityMap::outputPaths(small));
    EXPECT_TRUE(fs::exists(small + "_costmap.pgm"));
    EXPECT_FALSE(fs::exists(small + "_costmap_metadata.yaml"));
    // Pictures and GeoTIFF in both; a picture of the overview is at most pictureSide cells a side.
    EXPECT_TRUE(fs::exists(big + "_layer_class.png"));
    EXPECT_TRUE(fs::exists(big + "_layers.tif"));
    how.pictureSide = 8;
    EXPECT_THROW(map.write(big, how), std::invalid_argument) << "pictureSide below 16";
    how.pictureSide = 2048, how.costmapTile = 32;
    EXPECT_THROW(map.write(big, how), std::invalid_argument) << "costmapTile below 64";
    // The tiles of an earlier tiled run are never replaced without overwrite (the tools' -w): with
    // every other file of the map gone, their metadata still stops the up-front check.
    for (const std::string& path : TraversabilityMap::outputPaths(big)) fs::remove(path);
    std::vector<gseg::io::NamedPath> outputs, named;
    for (const std::string& path : TraversabilityMap::pathsToCheck(big)) outputs.push_back({"-o", path});
    for (const std::string& path : TraversabilityMap::outputPaths(big)) named.push_back({"-o", path});
    EXPECT_NO_THROW(gseg::io::checkOutputs({}, named, {false, false})) << "the fixed names alone miss the tiles";
    EXPECT_THROW(gseg::io::checkOutputs({}, outputs, {false, false}), std::invalid_argument);
    EXPECT_NO_THROW(gseg::io::checkOutputs({}, outputs, {true, false}));
}

/// Maps `positions` in a child under RLIMIT_AS `limitBytes` and writes the maps (tiled where
/// big); the child exits 0 when written, its peak resident memory [MB] beside. (Unused under
/// AddressSanitizer, whose shadow memory does not fit an address-space limit.)
[[maybe_unused]] void mapUnderLimit(const std::vector<Eigen::Vector2d>& positions, double limitBytes, const fs::path& dir, long& peakMb,
                   const gseg::map::TraversabilityOptions& options = {}) {
    const fs::path peakFile = dir / "peak_kb";
    const auto child = gseg::test::runInChild([&] {
        rlimit l{};
        ::getrlimit(RLIMIT_AS, &l);
        l.rlim_cur = rlim_t(limitBytes);
        if (::setrlimit(RLIMIT_AS, &l) != 0) return 11;
        TraversabilityMap map(options);
        for (const Eigen::Vector2d& p : positions) insertScan(map, p.x(), p.y());
        map.write((dir / "m").string());
        std::ofstream(peakFile) << peakKb();
        return 0;
    });
    ASSERT_TRUE(child.exited) << "signal " << child.signal;
    ASSERT_EQ(child.code, 0);
    std::ifstream(peakFile) >> peakMb;
    peakMb /= 1024;
    EXPECT_TRUE(fs::exists(dir / "m_costmap_metadata.yaml")) << "a big box: tiles";
    EXPECT_TRUE(fs::exists(dir / "m_layers.tif"));
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp"), "") << "no temporary";
}

TEST(LayerTiles, APoseJumpOfSixKilometresMapsUnderFourGigabytesOfAddressSpace) {
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "a limit of the address space and AddressSanitizer's shadow memory do not mix";
#else
    const fs::path dir = gseg::test::freshDir("layer_tiles", "jump");
    long peakMb = 0;
    // The second scan 4243 m along x and y: a box of 21400 cells a side (3.7 GB of 8 float layers
    // as one grid; before #35 the layers and their temporaries were dense over it).
    mapUnderLimit({{0, 0}, {4243, 4243}}, 4e9, dir, peakMb);
    EXPECT_LT(peakMb, 1000) << "the ground seen, not the box";
    const Metadata m = readMetadata((dir / "m_costmap_metadata.yaml").string());
    EXPECT_LE(m.tiles.size(), 5u) << "at most 4 tiles around the first scan, 1 around the second";
    EXPECT_EQ(m.tiles.count("m_costmap_20_20.yaml"), 1u) << "the second scan's tile, at 4096 m";
#endif
}

TEST(LayerTiles, ATenKilometreLoopMapsUnderFourGigabytesOfAddressSpace) {
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "a limit of the address space and AddressSanitizer's shadow memory do not mix";
#else
    const fs::path dir = gseg::test::freshDir("layer_tiles", "loop");
    // A 10 km x 10 km square loop (map x, y from -5 km to 5 km), a scan every 500 m: 80 scans.
    std::vector<Eigen::Vector2d> loop;
    const Eigen::Vector2d corners[5] = {{-5000, -5000}, {5000, -5000}, {5000, 5000}, {-5000, 5000}, {-5000, -5000}};
    for (int side = 0; side < 4; ++side)
        for (int k = 0; k < 20; ++k) loop.push_back(corners[side] + (corners[side + 1] - corners[side]) * (k / 20.0));
    // At 0.5 m: a box of 20000 cells a side (13 GB as one grid of 8 float layers), written as a
    // COG of the blocks seen.
    gseg::map::TraversabilityOptions coarse;
    coarse.resolution = 0.5;
    long peakMb = 0;
    mapUnderLimit(loop, 4e9, dir, peakMb, coarse);
    EXPECT_LT(peakMb, 1000) << "the ground seen, not the box";
    const Metadata m = readMetadata((dir / "m_costmap_metadata.yaml").string());
    EXPECT_GE(m.tiles.size(), 80u / 3) << "costmap tiles of 512 m: about one per scan and corner";
    EXPECT_LE(m.tiles.size(), 4 * 80u);
#endif
}

}  // namespace
