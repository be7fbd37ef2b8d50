#pragma once
/// \file scene.hpp
/// MRPT 3D scenes (`.3Dscene`, opened by SceneViewer3D from Debian's mrpt-apps): the route to look
/// at gseg's outputs in 3D on stock Debian (SceneViewer3D refuses PLY point clouds, and octovis
/// 1.9.7 shows a black view on bookworm).

#include <gseg/point_cloud.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace mrpt::opengl {
class COpenGLScene;
}

namespace gseg::mrpt {

/// The bytes of a `.3Dscene` file: the serialized scene, gzip-compressed, as
/// COpenGLScene::saveToFile() writes it (COpenGLScene::loadFromFile() reads it), but in memory so
/// that the caller writes it with checked writes. The same scene always gives the same bytes.
std::string sceneFileBytes(const ::mrpt::opengl::COpenGLScene& scene);

/// A scene of a labelled scan in its sensor frame: ground points green, non-ground red (the
/// colours of the PLY and the PNG), and x/y/z axes of 1 m at the sensor. Throws
/// std::invalid_argument if the label count differs from the point count.
std::string scanSceneBytes(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels);

}  // namespace gseg::mrpt
