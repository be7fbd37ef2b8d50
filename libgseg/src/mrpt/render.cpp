#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/render.hpp>

#include <mrpt/img/CImage.h>

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace gseg::mrpt {
namespace {

void putBigEndian(std::string& out, std::uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out += char((v >> shift) & 0xff);
}

void putChunk(std::string& out, const char* type, const std::string& data) {
    putBigEndian(out, std::uint32_t(data.size()));
    const std::size_t start = out.size();
    out += type;
    out += data;
    putBigEndian(out, std::uint32_t(crc32(0, reinterpret_cast<const Bytef*>(out.data() + start), uInt(out.size() - start))));
}

double fitRange(const PointCloudView& cloud) {
    std::vector<float> r;
    r.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (const float d = std::hypot(cloud.x(i), cloud.y(i)); std::isfinite(d)) r.push_back(d);
    if (r.empty()) return 10.0;
    const std::size_t k = std::min(r.size() - 1, std::size_t(0.98 * double(r.size())));
    std::nth_element(r.begin(), r.begin() + long(k), r.end());
    return std::clamp(double(r[k]) * 1.05, 5.0, 80.0);
}

}  // namespace

std::string encodePng(const ::mrpt::img::CImage& image) {
    const std::size_t w = image.getWidth(), h = image.getHeight();
    const bool colour = image.isColor();
    if (w == 0 || h == 0 || image.getPixelDepth() != ::mrpt::img::PixelDepth::D8U)
        throw std::invalid_argument("encodePng: needs a non-empty 8-bit image");
    const bool bgr = colour && image.getChannelsOrder() == "BGR";
    const std::size_t channels = colour ? 3 : 1;
    // Rows, each led by filter type 0 (none), RGB or grey.
    std::string raw;
    raw.reserve(h * (1 + w * channels));
    for (std::size_t y = 0; y < h; ++y) {
        raw += '\0';
        const std::uint8_t* line = image.ptrLine<std::uint8_t>(unsigned(y));
        for (std::size_t x = 0; x < w; ++x, line += channels) {
            if (!colour) raw += char(line[0]);
            else if (bgr) raw += {char(line[2]), char(line[1]), char(line[0])};
            else raw += {char(line[0]), char(line[1]), char(line[2])};
        }
    }
    uLongf packedSize = compressBound(uLong(raw.size()));
    std::string packed(packedSize, '\0');
    if (compress2(reinterpret_cast<Bytef*>(packed.data()), &packedSize, reinterpret_cast<const Bytef*>(raw.data()),
                  uLong(raw.size()), 6) != Z_OK)
        throw std::runtime_error("encodePng: compression failed");
    packed.resize(packedSize);
    std::string header;
    putBigEndian(header, std::uint32_t(w));
    putBigEndian(header, std::uint32_t(h));
    header += {char(8), char(colour ? 2 : 0), char(0), char(0), char(0)};  // 8 bit, RGB/grey, deflate, no interlace
    std::string png("\x89PNG\r\n\x1a\n", 8);
    putChunk(png, "IHDR", header);
    putChunk(png, "IDAT", packed);
    putChunk(png, "IEND", "");
    return png;
}

void writePng(const std::string& path, const ::mrpt::img::CImage& image) {
    const std::string png = encodePng(image);
    gseg::io::writeFileAtomic(path, png.data(), png.size());
}

void writeTopDownPng(const std::string& path, const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                     const RenderOptions& options) {
    const std::string png = topDownPng(cloud, labels, options);
    gseg::io::writeFileAtomic(path, png.data(), png.size());
}

std::string topDownPng(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels, const RenderOptions& opt) {
    if (labels.size() != cloud.size())
        throw std::invalid_argument("topDownPng: " + std::to_string(labels.size()) + " labels for " +
                                    std::to_string(cloud.size()) + " points");
    const int size = std::max(100, opt.sizePx);
    const double range = opt.rangeM > 0 ? opt.rangeM : fitRange(cloud);
    const double scale = 0.5 * size / range;  // px per metre
    const int c = size / 2;
    ::mrpt::img::CImage img(size, size, ::mrpt::img::CH_RGB);
    img.filledRectangle(0, 0, size - 1, size - 1, ::mrpt::img::TColor(20, 20, 28));
    for (double ring = opt.ringStepM; opt.ringStepM >= range / 100 && ring <= range * 1.5; ring += opt.ringStepM)
        img.drawCircle(c, c, int(ring * scale), ::mrpt::img::TColor(70, 70, 80));

    std::size_t ground = 0;
    auto draw = [&](std::uint8_t label, const ::mrpt::img::TColor& colour) {
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (labels[i] != label) continue;
            const double u = c - std::round(cloud.y(i) * scale);  // y (left) to the left
            const double v = c - std::round(cloud.x(i) * scale);  // x (forward) up
            if (!(u >= 0 && v >= 0 && u < size - 1 && v < size - 1)) continue;  // also NaN
            img.filledRectangle(int(u), int(v), int(u) + 1, int(v) + 1, colour);
        }
    };
    for (std::uint8_t l : labels) ground += l;
    draw(1, ::mrpt::img::TColor(40, 200, 60));
    draw(0, ::mrpt::img::TColor(235, 60, 40));
    img.line(c - 6, c, c + 6, c, ::mrpt::img::TColor(255, 255, 255), 2);
    img.line(c, c - 6, c, c + 6, ::mrpt::img::TColor(255, 255, 255), 2);

    char legend[160];
    std::snprintf(legend, sizeof legend, "ground %zu (green)  non-ground %zu (red)  circles every %.0f m",
                  ground, cloud.size() - ground, opt.ringStepM);
    if (!opt.title.empty()) img.textOut(8, 8, opt.title, ::mrpt::img::TColor(230, 230, 230));
    img.textOut(8, size - 20, legend, ::mrpt::img::TColor(230, 230, 230));

    return encodePng(img);
}

}  // namespace gseg::mrpt
