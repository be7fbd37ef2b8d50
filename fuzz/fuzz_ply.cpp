// libFuzzer target: the PLY reader on arbitrary bytes. Contract: 4 floats per vertex, or
// std::runtime_error; memory bounded by the input (libFuzzer's -rss_limit_mb / -malloc_limit_mb
// catch a header that makes it allocate more). A cloud that reads back is written with
// labelledPlyBytes() and must read back identically.
#include "fuzz_input.hpp"

#include <gseg/io/ply.hpp>

#include <stdexcept>

namespace {

bool same(float a, float b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::vector<float> pts;
    try {
        pts = gseg::io::parsePly(data, size, "fuzz.ply");
    } catch (const std::runtime_error&) {
        return 0;
    }
    GSEG_FUZZ_CHECK(pts.size() % 4 == 0);
    GSEG_FUZZ_CHECK(pts.size() / 4 <= size);  // at least a byte per vertex
    const std::size_t n = pts.size() / 4;
    const std::vector<std::uint8_t> labels(n, 1);
    const std::string again = gseg::io::labelledPlyBytes(gseg::PointCloudView(pts.data(), n, 16), labels);
    const std::vector<float> back =
        gseg::io::parsePly(reinterpret_cast<const std::uint8_t*>(again.data()), again.size(), "roundtrip.ply");
    GSEG_FUZZ_CHECK(back.size() == pts.size());
    for (std::size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) GSEG_FUZZ_CHECK(same(back[4 * i + a], pts[4 * i + a]));
    return 0;
}
