#include "map_scene.hpp"

#include <gseg/mrpt/gzip_stream.hpp>
#include <gseg/map/layer_grid.hpp>
#include <gseg/mrpt/scene.hpp>
#include <gseg/map/map_colours.hpp>

#include <mrpt/opengl/COctoMapVoxels.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/CSetOfTriangles.h>
#include <mrpt/opengl/stock_objects.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace gseg::map::detail {
namespace {

/// [m/m] the elevation's slope along one axis at a cell: central difference over the known
/// neighbours, one-sided at an edge or beside an unknown cell, 0 without a known neighbour.
float gradient(float before, float here, float after, float cell) {
    const bool b = std::isfinite(before), a = std::isfinite(after);
    if (b && a) return (after - before) / (2 * cell);
    if (a) return (after - here) / cell;
    if (b) return (here - before) / cell;
    return 0;
}

}  // namespace

std::shared_ptr<::mrpt::opengl::CSetOfTriangles> elevationMesh(const LayerGrid& layers) {
    const LayerGrid::Layer& elevation = layers.layer("elevation");
    const LayerGrid::Layer* cls = layers.find("class");
    if (elevation.values.size() != layers.cells() || (cls && cls->values.size() != layers.cells()))
        throw std::invalid_argument("elevation mesh: a layer without one value per cell");
    const float nan = std::numeric_limits<float>::quiet_NaN(), res = float(layers.resolution());
    auto z = [&](int cx, int cy) { return layers.inside(cx, cy) ? elevation.values[layers.index(cx, cy)] : nan; };
    auto mesh = ::mrpt::opengl::CSetOfTriangles::Create();
    mesh->setName("gseg 2.5D map: a tile per cell at its ground elevation; green traversable, red not traversable, grey no class; "
                  "cells without elevation left out");
    std::size_t known = 0;
    for (float v : elevation.values) known += std::isfinite(v) ? 1 : 0;
    mesh->reserve(2 * known);
    for (int cy = 0; cy < layers.height(); ++cy)
        for (int cx = 0; cx < layers.width(); ++cx) {
            const float h = z(cx, cy);
            if (!std::isfinite(h)) continue;
            const float c = cls ? cls->values[layers.index(cx, cy)] : nan;
            const Rgb rgb = colourOf(c == 1.0f ? ColumnClass::Traversable : c == 2.0f ? ColumnClass::Obstacle : ColumnClass::Unknown);
            const ::mrpt::math::TVector3Df n(-gradient(z(cx - 1, cy), h, z(cx + 1, cy), res), -gradient(z(cx, cy - 1), h, z(cx, cy + 1), res), 1.0f);
            const float x0 = float(layers.originX() + cx * layers.resolution()), y0 = float(layers.originY() + cy * layers.resolution());
            const ::mrpt::math::TPoint3Df p00(x0, y0, h), p10(x0 + res, y0, h), p11(x0 + res, y0 + res, h), p01(x0, y0 + res, h);
            for (const auto& tri : {::mrpt::opengl::TTriangle(p00, p10, p11, n, n, n), ::mrpt::opengl::TTriangle(p00, p11, p01, n, n, n)}) {
                ::mrpt::opengl::TTriangle t = tri;
                t.setColor(::mrpt::img::TColor(rgb.r, rgb.g, rgb.b));
                mesh->insertTriangle(t);
            }
        }
    return mesh;
}

double pathMarkSize(double extent, double resolution) {
    return std::max(2 * resolution, std::min(5.0, 0.01 * extent));
}

