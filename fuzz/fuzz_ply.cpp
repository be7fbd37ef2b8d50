// libFuzzer target: the PLY reader on arbitrary bytes. Contract: 4 floats per vertex, or
// std::runtime_error; memory bounded by the input (libFuzzer's -rss_limit_mb / -malloc_limit_mb
// catch a header that makes it allocate more). A cloud that reads back is written with
// labelledPlyBytes() (with intensity and labels) and must read back identically.
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
    std::vector<std::uint8_t> labels(n);
    for (std::size_t i = 0; i < n; ++i) labels[i] = std::uint8_t(i % 3 == 0);
    gseg::io::PlyOptions options;
    options.intensity = true;
    const std::string again = gseg::io::labelledPlyBytes(gseg::PointCloudView(pts.data(), n, 16), labels, {}, options);
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(again.data());
    const std::vector<float> back = gseg::io::parsePly(bytes, again.size(), "roundtrip.ply");
    GSEG_FUZZ_CHECK(back.size() == pts.size());
    for (std::size_t i = 0; i < 4 * n; ++i) GSEG_FUZZ_CHECK(same(back[i], pts[i]));
    const std::vector<double> backLabels = gseg::io::parsePlyProperty(bytes, again.size(), "roundtrip.ply", "label");
    GSEG_FUZZ_CHECK(backLabels.size() == n);
    for (std::size_t i = 0; i < n; ++i) GSEG_FUZZ_CHECK(backLabels[i] == labels[i]);
    return 0;
}
