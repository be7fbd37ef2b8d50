// The map's .3Dscene (libgseg/src/map/map_scene.hpp): the 2.5D elevation as a mesh of tiles
// coloured by class, unknown cells left out, read back with MRPT.
#include "map_scene.hpp"

#include <gseg/io/atomic_file.hpp>
#include <gseg/map/layer_grid.hpp>
#include <gseg/map/map_colours.hpp>

#include <support/child.hpp>

#include <mrpt/opengl/COctoMapVoxels.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CSetOfTriangles.h>

#include <gtest/gtest.h>

#include <cmath>
#include <map>

namespace {

using gseg::map::LayerGrid;

/// A 7 x 5 grid at a negative origin: elevation = 0.1 * cx - 0.05 * cy + 1 (a plane rising along
/// x), unknown on the diagonal cx == cy; class 1 where cx < 4, 2 elsewhere, NaN at (6, 4).
LayerGrid planeGrid() {
    LayerGrid g(7, 5, 0.25, -2.0, -1.5);
    auto& e = g.add("elevation", "m", "ground height");
    auto& c = g.add("class", "-", "1 traversable, 2 not traversable");
    for (int cy = 0; cy < 5; ++cy)
        for (int cx = 0; cx < 7; ++cx) {
            e.values[g.index(cx, cy)] = cx == cy ? NAN : 0.1f * float(cx) - 0.05f * float(cy) + 1.0f;
            c.values[g.index(cx, cy)] = cx < 4 ? 1.0f : 2.0f;
        }
    c.values[g.index(6, 4)] = NAN;
    return g;
}

bool sameRgb(const mrpt::opengl::TTriangle& t, int k, gseg::map::Rgb c) { return t.r(k) == c.r && t.g(k) == c.g && t.b(k) == c.b; }

/// Checks every tile of `mesh` against the grid: 2 triangles per known cell, each vertex at a
/// corner of its cell at the cell's elevation, coloured by class.
void expectTilesOf(const mrpt::opengl::CSetOfTriangles& mesh, const LayerGrid& g) {
    const auto& e = g.layer("elevation").values;
    const auto& c = g.layer("class").values;
    std::size_t known = 0;
    for (float v : e) known += std::isfinite(v) ? 1 : 0;
    ASSERT_EQ(mesh.getTrianglesCount(), 2 * known);  // 6 vertices a known cell
    std::map<std::size_t, int> trianglesOfCell;
    for (std::size_t i = 0; i < mesh.getTrianglesCount(); ++i) {
        mrpt::opengl::TTriangle t;
        mesh.getTriangle(i, t);
        const float mx = (t.x(0) + t.x(1) + t.x(2)) / 3, my = (t.y(0) + t.y(1) + t.y(2)) / 3;
        const long long cx = g.cellX(mx), cy = g.cellY(my);
        ASSERT_TRUE(g.inside(cx, cy)) << mx << " " << my;
        const std::size_t cell = g.index(int(cx), int(cy));
        ++trianglesOfCell[cell];
        ASSERT_TRUE(std::isfinite(e[cell])) << "a tile over an unknown cell " << cx << ", " << cy;
        const gseg::map::Rgb want = gseg::map::colourOf(c[cell] == 1.0f   ? gseg::map::ColumnClass::Traversable
                                                        : c[cell] == 2.0f ? gseg::map::ColumnClass::Obstacle
                                                                          : gseg::map::ColumnClass::Unknown);
        for (int k = 0; k < 3; ++k) {
            EXPECT_FLOAT_EQ(t.z(k), e[cell]);
            EXPECT_NEAR(std::fmod(t.x(k) - g.originX() + 10 * g.resolution(), g.resolution()), 0.0, 1e-5);  // on a cell corner
            EXPECT_GE(t.x(k), g.originX() + cx * g.resolution() - 1e-5);
            EXPECT_LE(t.x(k), g.originX() + (cx + 1) * g.resolution() + 1e-5);
            EXPECT_GE(t.y(k), g.originY() + cy * g.resolution() - 1e-5);
            EXPECT_LE(t.y(k), g.originY() + (cy + 1) * g.resolution() + 1e-5);
            EXPECT_TRUE(sameRgb(t, k, want)) << cx << ", " << cy;
        }
        // Counter-clockwise seen from above: the face points up.
        const float cross = (t.x(1) - t.x(0)) * (t.y(2) - t.y(0)) - (t.y(1) - t.y(0)) * (t.x(2) - t.x(0));
        EXPECT_GT(cross, 0);
    }
    for (const auto& [cell, n] : trianglesOfCell) EXPECT_EQ(n, 2) << cell;
}

TEST(MapScene, ElevationMeshHasATilePerKnownCellAtItsHeightColouredByClass) {
    const LayerGrid g = planeGrid();
    const auto mesh = gseg::map::detail::elevationMesh(g);
    expectTilesOf(*mesh, g);
    // Shaded by the slope: the normal leans against the rise (+0.1 m per 0.25 m cell along x,
    // -0.05 m along y) where both neighbours are known (cell 3, 1), one-sided beside an unknown
    // cell (1, 0: x from the right only; y has none: 0).
    auto normalOf = [&](int cx, int cy) {
        for (std::size_t i = 0; i < mesh->getTrianglesCount(); ++i) {
            mrpt::opengl::TTriangle t;
            mesh->getTriangle(i, t);
            if (g.cellX((t.x(0) + t.x(1) + t.x(2)) / 3) == cx && g.cellY((t.y(0) + t.y(1) + t.y(2)) / 3) == cy) return t.vertices[0].normal;
        }
        ADD_FAILURE() << "no tile at " << cx << ", " << cy;
        return mrpt::math::TVector3Df(0, 0, 0);
    };
    EXPECT_NEAR(normalOf(3, 1).x, -0.4, 1e-5);
    EXPECT_NEAR(normalOf(3, 1).y, 0.2, 1e-5);
    EXPECT_FLOAT_EQ(normalOf(3, 1).z, 1.0f);
    EXPECT_NEAR(normalOf(1, 0).x, -0.4, 1e-5);
    EXPECT_NEAR(normalOf(1, 0).y, 0.0, 1e-6);
}

TEST(MapScene, ElevationMeshNeedsTheElevationLayer) {
    LayerGrid g(3, 3, 0.2, 0, 0);
    g.add("slope", "deg", "");
    EXPECT_THROW(gseg::map::detail::elevationMesh(g), std::out_of_range);
    g.add("elevation", "m", "").values.resize(4);
    EXPECT_THROW(gseg::map::detail::elevationMesh(g), std::invalid_argument);
    LayerGrid unknown(4, 2, 0.2, 0, 0);
    unknown.add("elevation", "m", "");
    EXPECT_EQ(gseg::map::detail::elevationMesh(unknown)->getTrianglesCount(), 0u);  // nothing at height 0
}

TEST(MapScene, SceneFileHoldsTheMeshAndMrptReadsItBack) {
    const LayerGrid g = planeGrid();
    const std::string path = (gseg::test::freshDir("map_scene", "mesh") / "map.3Dscene").string();
    {
        gseg::io::AtomicFile file(path);
        const std::vector<float> xyz = {0.1f, 0.1f, 1.1f};
        gseg::map::detail::writeMapScene(file, xyz, {1}, 0.2, {Eigen::Vector3d(0, 0, 1.7), Eigen::Vector3d(1, 0, 1.7)}, &g);
        file.commit();
    }
    mrpt::opengl::COpenGLScene scene;
    ASSERT_TRUE(scene.loadFromFile(path));
    const auto mesh = scene.getByClass<mrpt::opengl::CSetOfTriangles>();
    ASSERT_TRUE(mesh);
    EXPECT_NE(mesh->getName().find("2.5D"), std::string::npos) << mesh->getName();
    expectTilesOf(*mesh, g);
    EXPECT_TRUE(scene.getByClass<mrpt::opengl::COctoMapVoxels>());  // the voxels are still there

    // Without layers: the scene as before, no mesh.
    const std::string plain = (gseg::test::freshDir("map_scene", "plain") / "map.3Dscene").string();
    {
        gseg::io::AtomicFile file(plain);
        gseg::map::detail::writeMapScene(file, {0.1f, 0.1f, 1.1f}, {1}, 0.2, {Eigen::Vector3d(0, 0, 1.7)});
        file.commit();
    }
    mrpt::opengl::COpenGLScene without;
    ASSERT_TRUE(without.loadFromFile(plain));
    EXPECT_FALSE(without.getByClass<mrpt::opengl::CSetOfTriangles>());
}

TEST(MapScene, PathShowsOnAWholeDriveAndTheLightComesFromAbove) {
    // A 300 m drive: the boxes at the sensor positions are 1 % of the extent (3 m), not 0.4 m
    // specks; on a small map at least two voxels.
    EXPECT_DOUBLE_EQ(gseg::map::detail::pathMarkSize(300.0, 0.2), 3.0);
    EXPECT_DOUBLE_EQ(gseg::map::detail::pathMarkSize(10.0, 0.2), 0.4);
    EXPECT_DOUBLE_EQ(gseg::map::detail::pathMarkSize(5000.0, 0.2), 5.0);
    const std::string path = (gseg::test::freshDir("map_scene", "drive") / "map.3Dscene").string();
    {
        gseg::io::AtomicFile file(path);
        std::vector<Eigen::Vector3d> drive;
        for (int k = 0; k <= 300; k += 10) drive.emplace_back(double(k), 0, 1.7);
        gseg::map::detail::writeMapScene(file, {0.1f, 0.1f, 0.1f, 299.9f, 0.1f, 0.1f}, {1, 0}, 0.2, drive, nullptr, 0);
        file.commit();
    }
    mrpt::opengl::COpenGLScene scene;
    ASSERT_TRUE(scene.loadFromFile(path));
    std::size_t marks = 0;
    for (const auto& o : *scene.getViewport("main"))
        if (const auto v = std::dynamic_pointer_cast<mrpt::opengl::COctoMapVoxels>(o); v && v->getName() == "sensor positions, blue") {
            marks = v->getVoxelCount(0);
            ASSERT_GT(marks, 0u);
            EXPECT_NEAR(v->getVoxel(0, 0).side_length, 3.0, 0.01);
        }
    EXPECT_EQ(marks, 31u);
    // Lit from above, as read back: a top face (normal +z) gets ambient + diffuse = the legend's
    // colour, and any face at least 80 % of it (ambient).
    const auto& light = scene.getViewport("main")->lightParameters();
    EXPECT_LT(light.direction.z, -0.95f);
    EXPECT_NEAR(light.ambient.R + light.diffuse.R * -light.direction.z, 1.0f, 0.03f);
    EXPECT_GE(light.ambient.R, 0.8f);
}

}  // namespace
