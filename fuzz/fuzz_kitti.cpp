// libFuzzer target: the KITTI .bin and .label readers on arbitrary bytes. Contract: a scan of
// size/16 points, or std::runtime_error; nothing else escapes.
#include "fuzz_input.hpp"

#include <gseg/io/kitti.hpp>

#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    try {
        const std::vector<float> pts = gseg::io::parseKittiBin(data, size, "fuzz.bin");
        GSEG_FUZZ_CHECK(pts.size() * sizeof(float) == size && size % 16 == 0 && size > 0);
        GSEG_FUZZ_CHECK(std::memcmp(pts.data(), data, size) == 0);
    } catch (const std::runtime_error&) {
        GSEG_FUZZ_CHECK(size == 0 || size % 16 != 0);
    }
    const std::size_t expected = size > 0 ? data[0] : SIZE_MAX;
    try {
        const auto labels = gseg::io::parseKittiLabels(data, size, "fuzz.label", expected);
        GSEG_FUZZ_CHECK((expected == SIZE_MAX || labels.size() == expected) && labels.size() * 4 == size);
    } catch (const std::runtime_error&) {
    }
    return 0;
}
