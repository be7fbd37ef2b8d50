// The GeoTIFF of the map's 2.5D layers (gseg/map/layer_file.hpp): every band and value back
// (NaN included) on seeded grids of odd sizes and negative origins, the same bytes for the same
// grid, GDAL's own tools reading the file, and bad files refused with the file named.
#include <gseg/io/atomic_file.hpp>
#include <gseg/map/layer_file.hpp>

#include <support/child.hpp>
#include <support/output_files.hpp>
#include <support/paths.hpp>

#include <gdal.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <thread>

namespace {

using gseg::map::LayerGrid;

/// The layers the map layer produces, with their units; values drawn from `seed`, about a fifth
/// of the cells unknown (NaN); `class` takes 1, 2 or NaN.
LayerGrid syntheticGrid(int w, int h, double res, double ox, double oy, unsigned seed) {
    LayerGrid g(w, h, res, ox, oy);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-3.0f, 40.0f);
    std::bernoulli_distribution unknown(0.2);
    const char* layers[][3] = {{"elevation", "m", "ground height from the ground points"},
                               {"slope", "deg", "ground inclination"},
                               {"step", "m", "largest height jump to a neighbour"},
                               {"roughness", "m", "spread of the ground heights"},
                               {"clearance", "m", "free height above the ground"},
                               {"class", "-", "1 traversable, 2 not traversable, NaN unknown"},
                               {"cost", "-", "planner cost"}};
    for (const auto& l : layers) {
        auto& layer = g.add(l[0], l[1], l[2]);
        for (float& v : layer.values)
            v = unknown(rng) ? std::numeric_limits<float>::quiet_NaN() : std::strcmp(l[0], "class") == 0 ? float(1 + rng() % 2) : u(rng);
    }
    return g;
}

std::string fileIn(const std::string& test, const std::string& name) {
    return (gseg::test::freshDir("layer_file", test) / name).string();
}

