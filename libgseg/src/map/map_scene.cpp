#include "map_scene.hpp"

#include <gseg/mrpt/gzip_stream.hpp>
#include <gseg/mrpt/scene.hpp>
#include <gseg/map/traversability_map.hpp>

#include <mrpt/opengl/COctoMapVoxels.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/stock_objects.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cstdio>

namespace gseg::map::detail {

void writeMapScene(gseg::io::AtomicFile& file, const std::vector<float>& xyz,
                   const std::vector<std::uint8_t>& labels, double resolution, const std::vector<Eigen::Vector3d>& path) {
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
    const Rgb colours[2] = {colourOf(CellClass::Obstacle), colourOf(CellClass::Traversable)};
    const std::size_t ground = std::size_t(std::count(labels.begin(), labels.end(), std::uint8_t(1)));
    voxels->reserveVoxels(0, ground);  // exactly: no doubling of the largest vectors of the run
    voxels->reserveVoxels(1, labels.size() - ground);
    for (std::size_t i = 0; i < labels.size(); ++i) {
        const Rgb c = colours[labels[i]];
        voxels->push_back_Voxel(labels[i] ? 0 : 1, gl::COctoMapVoxels::TVoxel({xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]},
                                                                                  resolution, ::mrpt::img::TColor(c.r, c.g, c.b)));
    }
    gl::COpenGLScene scene;
    scene.insert(voxels);
    auto line = gl::CSetOfLines::Create();
    line->setName("driven path (sensor positions), blue");
    line->setColor_u8(40, 120, 255);
    line->setLineWidth(3);
    for (std::size_t i = 1; i < path.size(); ++i)
        line->appendLine(path[i - 1].x(), path[i - 1].y(), path[i - 1].z(), path[i].x(), path[i].y(), path[i].z());
    scene.insert(line);
    // Lines are one pixel wide in most OpenGL core profiles: blue boxes at the sensor positions
    // make the path visible from afar.
    auto marks = gl::COctoMapVoxels::Create();
    marks->setName("sensor positions, blue");
    marks->resizeVoxelSets(1);
    marks->showGridLines(false);
    marks->enableLights(true);
    marks->enableCubeTransparency(false);
    marks->cullFaces(::mrpt::opengl::TCullFace::BACK);
    for (const auto& p : path)
        marks->push_back_Voxel(0, gl::COctoMapVoxels::TVoxel({float(p.x()), float(p.y()), float(p.z())}, 2 * resolution,
                                                             ::mrpt::img::TColor(40, 120, 255)));
    scene.insert(marks);
    auto axes = gl::stock_objects::CornerXYZ(2.0f);
    axes->setName("start of the path: x (red), y (green), z (blue), 2 m");
    if (!path.empty()) axes->setLocation(path[0].x(), path[0].y(), path[0].z());
    scene.insert(axes);
    // The legend and a camera framing the voxels and the path (the shared scene helper).
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    bool any = false;
    const auto grow = [&](float x, float y, float z) {
        const float p[3] = {x, y, z};
        for (int a = 0; a < 3; ++a) lo[a] = any ? std::min(lo[a], p[a]) : p[a], hi[a] = any ? std::max(hi[a], p[a]) : p[a];
        any = true;
    };
    for (std::size_t i = 0; i < labels.size(); ++i) grow(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    for (const auto& p : path) grow(float(p.x()), float(p.y()), float(p.z()));
    char title[96];
    std::snprintf(title, sizeof title, "gseg traversability map, %.2f m voxels", resolution);
    gseg::mrpt::addLegendAndCamera(
        scene, title,
        {{colours[1], "traversable: ground voxels (" + std::to_string(ground) + ")"},
         {colours[0], "obstacle voxels (" + std::to_string(labels.size() - ground) + ")"},
         {Rgb{40, 120, 255}, "driven path: a box at each sensor position (" + std::to_string(path.size()) + ")"},
         {Rgb{200, 200, 200}, "axes at the start: x red, y green, z up blue, 2 m"}},
        lo, hi);
    gseg::mrpt::writeGzipObject(file, scene);
}

}  // namespace gseg::map::detail
