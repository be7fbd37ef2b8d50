#include <gseg/mrpt/config.hpp>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/containers/yaml.h>

#include <algorithm>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace gseg::mrpt {
namespace {

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

bool endsWith(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Applies one key = value pair; the single place both formats go through.
void apply(LoadedConfig& cfg, const std::string& key, const std::string& value, const std::string& where) {
    try {
        if (key == "distToGround" && lower(value) == "auto") {
            cfg.distToGroundAuto = true;
            return;
        }
        if (key == "distToGround") cfg.distToGroundAuto = false;
        cfg.params.set(key, value);
    } catch (const std::exception& e) {
        throw std::runtime_error(where + ": " + e.what());
    }
}

void finish(LoadedConfig& cfg, const std::string& where) {
    try {
        cfg.params.validate();
    } catch (const std::exception& e) {
        throw std::runtime_error(where + ": " + e.what());
    }
}

}  // namespace

LoadedConfig loadConfigFromYaml(const ::mrpt::containers::yaml& root, const std::string& where) {
    LoadedConfig cfg;
    if (root.isNullNode()) {
        finish(cfg, where);
        return cfg;
    }
    if (!root.isMap()) throw std::runtime_error(where + ": expected a map of 'key: value' lines");
    const ::mrpt::containers::yaml::map_t* map = &root.asMap();
    const auto nested = map->find(::mrpt::containers::yaml::node_t(std::string("gseg")));
    if (nested != map->end() && nested->second.isMap()) map = &nested->second.asMap();
    for (const auto& [k, v] : *map) {
        const std::string key = k.as<std::string>();
        if (!v.isScalar()) throw std::runtime_error(where + ": parameter '" + key + "' must be a single value");
        apply(cfg, key, v.as<std::string>(), where);
    }
    finish(cfg, where);
    return cfg;
}

LoadedConfig loadConfigFromIni(const ::mrpt::config::CConfigFileBase& ini, const std::string& section,
                               const std::string& where) {
    LoadedConfig cfg;
    std::vector<std::string> keys;
    ini.getAllKeys(section, keys);
    for (const std::string& key : keys) {
        std::string value = ini.read_string(section, key, "", true);
        value = value.substr(0, value.find_first_of(";#"));  // inline comment
        value.erase(value.find_last_not_of(" \t") + 1);
        apply(cfg, key, value, where);
    }
    finish(cfg, where);
    return cfg;
}

LoadedConfig loadConfig(const std::string& path) {
    if (!std::ifstream(path)) throw std::runtime_error(path + ": cannot open the configuration file");
    const std::string ext = lower(path);
    if (endsWith(ext, ".yaml") || endsWith(ext, ".yml")) {
        ::mrpt::containers::yaml doc;
        try {
            doc = ::mrpt::containers::yaml::FromFile(path);
        } catch (const std::exception& e) {
            std::string what = e.what();
            what = what.substr(0, what.find('\n'));
            throw std::runtime_error(path + ": not valid YAML (" + what + ")");
        }
        return loadConfigFromYaml(doc, path);
    }
    if (endsWith(ext, ".ini") || endsWith(ext, ".cfg")) {
        const ::mrpt::config::CConfigFile ini(path);
        if (!ini.sectionExists("gseg")) throw std::runtime_error(path + ": no [gseg] section");
        return loadConfigFromIni(ini, "gseg", path);
    }
    throw std::runtime_error(path + ": unknown configuration format (use .yaml/.yml or .ini/.cfg)");
}

std::string toYaml(const LoadedConfig& config) {
    std::string out;
    for (const std::string& key : gseg::Params::keys())
        out += key + ": " + (key == "distToGround" && config.distToGroundAuto ? "auto" : config.params.get(key)) + "\n";
    return out;
}

}  // namespace gseg::mrpt
