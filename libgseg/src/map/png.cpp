#include "png.hpp"

#include <zlib.h>

#include <stdexcept>
#include <vector>

namespace gseg::map::detail {
namespace {

void putBigEndian32(std::string& out, std::uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(char(std::uint8_t(v >> shift)));
}

/// Appends a chunk: length, type, data, CRC of type + data.
void putChunk(std::string& out, const char* type, const std::string& data) {
    putBigEndian32(out, std::uint32_t(data.size()));
    const std::size_t typeAt = out.size();
    out.append(type, 4);
    out += data;
    const auto* crcFrom = reinterpret_cast<const Bytef*>(out.data() + typeAt);
    putBigEndian32(out, std::uint32_t(crc32(crc32(0L, Z_NULL, 0), crcFrom, uInt(4 + data.size()))));
}

/// zlib stream of the rows (filter type 0 before each row).
std::string deflateRows(int width, int height, const std::function<void(int, std::uint8_t*)>& fillRow) {
    z_stream z{};
    if (deflateInit(&z, 6) != Z_OK) throw std::runtime_error("PNG: zlib initialisation failed");
    std::vector<std::uint8_t> row(1 + 3 * std::size_t(width));
    std::string out;
    std::vector<std::uint8_t> buf(1 << 16);
    auto pump = [&](int flush) {
        int rc = Z_OK;
        do {
            z.next_out = buf.data();
            z.avail_out = uInt(buf.size());
            rc = deflate(&z, flush);
            out.append(reinterpret_cast<const char*>(buf.data()), buf.size() - z.avail_out);
        } while (z.avail_out == 0 && rc != Z_STREAM_END);
        return rc;
    };
    for (int r = 0; r < height; ++r) {
        row[0] = 0;
        fillRow(r, row.data() + 1);
        z.next_in = row.data();
        z.avail_in = uInt(row.size());
        pump(Z_NO_FLUSH);
    }
    const int rc = pump(Z_FINISH);
    deflateEnd(&z);
    if (rc != Z_STREAM_END) throw std::runtime_error("PNG: zlib compression failed");
    return out;
}

}  // namespace

std::string encodePngRgb(int width, int height, const std::function<void(int, std::uint8_t*)>& fillRow) {
    if (width <= 0 || height <= 0) throw std::invalid_argument("PNG: empty picture");
    std::string png("\x89PNG\r\n\x1a\n", 8);
    std::string header;
    putBigEndian32(header, std::uint32_t(width));
    putBigEndian32(header, std::uint32_t(height));
    header += std::string("\x08\x02\x00\x00\x00", 5);  // 8-bit RGB, deflate, filter 0, no interlace
    putChunk(png, "IHDR", header);
    putChunk(png, "IDAT", deflateRows(width, height, fillRow));
    putChunk(png, "IEND", "");
    return png;
}

}  // namespace gseg::map::detail
