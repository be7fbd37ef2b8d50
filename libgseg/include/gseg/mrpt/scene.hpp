#pragma once
/// \file scene.hpp
/// MRPT 3D scenes (`.3Dscene`, opened by SceneViewer3D from Debian's mrpt-apps): the route to look
/// at gseg's outputs in 3D on stock Debian (SceneViewer3D refuses PLY point clouds, and octovis
/// 1.9.7 shows a black view on bookworm).

#include <gseg/mrpt/picture.hpp>
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

/// One line of a scene's legend: its text, drawn in `colour` (the class colour it explains).
struct SceneLegendLine {
    Colour colour;
    std::string text;
};

/// What SceneViewer3D (mrpt-apps 2.5.8) shows at first open, for every `.3Dscene` gseg writes
/// (scans and maps): adds to `scene` a viewport named "legend" over the bottom-left corner of the
/// main view, sized in pixels to its text (kSceneLegendCharPx a character of its longest line,
/// kSceneLegendLinePx a line, whatever the window's size; dark, its own fixed camera, so it stays
/// readable whatever the user does with the main view) holding `title` in white and one line per
/// entry of `legend` in its colour (bitmap text, CText); and sets the main viewport's camera to frame the axis-aligned box
/// [lo, hi] (metres, the scene's frame: the content's bounding box) whole, seen from behind and
/// above (azimuth -135 deg, elevation 50 deg), with followCamera on, which SceneViewer3D reads
/// from the file instead of keeping its default close-up camera.
inline constexpr double kSceneLegendCharPx = 6.5; ///< [px] a character of the legend's 16 px font (measured in SceneViewer3D: 5.7 on average)
inline constexpr double kSceneLegendLinePx = 22;  ///< [px] a line of the legend
inline constexpr double kSceneLegendPadPx = 10;   ///< [px] around the legend's text
void addLegendAndCamera(::mrpt::opengl::COpenGLScene& scene, const std::string& title,
                        const std::vector<SceneLegendLine>& legend, const float lo[3], const float hi[3]);

/// A scene of a labelled scan in its sensor frame: ground points green, non-ground red (the
/// colours of the PLY and the PNG), x/y/z axes of 1 m at the sensor, the legend and the camera
/// framing every finite point (addLegendAndCamera()); `title` heads the legend. Throws
/// std::invalid_argument if the label count differs from the point count.
std::string scanSceneBytes(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                           const std::string& title = "gseg ground segmentation");

}  // namespace gseg::mrpt
