#pragma once
// The map files of a run: their names (kMapFiles), and one map truth (#33): the class layer's
// picture (PREFIX_layer_class.png) shows the costmap (PREFIX_costmap.pgm) cell for cell, in the
// PGM's orientation (x right, y up). Header-only (MRPT tests only: the support library stays free
// of MRPT).

#include <gseg/map/column_class.hpp>
#include <gseg/map/map_colours.hpp>

#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>
#include <mrpt/math/CMatrixF.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace gseg::test {

/// The 17 files of `rawlog-octomap -o PREFIX` (and of map 00 of gseg-observations2map), PREFIX-relative,
/// stated here apart from the library's list (TraversabilityMap::outputPaths()) for the tests to check it.
inline const std::vector<std::string> kMapFiles = {
    "_ground.bt", "_obstacles.bt", "_traversability.ot", "_traversability.png", "_traversability.ply", "_traversability.3Dscene",
    "_costmap.pgm", "_costmap.yaml", "_layers.tif", "_layer_elevation.png", "_layer_slope.png", "_layer_step.png",
    "_layer_roughness.png", "_layer_clearance.png", "_layer_class.png", "_layer_cost.png", "_layer_source.png"};

/// A binary PGM (P5, maxval 255): width, height and the pixels, row 0 at the top.
struct Pgm {
    int width = 0, height = 0;
    std::vector<std::uint8_t> pixels;
    std::uint8_t at(int col, int row) const { return pixels[std::size_t(row) * std::size_t(width) + std::size_t(col)]; }
};

inline bool readPgm(const std::string& path, Pgm& pgm) {
    std::ifstream in(path, std::ios::binary);
    std::string magic;
    in >> magic;
    if (magic != "P5") return false;
    auto number = [&](int& v) {
        in >> std::ws;
        while (in.peek() == '#') {
            std::string comment;
            std::getline(in, comment);
            in >> std::ws;
        }
        return bool(in >> v);
    };
    int maxval = 0;
    if (!number(pgm.width) || !number(pgm.height) || !number(maxval) || maxval != 255) return false;
    in.get();  // the one whitespace before the pixels
    pgm.pixels.resize(std::size_t(pgm.width) * std::size_t(pgm.height));
    in.read(reinterpret_cast<char*>(pgm.pixels.data()), std::streamsize(pgm.pixels.size()));
    return bool(in);
}

/// Checks that the map area of `classPng` shows `costmapPgm` cell for cell: free (254) in the
/// traversable colour, occupied (0) in the obstacle colour, unknown (205) in the unknown colour,
/// PGM column c / row r at the picture's block c / r (x right, y up, no turn, no mirror). The map
/// area is found by trying every enlargement (1 to 16 pixels a cell), the picture's left margin
/// or a centred map, and every title band height (8 + 20 n + 8 pixels).
inline ::testing::AssertionResult classPictureShowsCostmap(const std::string& classPng, const std::string& costmapPgm) {
    Pgm pgm;
    if (!readPgm(costmapPgm, pgm)) return ::testing::AssertionFailure() << costmapPgm << ": not a P5 PGM";
    std::size_t counts[3] = {0, 0, 0};
    for (std::uint8_t v : pgm.pixels) ++counts[v == 254 ? 0 : v == 0 ? 1 : 2];
    ::mrpt::img::CImage img;
    if (!img.loadFromFile(classPng)) return ::testing::AssertionFailure() << classPng << ": cannot be read";
    ::mrpt::math::CMatrixFloat R, G, B;
    img.getAsRGBMatrices(R, G, B);
    if (img.getChannelsOrder() == "BGR") std::swap(R, B);
    const int w = int(img.getWidth()), h = int(img.getHeight());
    using gseg::map::ColumnClass;
    const gseg::map::Rgb want[3] = {gseg::map::colourOf(ColumnClass::Traversable), gseg::map::colourOf(ColumnClass::Obstacle),
                                    gseg::map::colourOf(ColumnClass::Unknown)};
    auto is = [&](int x, int y, gseg::map::Rgb c) {
        return std::lround(255 * R(y, x)) == c.r && std::lround(255 * G(y, x)) == c.g && std::lround(255 * B(y, x)) == c.b;
    };
    std::size_t best = pgm.pixels.size() + 1;
    for (int ppc = 1; ppc <= 16; ++ppc) {
        const int mw = pgm.width * ppc, mh = pgm.height * ppc;
        if (mw > w || mh > h) break;
        for (const int left : {12, (w - mw) / 2})
            for (int top = 36; top + mh <= h; top += 20) {
                std::size_t wrong = 0;
                for (int r = 0; r < pgm.height && wrong < best; ++r)
                    for (int c = 0; c < pgm.width && wrong < best; ++c) {
                        const std::uint8_t v = pgm.at(c, r);
                        wrong += !is(left + c * ppc + ppc / 2, top + r * ppc + ppc / 2, want[v == 254 ? 0 : v == 0 ? 1 : 2]);
                    }
                if (wrong == 0)
                    return ::testing::AssertionSuccess() << pgm.width << " x " << pgm.height << " cells (" << counts[0] << " free, "
                                                         << counts[1] << " occupied, " << counts[2] << " unknown) at " << ppc
                                                         << " px a cell";
                best = std::min(best, wrong);
            }
    }
    return ::testing::AssertionFailure() << classPng << " does not show " << costmapPgm << " (" << pgm.width << " x " << pgm.height
                                         << " cells): " << best << " cells differ at the best placement";
}

}  // namespace gseg::test