void writeBytes(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

void expectSameGrid(const LayerGrid& a, const LayerGrid& b) {
    ASSERT_EQ(a.width(), b.width());
    ASSERT_EQ(a.height(), b.height());
    EXPECT_NEAR(a.resolution(), b.resolution(), 1e-12);
    EXPECT_NEAR(a.originX(), b.originX(), 1e-9);
    EXPECT_NEAR(a.originY(), b.originY(), 1e-9);
    ASSERT_EQ(a.layers().size(), b.layers().size());
    for (std::size_t i = 0; i < a.layers().size(); ++i) {
        const auto &la = a.layers()[i], &lb = b.layers()[i];
        EXPECT_EQ(la.name, lb.name);
        EXPECT_EQ(la.unit, lb.unit) << la.name;
        EXPECT_EQ(la.meaning, lb.meaning) << la.name;
        ASSERT_EQ(la.values.size(), lb.values.size());
        std::size_t differ = 0;
        for (std::size_t k = 0; k < la.values.size(); ++k)
            if (std::isnan(la.values[k]) ? !std::isnan(lb.values[k]) : la.values[k] != lb.values[k]) ++differ;
        EXPECT_EQ(differ, 0u) << la.name << ": cells whose value did not come back";
    }
}

bool haveGdalTools(std::string& why) {
    if (gseg::test::runCommand("command -v gdalinfo && command -v gdal_translate").status == 0) return true;
    why = "gdalinfo / gdal_translate not installed (Debian's gdal-bin): GDAL's own tools not tried";
    return false;
}

TEST(LayerFile, RoundTripsEveryBandAndValueOnOddSizesAndNegativeOrigins) {
    struct Case { int w, h; double res, ox, oy; };
    unsigned seed = 7;
    for (const Case c : {Case{1, 1, 0.2, -0.3, -0.1}, Case{7, 3, 0.2, -12.3, -7.7}, Case{13, 29, 0.25, -101.0, 4.4},
                         Case{101, 37, 0.1, 3.05, -250.15}}) {
        const LayerGrid g = syntheticGrid(c.w, c.h, c.res, c.ox, c.oy, seed++);
        const std::string path = fileIn("round_trip", "layers.tif");
        gseg::test::writeBytes(path, gseg::map::encodeLayersGeoTiff(g));
        SCOPED_TRACE(std::to_string(c.w) + " x " + std::to_string(c.h));
        expectSameGrid(g, gseg::map::readLayersGeoTiff(path));
    }
}

TEST(LayerFile, SameGridGivesTheSameBytes) {
    const std::string a = gseg::map::encodeLayersGeoTiff(syntheticGrid(31, 17, 0.2, -3.1, -1.7, 3));
    const std::string b = gseg::map::encodeLayersGeoTiff(syntheticGrid(31, 17, 0.2, -3.1, -1.7, 3));
    EXPECT_EQ(a, b);
    EXPECT_EQ(a, gseg::map::encodeLayersGeoTiff(syntheticGrid(31, 17, 0.2, -3.1, -1.7, 3)));
    EXPECT_NE(a, gseg::map::encodeLayersGeoTiff(syntheticGrid(31, 17, 0.2, -3.1, -1.7, 4)));  // the bytes carry the values
    EXPECT_EQ(a.compare(0, 4, std::string("II*\0", 4)), 0);
}

TEST(LayerFile, ThreadsEncodingAtOnceGetTheSameBytes) {
    const LayerGrid g = syntheticGrid(57, 23, 0.2, -1.3, -9.9, 21);
    const std::string want = gseg::map::encodeLayersGeoTiff(g);
    std::vector<std::string> got(4);
    std::vector<std::thread> threads;
    for (std::size_t t = 0; t < got.size(); ++t)
        threads.emplace_back([&, t] {
            for (int i = 0; i < 5; ++i) got[t] = gseg::map::encodeLayersGeoTiff(g);
        });
    for (auto& t : threads) t.join();
    for (const auto& bytes : got) EXPECT_EQ(bytes, want);
}

TEST(LayerFile, FirstRowIsTheLargestYAndCellsSitWhereTheGridSays) {
    // One known value per cell: 100 * cx + cy; the reader's rows must match, and so must the
    // file's north-up layout as GDAL reads it (row 0 = largest y).
    LayerGrid g(5, 3, 0.5, -1.0, -2.0);
    auto& e = g.add("elevation", "m", "test");
    for (int cy = 0; cy < 3; ++cy)
        for (int cx = 0; cx < 5; ++cx) e.values[g.index(cx, cy)] = float(100 * cx + cy);
    const std::string path = fileIn("layout", "layers.tif");
    gseg::test::writeBytes(path, gseg::map::encodeLayersGeoTiff(g));
    GDALAllRegister();
    GDALDatasetH ds = GDALOpen(path.c_str(), GA_ReadOnly);
    ASSERT_NE(ds, nullptr);
    double gt[6];
    ASSERT_EQ(GDALGetGeoTransform(ds, gt), CE_None);
    EXPECT_DOUBLE_EQ(gt[0], -1.0);
    EXPECT_DOUBLE_EQ(gt[1], 0.5);
    EXPECT_DOUBLE_EQ(gt[3], -0.5);  // top edge: originY + 3 * 0.5
    EXPECT_DOUBLE_EQ(gt[5], -0.5);
    float row0[5];
    ASSERT_EQ(GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Read, 0, 0, 5, 1, row0, 5, 1, GDT_Float32, 0, 0), CE_None);
    EXPECT_EQ(row0[0], 2.0f);    // cx 0, cy 2
    EXPECT_EQ(row0[4], 402.0f);  // cx 4, cy 2
    EXPECT_STREQ(GDALGetDescription(GDALGetRasterBand(ds, 1)), "elevation");
    EXPECT_STREQ(GDALGetRasterUnitType(GDALGetRasterBand(ds, 1)), "m");
    int hasNodata = 0;
    EXPECT_TRUE(std::isnan(GDALGetRasterNoDataValue(GDALGetRasterBand(ds, 1), &hasNodata)));
    EXPECT_TRUE(hasNodata);
    const std::string wkt = GDALGetProjectionRef(ds);
    EXPECT_NE(wkt.find("gseg map frame"), std::string::npos) << wkt;
    EXPECT_NE(wkt.find("metre"), std::string::npos) << wkt;
    GDALClose(ds);
    const LayerGrid back = gseg::map::readLayersGeoTiff(path);
    EXPECT_EQ(back.layer("elevation").values[back.index(3, 1)], 301.0f);
}

