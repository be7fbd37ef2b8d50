#include <gseg/mrpt/gzip_stream.hpp>
#include <gseg/mrpt/render.hpp>
#include <gseg/mrpt/scene.hpp>

#include <mrpt/io/CStream.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/COpenGLViewport.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CText.h>
#include <mrpt/opengl/stock_objects.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace gseg::mrpt {

std::string sceneFileBytes(const ::mrpt::opengl::COpenGLScene& scene) {
    std::string bytes;
    GzipOutputStream gz([&bytes](const void* d, std::size_t n) { bytes.append(static_cast<const char*>(d), n); }, "scene");
    ::mrpt::serialization::archiveFrom(gz) << scene;
    gz.finish();
    return bytes;
}

void addLegendAndCamera(::mrpt::opengl::COpenGLScene& scene, const std::string& title,
                        const std::vector<SceneLegendLine>& legend, const float lo[3], const float hi[3]) {
    namespace gl = ::mrpt::opengl;
    // The main camera: pointing at the box centre, far enough for the box's bounding sphere to
    // fit the vertical field of view with a margin (a wide window shows more sideways).
    float centre[3], radius = 0;
    for (int a = 0; a < 3; ++a) {
        centre[a] = 0.5f * (lo[a] + hi[a]);
        radius += 0.25f * (hi[a] - lo[a]) * (hi[a] - lo[a]);
    }
    radius = std::max(1.0f, std::sqrt(radius));
    gl::CCamera& cam = scene.getViewport("main")->getCamera();
    constexpr float kFovDeg = 30.f;  // CCamera's default projective field of view
    cam.setProjectiveFOVdeg(kFovDeg);
    cam.setPointingAt(centre[0], centre[1], centre[2]);
    cam.setZoomDistance(0.85f * radius / std::sin(0.5f * kFovDeg * 3.14159265f / 180.f));
    cam.setAzimuthDegrees(-135.f);
    cam.setElevationDegrees(50.f);
    scene.enableFollowCamera(true);

    // The legend: its own viewport at the bottom left, sized in pixels to its text (lines of
    // kLinePx, about kCharPx a character of the 16 px font) whatever the window's size, dark so
    // that every class colour reads on it; a fixed camera looking down at text lines one unit
    // apart, scaled so that a unit is kLinePx pixels.
    std::vector<SceneLegendLine> lines;
    lines.push_back({Colour{255, 255, 255}, title});
    lines.insert(lines.end(), legend.begin(), legend.end());
    std::size_t chars = 0;
    for (const auto& l : lines) chars = std::max(chars, l.text.size());
    const double widthPx = kSceneLegendCharPx * double(chars) + 2 * kSceneLegendPadPx;
    const double heightPx = kSceneLegendLinePx * double(lines.size()) + kSceneLegendPadPx;
    auto view = scene.createViewport("legend");
    view->setViewportPosition(0.0, 0.0, widthPx, heightPx);
    view->setTransparent(false);
    view->setCustomBackgroundColor(::mrpt::img::TColorf(0.08f, 0.08f, 0.1f));
    view->setBorderSize(1);
    gl::CCamera& fixed = view->getCamera();
    fixed.setProjectiveFOVdeg(kFovDeg);
    const double unitsHigh = heightPx / kSceneLegendLinePx, unitsWide = widthPx / kSceneLegendLinePx;
    fixed.setPointingAt(float(0.5 * unitsWide), float(-0.5 * unitsHigh), 0.f);
    fixed.setAzimuthDegrees(-90.f);
    fixed.setElevationDegrees(89.f);  // straight down leaves the view's up direction undefined
    fixed.setZoomDistance(float(unitsHigh / (2 * std::tan(0.5 * kFovDeg * 3.14159265 / 180))));  // the view spans unitsHigh
    const double pad = kSceneLegendPadPx / kSceneLegendLinePx;
    for (std::size_t i = 0; i < lines.size(); ++i) {
        auto text = gl::CText::Create(lines[i].text);
        text->setName("legend: " + lines[i].text);
        text->setFont("sans", 16);
        text->setColor_u8(lines[i].colour.r, lines[i].colour.g, lines[i].colour.b);
        text->setLocation(pad, -double(i + 1) + 0.2, 0.0);
        view->insert(text);
    }
}

std::string scanSceneBytes(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels, const std::string& title) {
    if (labels.size() != cloud.size())
        throw std::invalid_argument("scanSceneBytes: " + std::to_string(labels.size()) + " labels for " +
                                    std::to_string(cloud.size()) + " points");
    auto points = ::mrpt::opengl::CPointCloudColoured::Create();
    points->setName("gseg: ground green, non-ground red");
    points->setPointSize(2.0f);
    points->reserve(cloud.size());
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};  // the sensor (the axes) is in the box too
    std::size_t ground = 0, nonGround = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!std::isfinite(cloud.x(i)) || !std::isfinite(cloud.y(i)) || !std::isfinite(cloud.z(i))) continue;
        const Colour c = labels[i] ? kGroundColour : kNonGroundColour;
        points->insertPoint({cloud.x(i), cloud.y(i), cloud.z(i), c.r, c.g, c.b, 255});
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], cloud.point(i)[a]), hi[a] = std::max(hi[a], cloud.point(i)[a]);
        (labels[i] ? ground : nonGround) += 1;
    }
    ::mrpt::opengl::COpenGLScene scene;
    scene.insert(points);
    auto axes = ::mrpt::opengl::stock_objects::CornerXYZ(1.0f);
    axes->setName("sensor: x forward (red), y left (green), z up (blue)");
    scene.insert(axes);
    addLegendAndCamera(scene, title,
                       {{kGroundColour, "ground: " + std::to_string(ground) + " points"},
                        {kNonGroundColour, "non-ground: " + std::to_string(nonGround) + " points"},
                        {Colour{200, 200, 200}, "axes at the sensor: x forward red, y left green, z up blue, 1 m"}},
                       lo, hi);
    return sceneFileBytes(scene);
}

}  // namespace gseg::mrpt
