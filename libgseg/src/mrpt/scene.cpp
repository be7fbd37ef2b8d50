#include <gseg/mrpt/render.hpp>
#include <gseg/mrpt/scene.hpp>

#include <mrpt/io/CStream.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/stock_objects.h>
#include <mrpt/serialization/CArchive.h>

#include <zlib.h>

#include <cmath>
#include <stdexcept>

namespace gseg::mrpt {
namespace {

/// gzip of `data` (header without a time stamp: the same input gives the same bytes).
std::string gzip(const void* data, std::size_t size) {
    z_stream z{};
    if (deflateInit2(&z, 1, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK)
        throw std::runtime_error("gzip: zlib initialisation failed");
    std::string out(deflateBound(&z, uLong(size)), '\0');
    z.next_in = static_cast<Bytef*>(const_cast<void*>(data));
    z.avail_in = uInt(size);
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = uInt(out.size());
    const int rc = deflate(&z, Z_FINISH);
    out.resize(out.size() - z.avail_out);
    deflateEnd(&z);
    if (rc != Z_STREAM_END) throw std::runtime_error("gzip: zlib compression failed");
    return out;
}

/// An MRPT output stream into a string (CMemoryStream grows 4 KB at a time: slow for large maps).
class StringOutput : public ::mrpt::io::CStream {
public:
    std::string bytes;
    size_t Write(const void* buffer, size_t count) override {
        bytes.append(static_cast<const char*>(buffer), count);
        return count;
    }
    size_t Read(void*, size_t) override { throw std::logic_error("StringOutput: write-only"); }
    uint64_t Seek(int64_t, CStream::TSeekOrigin) override { throw std::logic_error("StringOutput: not seekable"); }
    uint64_t getTotalBytesCount() const override { return bytes.size(); }
    uint64_t getPosition() const override { return bytes.size(); }
};

}  // namespace

std::string sceneFileBytes(const ::mrpt::opengl::COpenGLScene& scene) {
    StringOutput buffer;
    ::mrpt::serialization::archiveFrom(buffer) << scene;
    return gzip(buffer.bytes.data(), buffer.bytes.size());
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
