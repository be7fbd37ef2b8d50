// libFuzzer target: the configuration loader (YAML subset and MRPT INI) on arbitrary text.
// Contract: a validated configuration within configLimits(), or std::runtime_error; never a hang
// (libFuzzer's -timeout). A loaded configuration written with toYaml() loads back identically.
#include "fuzz_input.hpp"

#include <gseg/mrpt/config.hpp>

#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const auto format = data[0] & 1 ? gseg::mrpt::ConfigFormat::Ini : gseg::mrpt::ConfigFormat::Yaml;
    const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
    gseg::mrpt::LoadedConfig cfg;
    try {
        cfg = gseg::mrpt::loadConfigFromText(text, format, "fuzz");
    } catch (const std::runtime_error&) {
        return 0;
    }
    cfg.params.validate();  // throws (and the fuzzer reports it) if the loader let something through
    const gseg::mrpt::LoadedConfig back =
        gseg::mrpt::loadConfigFromText(gseg::mrpt::toYaml(cfg), gseg::mrpt::ConfigFormat::Yaml, "roundtrip");
    GSEG_FUZZ_CHECK(back.distToGroundAuto == cfg.distToGroundAuto);
    for (const std::string& key : gseg::Params::keys()) GSEG_FUZZ_CHECK(back.params.get(key) == cfg.params.get(key));
    return 0;
}
