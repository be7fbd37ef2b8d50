// PNG output: the encoder of every gseg picture (zlib, no filter), and its checked file.
#include <gseg/mrpt/png.hpp>

#include <mrpt/img/CImage.h>

#include <zlib.h>

#include <cstdint>
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

}  // namespace gseg::mrpt