TEST(LayerFile, NoLimitIsAFiniteCapThatComesBackAsInfinity) {
    // #33: the clearance band held +inf where no obstacle is above the ground, and GDAL's
    // statistics (gdalinfo -stats, QGIS's stretch) came out NaN.
    LayerGrid g = syntheticGrid(9, 6, 0.2, -4.3, -2.1, 12);
    ASSERT_EQ(g.layers()[4].name, "clearance");
    auto& clearance = g.find("clearance")->values;
    for (std::size_t k = 0; k < clearance.size(); k += 3) clearance[k] = std::numeric_limits<float>::infinity();
    const std::string path = fileIn("no_limit", "layers.tif");
    gseg::test::writeBytes(path, gseg::map::encodeLayersGeoTiff(g));
    expectSameGrid(g, gseg::map::readLayersGeoTiff(path));  // +inf back as +inf, the other bands as they were
    // What GDAL reads: the cap, said in the band's metadata; no NO_LIMIT on a band without +-inf.
    GDALAllRegister();
    GDALDatasetH ds = GDALOpen(path.c_str(), GA_ReadOnly);
    ASSERT_NE(ds, nullptr);
    std::vector<float> row(9);
    ASSERT_EQ(GDALRasterIO(GDALGetRasterBand(ds, 5), GF_Read, 0, 5, 9, 1, row.data(), 9, 1, GDT_Float32, 0, 0), CE_None);
    EXPECT_EQ(row[0], gseg::map::kNoLimit) << "cell (0, 0), +inf, is the image's last row";
    const char* item = GDALGetMetadataItem(GDALGetRasterBand(ds, 5), "NO_LIMIT", nullptr);
    ASSERT_NE(item, nullptr);
    EXPECT_STREQ(item, "1000");
    EXPECT_EQ(GDALGetMetadataItem(GDALGetRasterBand(ds, 1), "NO_LIMIT", nullptr), nullptr);
    double stats[4] = {0, 0, 0, 0};
    ASSERT_EQ(GDALComputeRasterStatistics(GDALGetRasterBand(ds, 5), FALSE, &stats[0], &stats[1], &stats[2], &stats[3], nullptr, nullptr),
              CE_None);
    for (double v : stats) EXPECT_TRUE(std::isfinite(v)) << "min, max, mean, stddev: " << stats[0] << ", " << stats[1] << ", " << stats[2] << ", " << stats[3];
    EXPECT_EQ(stats[1], 1000.0);
    GDALClose(ds);
    std::string why;
    if (!haveGdalTools(why)) GTEST_SKIP() << why;
    const auto info = gseg::test::runCommand("gdalinfo -stats '" + path + "'");
    ASSERT_EQ(info.status, 0) << info.output;
    std::size_t statistics = 0;
    for (std::size_t at = 0; (at = info.output.find("STATISTICS_", at)) != std::string::npos; ++at) {
        const std::string line = info.output.substr(at, info.output.find('\n', at) - at);
        if (line.rfind("STATISTICS_VALID_PERCENT", 0) == 0) continue;
        ++statistics;
        EXPECT_EQ(line.find("nan"), std::string::npos) << line;
        EXPECT_EQ(line.find("inf"), std::string::npos) << line;
    }
    EXPECT_GE(statistics, 7u * 4) << "min, max, mean, stddev of each band:\n" << info.output;
    EXPECT_NE(info.output.find("STATISTICS_MAXIMUM=1000"), std::string::npos) << info.output;
    EXPECT_NE(info.output.find("NO_LIMIT=1000"), std::string::npos) << info.output;
}

