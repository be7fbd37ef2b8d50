#include <gseg/mrpt/gzip_stream.hpp>
#include <gseg/mrpt/render.hpp>
#include <gseg/mrpt/scene.hpp>

#include <mrpt/io/CStream.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/stock_objects.h>
#include <mrpt/serialization/CArchive.h>

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

std::string scanSceneBytes(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels) {
    if (labels.size() != cloud.size())
        throw std::invalid_argument("scanSceneBytes: " + std::to_string(labels.size()) + " labels for " +
                                    std::to_string(cloud.size()) + " points");
    auto points = ::mrpt::opengl::CPointCloudColoured::Create();
    points->setName("gseg: ground green, non-ground red");
    points->setPointSize(2.0f);
    points->reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!std::isfinite(cloud.x(i)) || !std::isfinite(cloud.y(i)) || !std::isfinite(cloud.z(i))) continue;
        const Colour c = labels[i] ? kGroundColour : kNonGroundColour;
        points->insertPoint({cloud.x(i), cloud.y(i), cloud.z(i), c.r, c.g, c.b, 255});
    }
    ::mrpt::opengl::COpenGLScene scene;
    scene.insert(points);
    auto axes = ::mrpt::opengl::stock_objects::CornerXYZ(1.0f);
    axes->setName("sensor: x forward (red), y left (green), z up (blue)");
    scene.insert(axes);
    return sceneFileBytes(scene);
}

}  // namespace gseg::mrpt
