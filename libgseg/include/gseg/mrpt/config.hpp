#pragma once
/// \file config.hpp
/// gseg parameters from YAML or MRPT INI files. The keys are the field names of gseg::Params
/// (documented in <gseg/params.hpp>); both formats go through Params::set(), so they accept the
/// same keys and values.

#include <gseg/params.hpp>

#include <string>
#include <vector>

namespace mrpt::containers {
class yaml;
}
namespace mrpt::config {
class CConfigFileBase;
}

namespace gseg::mrpt {

/// Parameters read from a file, plus what Params cannot hold.
struct LoadedConfig {
    gseg::Params params;            ///< every key not given keeps its default; validated
    bool distToGroundAuto = false;  ///< the file said `distToGround: auto` (estimate it per scan)
};

/// Reads a YAML (`.yaml`, `.yml`) or INI (`.ini`, `.cfg`, section `[gseg]`) file. Throws
/// std::runtime_error (only that type) naming the file, and the line or key, on a missing or
/// unreadable file, a file with a NUL byte or over 1 MiB, an unknown or repeated key, an invalid
/// value, or a value beyond configLimits().
///
/// YAML: gseg reads flat files itself (no YAML library sees them): `key: value` lines, `#`
/// comments, blank lines, an optional leading `---`, and either every key at the top level or
/// every key indented under one top-level `gseg:` (then nothing beside it). Values are plain or
/// quoted scalars. Anything else (directives, flow collections, anchors, nested maps) is refused.
/// INI: MRPT's CConfigFile syntax and preprocessor (`@define`, `${VAR}`, `$eval{}`, `$env{}`), except
/// loops in `$eval{}` and self-expanding environment variables, which could run forever.
LoadedConfig loadConfig(const std::string& path);

/// The two configuration formats.
enum class ConfigFormat { Yaml, Ini };

/// The same as loadConfig() for a file's text; `where` names it in messages.
LoadedConfig loadConfigFromText(const std::string& text, ConfigFormat format, const std::string& where);

/// A bound the loader adds to gseg::Params::validate(): valid values beyond it would make one scan
/// run for hours (e.g. ransacMaxIterations 2147483647 with minGroundInlierRatio 0).
struct ConfigLimit {
    const char* key;
    double min, max;
    const char* why;
};
const std::vector<ConfigLimit>& configLimits();

/// From an already parsed YAML map (keys at its top level, or all under a `gseg:` map). `where`
/// names the source in errors.
LoadedConfig loadConfigFromYaml(const ::mrpt::containers::yaml& map, const std::string& where = "YAML");

/// From the section `section` of an MRPT INI configuration.
LoadedConfig loadConfigFromIni(const ::mrpt::config::CConfigFileBase& ini, const std::string& section = "gseg",
                               const std::string& where = "INI");

/// The configuration as YAML text (every key, with `auto` for an automatic distToGround).
std::string toYaml(const LoadedConfig& config);

}  // namespace gseg::mrpt
