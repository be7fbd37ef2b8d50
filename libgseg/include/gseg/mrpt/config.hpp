#pragma once
/// \file config.hpp
/// gseg parameters from YAML or MRPT INI files. The keys are the field names of gseg::Params
/// (documented in <gseg/params.hpp>); both formats go through Params::set(), so they accept the
/// same keys and values.

#include <gseg/params.hpp>

#include <string>

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

/// Reads a YAML (`.yaml`, `.yml`) or INI (`.ini`, `.cfg`, section `[gseg]`) file. In YAML the keys
/// may sit at the top level or under a top-level `gseg:` map. Throws std::runtime_error naming
/// the file and the key on a missing/unreadable file, an unknown key, or an invalid value.
LoadedConfig loadConfig(const std::string& path);

/// From an already parsed YAML map (keys at its top level). `where` names the source in errors.
LoadedConfig loadConfigFromYaml(const ::mrpt::containers::yaml& map, const std::string& where = "YAML");

/// From the section `section` of an MRPT INI configuration.
LoadedConfig loadConfigFromIni(const ::mrpt::config::CConfigFileBase& ini, const std::string& section = "gseg",
                               const std::string& where = "INI");

/// The configuration as YAML text (every key, with `auto` for an automatic distToGround).
std::string toYaml(const LoadedConfig& config);

}  // namespace gseg::mrpt
