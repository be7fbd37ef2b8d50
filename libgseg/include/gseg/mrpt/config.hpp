#pragma once
/// \file config.hpp
/// gseg's options from YAML or MRPT INI files: gseg::Params (<gseg/params.hpp>), the
/// `distToGround: auto` estimator's gseg::SensorHeightOptions (<gseg/sensor_height.hpp>) and the
/// maps' gseg::map::TraversabilityOptions (<gseg/traversability_options.hpp>). The keys are the
/// field names; every format goes through each struct's key table (set()), and every route
/// refuses an unknown or repeated key the same way.

#include <gseg/params.hpp>
#include <gseg/sensor_height.hpp>
#include <gseg/traversability_options.hpp>

#include <string>
#include <vector>

namespace mrpt::containers {
class yaml;
}
namespace mrpt::config {
class CConfigFileBase;
}

namespace gseg::mrpt {

/// Parameters read from a file, plus what Params cannot hold. A value-initialised LoadedConfig
/// holds the library defaults with the fixed distToGround of gseg::Params (KITTI's 1.723 m); what
/// the loaders start from is defaultConfig().
struct LoadedConfig {
    gseg::Params params;            ///< every key not given keeps its default; validated
    bool distToGroundAuto = false;  ///< estimate the sensor height per scan (`distToGround: auto`)
    gseg::SensorHeightOptions sensorHeight;           ///< YAML `sensorHeight:`, INI `[sensorHeight]`; validated
    gseg::map::TraversabilityOptions traversability;  ///< YAML `traversability:`, INI `[traversability]`; validated
    /// What the loader read but ignores, one line each naming where and why (a retired key, see
    /// retiredKeys()). Not errors: every tool prints each once as "<tool>: warning: <line>", the
    /// map plugin on stderr, Python as warnings.warn().
    std::vector<std::string> warnings;
};

/// A key gseg read once and now ignores: a file (or a Python call) that still sets it loads, with
/// a warning in LoadedConfig::warnings, so that old configurations keep working.
struct RetiredKey {
    const char* key;  ///< as in gseg::Params' table (the `gseg:` keys)
    const char* why;  ///< why it is ignored, and what to use instead
};
const std::vector<RetiredKey>& retiredKeys();

/// The configuration where no file sets a key: the library defaults (gseg::Params, the values of
/// config/kitti_hdl64.yaml) with `distToGround: auto`, so that a tool or the map plugin run
/// without a file, or with one that does not set distToGround, estimates the sensor height per
/// scan and gives sensible ground on any sensor at any height (Params::distToGround, 1.723 m, is
/// then the fallback for a scan without an estimate). A file that sets `distToGround` to a number
/// fixes the height (config/kitti_hdl64.yaml does); a fixed height the scan contradicts is
/// warned about by the segmenter. Every loader below starts from this.
LoadedConfig defaultConfig();

/// loadConfig(path), or defaultConfig() when `path` is empty (a tool run without `-c`).
LoadedConfig loadConfigOrDefault(const std::string& path);

/// Reads a YAML (`.yaml`, `.yml`) or INI (`.ini`, `.cfg`, section `[gseg]`) file. Throws
/// std::runtime_error (only that type) naming the file, and the line or key, on a missing or
/// unreadable file, a file with a NUL byte or over 1 MiB, an unknown or repeated key, an invalid
/// value, or a value beyond configLimits().
///
/// YAML: gseg reads flat files itself (no YAML library sees them): `key: value` lines, `#`
/// comments, blank lines, an optional leading `---`. The gseg::Params keys either all at the top
/// level or all indented under one top-level `gseg:` (then no parameter beside it); beside them,
/// at most one `sensorHeight:` and one `traversability:` map, their keys indented under them.
/// Values are plain or quoted scalars. Anything else (directives, flow collections, anchors, other
/// nested maps) is refused.
/// INI: sections `[gseg]` (required), `[sensorHeight]` and `[traversability]` (optional), no other;
/// MRPT's CConfigFile syntax and preprocessor (`@define`, `${VAR}`, `$eval{}`, `$env{}`), except
/// loops in `$eval{}` and self-expanding environment variables, which could run forever. A key
/// given twice in a section is refused (MRPT itself would keep the last silently).
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

/// The INI sections that hold each options struct (an absent section leaves its defaults).
struct IniSections {
    std::string params = "gseg";
    std::string sensorHeight = "sensorHeight";
    std::string traversability = "traversability";
};

/// From the sections `sections` of an MRPT INI configuration (the plugin: `<prefix>_gseg`,
/// `<prefix>_sensorHeight`, `<prefix>_creationOpts`). Unknown keys are refused; repeated keys too
/// where the text can be read again (a CConfigFile's file: MRPT itself keeps the last silently, and
/// a CConfigFileMemory holds them merged already), and messages then name the line. `where` names
/// the source (the file when none is given).
LoadedConfig loadConfigFromIni(const ::mrpt::config::CConfigFileBase& ini, const IniSections& sections = IniSections(),
                               const std::string& where = "");

/// The configuration as YAML text (every key, with `auto` for an automatic distToGround; the
/// sensorHeight and traversability options as maps with their unit and meaning in comments).
std::string toYaml(const LoadedConfig& config);

}  // namespace gseg::mrpt