TEST(LayerFile, GdalinfoListsEveryBandAndGdalTranslateReadsEveryValue) {
    std::string why;
    if (!haveGdalTools(why)) GTEST_SKIP() << why;
    const LayerGrid g = syntheticGrid(9, 6, 0.2, -4.3, -2.1, 11);
    const std::string path = fileIn("gdal_tools", "drive_layers.tif");
    gseg::test::writeBytes(path, gseg::map::encodeLayersGeoTiff(g));
    const auto info = gseg::test::runCommand("gdalinfo '" + path + "'");
    ASSERT_EQ(info.status, 0) << info.output;
    EXPECT_NE(info.output.find("Driver: GTiff/GeoTIFF"), std::string::npos) << info.output;
    EXPECT_NE(info.output.find("Size is 9, 6"), std::string::npos) << info.output;
    EXPECT_NE(info.output.find("Pixel Size = (0.200000000000000,-0.200000000000000)"), std::string::npos) << info.output;
    for (std::size_t b = 0; b < g.layers().size(); ++b) {
        const std::string band = "Band " + std::to_string(b + 1) + " Block=";
        const std::size_t at = info.output.find(band);
        ASSERT_NE(at, std::string::npos) << band << "\n" << info.output;
        const std::size_t next = info.output.find("Band " + std::to_string(b + 2) + " Block=");
        const std::string section = info.output.substr(at, next == std::string::npos ? std::string::npos : next - at);
        EXPECT_NE(section.find("Description = " + g.layers()[b].name), std::string::npos) << section;
        EXPECT_NE(section.find("NoData Value=nan"), std::string::npos) << section;
        EXPECT_NE(section.find("Unit Type: " + g.layers()[b].unit), std::string::npos) << section;
        EXPECT_NE(section.find("MEANING=" + g.layers()[b].meaning), std::string::npos) << section;
        // gdal_translate -of XYZ: one "x y value" line per cell, x and y the cell's centre.
        const auto xyz = gseg::test::runCommand("gdal_translate -q -b " + std::to_string(b + 1) + " -of XYZ '" + path + "' /vsistdout/");
        ASSERT_EQ(xyz.status, 0) << xyz.output;
        std::istringstream lines(xyz.output);
        std::string xs, ys, vs;
        std::size_t seen = 0, wrong = 0;
        while (lines >> xs >> ys >> vs) {
            const double x = std::stod(xs), y = std::stod(ys);
            const long long cx = g.cellX(x), cy = g.cellY(y);
            ASSERT_TRUE(g.inside(cx, cy)) << x << " " << y;
            EXPECT_NEAR(x, g.centreX(int(cx)), 1e-6);
            EXPECT_NEAR(y, g.centreY(int(cy)), 1e-6);
            const float want = g.layers()[b].values[g.index(int(cx), int(cy))];
            const bool nan = vs.find("nan") != std::string::npos || vs.find("NaN") != std::string::npos;
            if (std::isnan(want) ? !nan : (nan || std::fabs(std::stod(vs) - want) > 1e-4 * std::max(1.0f, std::fabs(want)))) ++wrong;
            ++seen;
        }
        EXPECT_EQ(seen, g.cells()) << g.layers()[b].name;
        EXPECT_EQ(wrong, 0u) << g.layers()[b].name;
    }
}

/// A GeoTIFF written by GDAL with the given geotransform (nullptr: none), one float32 band.
void gdalTiff(const std::string& path, const double* gt) {
    GDALAllRegister();
    GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), 4, 3, 1, GDT_Float32, nullptr);
    ASSERT_NE(ds, nullptr);
    if (gt) GDALSetGeoTransform(ds, const_cast<double*>(gt));
    float v[12] = {};
    ASSERT_EQ(GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, 4, 3, v, 4, 3, GDT_Float32, 0, 0), CE_None);
    GDALClose(ds);
}

void expectRefused(const std::string& path, const std::string& what) {
    try {
        gseg::map::readLayersGeoTiff(path);
        ADD_FAILURE() << path << ": read without error, expected '" << what << "'";
    } catch (const std::runtime_error& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.rfind(path + ": ", 0), 0u) << m;  // names the file first
        EXPECT_NE(m.find(what), std::string::npos) << m;
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
}