void writeMapScene(gseg::io::AtomicFile& file, const std::vector<float>& xyz,
                   const std::vector<std::uint8_t>& labels, double resolution, const std::vector<Eigen::Vector3d>& path,
                   const LayerGrid* layers, std::size_t groundUnderObstacles) {
    namespace gl = ::mrpt::opengl;
    auto voxels = gl::COctoMapVoxels::Create();
    voxels->setName("gseg traversability map: ground voxels green, obstacle voxels red");
    voxels->resizeVoxelSets(2);  // 0: ground, 1: obstacles
    voxels->showGridLines(false);
    voxels->enableLights(true);
    // Without culling, a voxel's dark bottom face wins the depth test against its top face
    // beyond some 40 m from the camera (24-bit depth buffer): the far map turned black.
    voxels->cullFaces(::mrpt::opengl::TCullFace::BACK);
    voxels->enableCubeTransparency(false);
    const Rgb colours[2] = {colourOf(ColumnClass::Obstacle), colourOf(ColumnClass::Traversable)};
    const std::size_t ground = std::size_t(std::count(labels.begin(), labels.end(), std::uint8_t(1)));
    voxels->reserveVoxels(0, ground);  // exactly: no doubling of the largest vectors of the run
    voxels->reserveVoxels(1, labels.size() - ground);
    for (std::size_t i = 0; i < labels.size(); ++i) {
        const Rgb c = colours[labels[i]];
        voxels->push_back_Voxel(labels[i] ? 0 : 1, gl::COctoMapVoxels::TVoxel({xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]},
                                                                                  resolution, ::mrpt::img::TColor(c.r, c.g, c.b)));
    }
    // The box of the voxels and the path: the camera frames it, the path marks scale with it.
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    bool any = false;
    const auto grow = [&](float x, float y, float z) {
        const float p[3] = {x, y, z};
        for (int a = 0; a < 3; ++a) lo[a] = any ? std::min(lo[a], p[a]) : p[a], hi[a] = any ? std::max(hi[a], p[a]) : p[a];
        any = true;
    };
    for (std::size_t i = 0; i < labels.size(); ++i) grow(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    for (const auto& p : path) grow(float(p.x()), float(p.y()), float(p.z()));
    gl::COpenGLScene scene;
    // Light from above (almost straight down) and mostly ambient, so that every face of a voxel
    // shows 80 to 100 % of the legend's colour: with MRPT's default light (35 deg, ambient 0.2) the
    // faces SceneViewer3D 2.5.8 draws of the voxels seen from above (with back-face culling, the
    // bottom faces: COctoMapVoxels winds them the other way) came out at 40 % (measured on a
    // screenshot of drive 00: (24, 72, 30) for the legend's (60, 180, 75)).
    auto& light = scene.getViewport("main")->lightParameters();
    light.direction = {-0.1f, -0.2f, -0.9747f};
    light.ambient = {0.8f, 0.8f, 0.8f, 1.0f};
    light.diffuse = {0.2f, 0.2f, 0.2f, 1.0f};
    light.specular = {0.0f, 0.0f, 0.0f, 1.0f};
    scene.insert(voxels);
    auto line = gl::CSetOfLines::Create();
    line->setName("driven path (sensor positions), blue");
    line->setColor_u8(40, 120, 255);
    line->setLineWidth(3);
    for (std::size_t i = 1; i < path.size(); ++i)
        line->appendLine(path[i - 1].x(), path[i - 1].y(), path[i - 1].z(), path[i].x(), path[i].y(), path[i].z());
    scene.insert(line);
    // Lines are one pixel wide in most OpenGL core profiles: blue boxes at the sensor positions,
    // 1 % of the map's extent, make the path visible on a whole drive.
    const float extent = any ? std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}) : 0.f;
    const double mark = pathMarkSize(extent, resolution);
    auto marks = gl::COctoMapVoxels::Create();
    marks->setName("sensor positions, blue");
    marks->resizeVoxelSets(1);
    marks->showGridLines(false);
    marks->enableLights(true);
    marks->enableCubeTransparency(false);
    marks->cullFaces(::mrpt::opengl::TCullFace::BACK);
    for (const auto& p : path)
        marks->push_back_Voxel(0, gl::COctoMapVoxels::TVoxel({float(p.x()), float(p.y()), float(p.z())}, mark,
                                                             ::mrpt::img::TColor(40, 120, 255)));
    scene.insert(marks);
    auto axes = gl::stock_objects::CornerXYZ(2.0f);
    axes->setName("start of the path: x (red), y (green), z (blue), 2 m");
    if (!path.empty()) axes->setLocation(path[0].x(), path[0].y(), path[0].z());
    scene.insert(axes);
    if (layers && layers->find("elevation")) scene.insert(elevationMesh(*layers));
    char title[96];
    std::snprintf(title, sizeof title, "gseg traversability map, %.2f m voxels", resolution);
    std::vector<gseg::mrpt::SceneLegendLine> legend;
    // The counts the console prints ("voxels (0.20 m): N ground, M obstacle"): a ground voxel under
    // an obstacle voxel is shown red, and the legend says how many.
    legend.push_back({colours[1], "ground voxels: " + std::to_string(ground + groundUnderObstacles) +
                                      (groundUnderObstacles ? " (" + std::to_string(groundUnderObstacles) + " under obstacles, shown red)" : "")});
    legend.push_back({colours[0], "obstacle voxels: " + std::to_string(labels.size() - ground)});
    if (layers && layers->find("elevation"))
        legend.push_back({Rgb{170, 170, 170}, "2.5D map: a tile per cell at its ground elevation, green traversable, red not"});
    char pathLine[128];
    std::snprintf(pathLine, sizeof pathLine, "driven path: a %.1f m box at each of %zu sensor positions", mark, path.size());
    legend.push_back({Rgb{40, 120, 255}, pathLine});
    legend.push_back({Rgb{200, 200, 200}, "axes at the start: x red, y green, z up blue, 2 m"});
    gseg::mrpt::addLegendAndCamera(scene, title, legend, lo, hi);
    gseg::mrpt::writeGzipObject(file, scene);
}

}  // namespace gseg::map::detail