TEST(LayerFile, ReaderRefusesFilesThatAreNotLayerGeoTiffsNamingTheFile) {
    const std::filesystem::path dir = gseg::test::freshDir("layer_file", "refused");
    expectRefused((dir / "missing.tif").string(), "cannot open");
    writeBytes((dir / "text.tif").string(), "elevation,slope\n1,2\n");
    expectRefused((dir / "text.tif").string(), "not a GeoTIFF");
    writeBytes((dir / "empty.tif").string(), "");
    expectRefused((dir / "empty.tif").string(), "not a GeoTIFF");
    writeBytes((dir / "picture.tif").string(), std::string("\x89PNG\r\n\x1a\n", 8) + std::string(100, '\0'));
    expectRefused((dir / "picture.tif").string(), "not a GeoTIFF");
    // A TIFF header and nothing after it.
    writeBytes((dir / "header_only.tif").string(), std::string("II*\0\x08\0\0\0", 8));
    expectRefused((dir / "header_only.tif").string(), "not a readable GeoTIFF");

    const std::string whole = gseg::map::encodeLayersGeoTiff(syntheticGrid(64, 48, 0.2, -5, -5, 5));
    for (const double part : {0.3, 0.6, 0.9, 0.99}) {
        const std::string cut = (dir / ("cut_" + std::to_string(int(part * 100)) + ".tif")).string();
        writeBytes(cut, whole.substr(0, std::size_t(double(whole.size()) * part)));
        SCOPED_TRACE(cut);
        expectRefused(cut, "truncated");
    }

    const double rotated[6] = {10, 0.2, 0.05, 20, 0.05, -0.2};
    gdalTiff((dir / "rotated.tif").string(), rotated);
    expectRefused((dir / "rotated.tif").string(), "rotated");
    const double oblong[6] = {10, 0.2, 0, 20, 0, -0.4};
    gdalTiff((dir / "oblong.tif").string(), oblong);
    expectRefused((dir / "oblong.tif").string(), "not square");
    gdalTiff((dir / "plain.tif").string(), nullptr);
    expectRefused((dir / "plain.tif").string(), "no geotransform");
}

TEST(LayerFile, ReaderTakesSouthUpFilesAndNodataValues) {
    // A file GDAL wrote with rows growing in y and a nodata value of -9999: read into the grid's
    // rows, the nodata cells NaN.
    const std::string path = fileIn("south_up", "south_up.tif");
    GDALAllRegister();
    GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), 2, 2, 1, GDT_Float32, nullptr);
    ASSERT_NE(ds, nullptr);
    double gt[6] = {-1, 0.5, 0, -3, 0, 0.5};
    GDALSetGeoTransform(ds, gt);
    GDALSetRasterNoDataValue(GDALGetRasterBand(ds, 1), -9999);
    float v[4] = {1, 2, -9999, 4};  // row 0 = y in [-3, -2.5)
    ASSERT_EQ(GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, 2, 2, v, 2, 2, GDT_Float32, 0, 0), CE_None);
    GDALClose(ds);
    const LayerGrid g = gseg::map::readLayersGeoTiff(path);
    EXPECT_DOUBLE_EQ(g.originY(), -3.0);
    const auto& l = g.layer("band 1");
    EXPECT_EQ(l.values[g.index(1, 0)], 2.0f);
    EXPECT_TRUE(std::isnan(l.values[g.index(0, 1)]));
    EXPECT_EQ(l.values[g.index(1, 1)], 4.0f);
}

TEST(LayerFile, InvalidGridsAreRefusedAndNothingIsWritten) {
    const std::string path = fileIn("invalid", "layers.tif");
    EXPECT_THROW(gseg::map::encodeLayersGeoTiff(LayerGrid()), std::invalid_argument);
    EXPECT_THROW(gseg::map::encodeLayersGeoTiff(LayerGrid(3, 3, 0.2, 0, 0)), std::invalid_argument);  // no layers
    LayerGrid g(3, 3, 0.2, 0, 0);
    g.add("elevation", "m", "").values.resize(5);
    try {
        gseg::test::writeBytes(path, gseg::map::encodeLayersGeoTiff(g));
        ADD_FAILURE() << "a layer of 5 values on 9 cells was written";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("'elevation' has 5 values for 9 cells"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(path));
    EXPECT_EQ(gseg::test::entriesContaining(std::filesystem::path(path).parent_path().string(), ""), "");
}

TEST(LayerFile, AFailedWriteKeepsThePreviousFile) {
    const std::string path = fileIn("keep", "layers.tif");
    gseg::test::writeBytes(path, gseg::map::encodeLayersGeoTiff(syntheticGrid(4, 4, 0.2, 0, 0, 1)));
    const std::string before = gseg::test::readText(path);
    LayerGrid bad(4, 4, 0.2, 0, 0);
    bad.add("elevation", "m", "").values.clear();
    EXPECT_THROW(gseg::test::writeBytes(path, gseg::map::encodeLayersGeoTiff(bad)), std::invalid_argument);
    EXPECT_EQ(gseg::test::readText(path), before);
}

}  // namespace
