#include <gseg/io/kitti.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/text.hpp>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/containers/yaml.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <map>
#include <stdexcept>
#include <vector>

namespace gseg::mrpt {
namespace {

// The options structs a configuration holds, by their YAML map and default INI section names.
enum class Section { Params, SensorHeight, Traversability };

struct SectionName {
    Section section;
    const char* name;
};
constexpr SectionName kSectionMaps[] = {
    {Section::Params, "gseg"}, {Section::SensorHeight, "sensorHeight"}, {Section::Traversability, "traversability"}};

const RetiredKey* retired(Section section, const std::string& key) {
    if (section != Section::Params) return nullptr;
    for (const RetiredKey& r : retiredKeys())
        if (key == r.key) return &r;
    return nullptr;
}

// Applies one key = value pair; the single place every format and route goes through.
void apply(LoadedConfig& cfg, Section section, const std::string& key, const std::string& value, const std::string& where) {
    if (const RetiredKey* r = retired(section, key)) {
        cfg.warnings.push_back(where + ": '" + key + "' is ignored: " + r->why);
        return;
    }
    try {
        if (section == Section::SensorHeight) return cfg.sensorHeight.set(key, value);
        if (section == Section::Traversability) return cfg.traversability.set(key, value);
        if (key == "distToGround" && lowercase(value) == "auto") {
            cfg.distToGroundAuto = true;
            return;
        }
        if (key == "distToGround") cfg.distToGroundAuto = false;
        cfg.params.set(key, value);
    } catch (const std::exception& e) {
        throw std::runtime_error(where + ": " + e.what());
    }
}

// Bounds the loader adds to Params::validate(): values that are valid but would make one scan run
// for hours (see configLimits()).
void checkLimits(const gseg::Params& p) {
    for (const ConfigLimit& l : configLimits()) {
        const double v = std::stod(p.get(l.key));
        if (v < l.min || v > l.max)
            throw std::invalid_argument("parameter '" + std::string(l.key) + "' = " + p.get(l.key) +
                                        " is outside what gseg runs in bounded time: " + l.why);
    }
}

void finish(LoadedConfig& cfg, const std::string& where) {
    try {
        cfg.params.validate();
        checkLimits(cfg.params);
        cfg.sensorHeight.validate();
        cfg.traversability.validate();
    } catch (const std::exception& e) {
        throw std::runtime_error(where + ": " + e.what());
    }
}

// --- The YAML subset of configuration files ---------------------------------------------------------
// `key: value` lines, comments, blank lines, an optional `---` first, and either every key at the
// top level or every key indented under one top-level `gseg:`. Everything else is refused with its
// line number, before any YAML library sees the text (libfyaml hangs on some `%` directives and
// accepts unclosed brackets, duplicate keys and text after a NUL byte with a warning on stderr).
struct YamlEntry {
    Section section = Section::Params;
    std::string key, value;
    int line = 0;
};

bool isKeyChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// Removes a comment (`#` at the start or after a blank, outside quotes) and trailing blanks.
std::string stripComment(const std::string& line) {
    char quote = 0;
    for (std::size_t i = 0; i < line.size(); ++i) {
        const char c = line[i];
        if (quote) {
            if (c == quote) quote = 0;
        } else if (c == '\'' || c == '"') {
            quote = c;
        } else if (c == '#' && (i == 0 || line[i - 1] == ' ' || line[i - 1] == '\t')) {
            return trim(line.substr(0, i)) == "" ? "" : line.substr(0, line.find_last_not_of(" \t", i - 1) + 1);
        }
    }
    return line.substr(0, line.find_last_not_of(" \t") + 1);
}

std::string yamlValue(std::string v, const std::string& where) {
    v = trim(v);
    if (v.empty()) throw std::runtime_error(where + ": the key has no value");
    if (v.front() == '\'' || v.front() == '"') {
        if (v.size() < 2 || v.back() != v.front() || v.find(v.front(), 1) != v.size() - 1)
            throw std::runtime_error(where + ": unbalanced quotes in " + v);
        return v.substr(1, v.size() - 2);
    }
    if (std::strchr("[]{}&*!|>%@`,?", v.front()) || (v.front() == '-' && (v.size() == 1 || v[1] == ' ')) ||
        v.find(": ") != std::string::npos)
        throw std::runtime_error(where + ": '" + v + "' is not a single plain value (gseg reads flat 'key: value' lines)");
    return v;
}

const SectionName* sectionMap(const std::string& key) {
    for (const SectionName& s : kSectionMaps)
        if (key == s.name) return &s;
    return nullptr;
}

std::vector<YamlEntry> parseFlatYaml(const std::string& text, const std::string& path) {
    std::vector<YamlEntry> entries;
    std::map<std::pair<Section, std::string>, int> seen;
    std::map<Section, int> mapLine;      // where each `name:` map starts
    const SectionName* open = nullptr;   // the map the indented lines belong to
    int topLevelLine = 0;                // the first top-level parameter
    std::size_t indent = 0;              // of the lines under `open` (0: none yet)
    bool contentSeen = false, ended = false;
    std::size_t pos = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;  // UTF-8 byte order mark
    for (int number = 1; pos <= text.size(); ++number) {
        std::size_t end = text.find('\n', pos);
        if (end == std::string::npos) end = text.size();
        std::string raw = text.substr(pos, end - pos);
        pos = end + 1;
        if (!raw.empty() && raw.back() == '\r') raw.pop_back();
        const std::string where = path + ":" + std::to_string(number);
        const std::string line = stripComment(raw);
        if (trim(line).empty()) continue;
        if (ended) throw std::runtime_error(where + ": text after the end of the document ('...')");
        if (line[0] == '%') throw std::runtime_error(where + ": YAML directives ('%...') are not supported");
        if (line == "---") {
            if (contentSeen) throw std::runtime_error(where + ": only one YAML document per file");
            contentSeen = true;
            continue;
        }
        if (line == "...") {
            ended = true;
            continue;
        }
        contentSeen = true;
        const std::size_t lead = line.find_first_not_of(' ');
        if (line[lead] == '\t') throw std::runtime_error(where + ": tabs are not allowed for indentation");
        std::size_t k = lead;
        while (k < line.size() && isKeyChar(line[k])) ++k;
        if (k == lead || k >= line.size() || line[k] != ':' || (k + 1 < line.size() && line[k + 1] != ' ' && line[k + 1] != '\t'))
            throw std::runtime_error(where + ": expected 'key: value', found '" + trim(line) + "'");
        const std::string key = line.substr(lead, k - lead), rest = line.substr(k + 1);
        if (lead == 0 && trim(rest).empty() && sectionMap(key)) {
            open = sectionMap(key), indent = 0;
            if (auto [it, fresh] = mapLine.emplace(open->section, number); !fresh)
                throw std::runtime_error(where + ": a second '" + key + ":' map (also on line " + std::to_string(it->second) + ")");
            continue;
        }
        Section section = Section::Params;
        if (lead > 0) {
            if (!open || (indent && lead != indent))
                throw std::runtime_error(where + ": unexpected indentation (only the keys under 'gseg:', 'sensorHeight:' or "
                                                 "'traversability:' are indented, each map's all by the same amount)");
            indent = lead;
            section = open->section;
        } else {
            open = nullptr;
            if (!topLevelLine) topLevelLine = number;
        }
        if (auto [it, fresh] = seen.emplace(std::pair{section, key}, number); !fresh)
            throw std::runtime_error(where + ": '" + key + "' given twice (also on line " + std::to_string(it->second) + ")");
        entries.push_back({section, key, yamlValue(rest, where + ": '" + key + "'"), number});
    }
    if (const auto g = mapLine.find(Section::Params); g != mapLine.end() && topLevelLine)
        throw std::runtime_error(path + ":" + std::to_string(topLevelLine) +
                                 ": a parameter beside the 'gseg:' map (line " + std::to_string(g->second) +
                                 "): put every parameter inside it, or drop 'gseg:'");
    return entries;
}

// --- INI ---------------------------------------------------------------------------------------------
// Calls f(number, line) for each line of an INI text (numbered from 1, without its '\n').
template <class F>
void forEachIniLine(const std::string& text, F&& f) {
    int number = 1;
    for (std::size_t pos = 0; pos < text.size(); ++number) {
        std::size_t end = text.find('\n', pos);
        if (end == std::string::npos) end = text.size();
        f(number, text.substr(pos, end - pos));
        pos = end + 1;
    }
}

// MRPT's INI preprocessor evaluates `$eval{...}` with exprtk, which has loops, and expands
// `$env{VAR}` repeatedly: `$eval{var x:=0; while(x<1e12)(x+=1); 1}` or a variable whose value holds
// `$env{...}` again would run forever. Both are refused before the preprocessor runs.
void refuseUnboundedIni(const std::string& text, const std::string& path) {
    forEachIniLine(text, [&](int number, const std::string& line) {
        const std::string where = path + ":" + std::to_string(number);
        if (line.find("$eval{") != std::string::npos || line.find("@define") != std::string::npos) {
            for (std::size_t i = 0; i < line.size();) {
                if (!std::isalpha(static_cast<unsigned char>(line[i]))) {
                    ++i;
                    continue;
                }
                std::size_t j = i;
                while (j < line.size() && isKeyChar(line[j])) ++j;
                const std::string word = lowercase(line.substr(i, j - i));
                if (word == "while" || word == "for" || word == "repeat" || word == "until")
                    throw std::runtime_error(where + ": '" + word + "' loops are not allowed in $eval{} (a configuration "
                                                     "must not be able to hang a tool)");
                i = j;
            }
        }
        for (std::size_t at = line.find("$env{"); at != std::string::npos; at = line.find("$env{", at + 1)) {
            const std::size_t close = line.find('}', at);
            if (close == std::string::npos) continue;  // MRPT reports it
            const char* value = std::getenv(line.substr(at + 5, close - at - 5).c_str());
            if (value && (std::strstr(value, "$env{") || std::strstr(value, "$eval{")))
                throw std::runtime_error(where + ": the environment variable " + line.substr(at + 5, close - at - 5) +
                                         " holds $env{} or $eval{} itself (it would expand forever)");
        }
    });
}


// One `key = value` line of an INI text.
struct IniKey {
    std::string section, key;  // as written
    int line = 0;
};

// The keys of every section of an INI text as written (MRPT's syntax: `[section]`, `key = value`,
// comments from `;`, `#` or `//`). MRPT's CConfigFile keeps the last of a repeated key without a
// word, so gseg reads the text once more to refuse one: the one INI scanner of both routes (the
// tools' files and the plugin's).
std::vector<IniKey> scanIniKeys(const std::string& text) {
    std::vector<IniKey> keys;
    std::string section;
    forEachIniLine(text, [&](int number, std::string t) {
        if (!t.empty() && t.back() == '\r') t.pop_back();
        t = trim(t);
        if (t.empty() || t[0] == ';' || t[0] == '#' || t.rfind("//", 0) == 0 || t[0] == '@') return;
        if (t[0] == '[') {
            const std::size_t close = t.find(']');
            if (close != std::string::npos) section = trim(t.substr(1, close - 1));
            return;
        }
        const std::size_t eq = t.find('=');
        if (eq == std::string::npos || eq == 0) return;  // MRPT's syntax, not ours to judge
        keys.push_back({section, trim(t.substr(0, eq)), number});
    });
    return keys;
}

// `[section]` of an INI read from `ini` (with its text, when known) into `section` of `cfg`.
void loadIniSection(LoadedConfig& cfg, const ::mrpt::config::CConfigFileBase& ini, Section section,
                    const std::string& name, const std::vector<IniKey>& scanned, const std::string& where) {
    std::map<std::string, int> lineOf;  // lower-case key -> line (MRPT's INI keys ignore case)
    for (const IniKey& k : scanned) {
        if (lowercase(k.section) != lowercase(name)) continue;
        if (auto [it, fresh] = lineOf.emplace(lowercase(k.key), k.line); !fresh)
            throw std::runtime_error(where + ":" + std::to_string(k.line) + ": [" + name + "] '" + k.key +
                                     "' given twice (also on line " + std::to_string(it->second) + ")");
    }
    if (!ini.sectionExists(name)) return;
    std::vector<std::string> keys;
    ini.getAllKeys(name, keys);
    for (const std::string& key : keys) {
        const auto line = lineOf.find(lowercase(key));
        const std::string at = where + (line == lineOf.end() ? "" : ":" + std::to_string(line->second)) + ": [" + name + "]";
        std::string value;
        try {
            value = ini.read_string(name, key, "", true);
        } catch (const std::exception& e) {
            throw std::runtime_error(at + " " + key + ": " + errorReason(e));
        }
        value = value.substr(0, value.find_first_of(";#"));  // inline comment
        value.erase(value.find_last_not_of(" \t") + 1);
        apply(cfg, section, key, value, at);
    }
}

LoadedConfig loadIni(const ::mrpt::config::CConfigFileBase& ini, const IniSections& names, const std::string& where,
                     const std::string* text) {
    LoadedConfig cfg = defaultConfig();
    const std::vector<IniKey> scanned = text ? scanIniKeys(*text) : std::vector<IniKey>();
    loadIniSection(cfg, ini, Section::Params, names.params, scanned, where);
    loadIniSection(cfg, ini, Section::SensorHeight, names.sensorHeight, scanned, where);
    loadIniSection(cfg, ini, Section::Traversability, names.traversability, scanned, where);
    finish(cfg, where);
    return cfg;
}

}  // namespace

const std::vector<RetiredKey>& retiredKeys() {
    static const std::vector<RetiredKey> keys = {
        {"threads", "one scan is no longer split over threads (it did not pay: 1 thread 6.68 ms, 2 threads 5.82 ms a "
                    "KITTI scan on 16 cores; the labels were the same); the tools' --threads segment several scans at once"},
    };
    return keys;
}

const std::vector<ConfigLimit>& configLimits() {
    static const std::vector<ConfigLimit> limits = {
        {"ransacMaxIterations", 1, 10000,
         "at most 10000 RANSAC iterations per cell (with minGroundInlierRatio 0 every planar cell runs them all)"},
        {"distToGround", -100, 100, "a sensor within 100 m of the ground"},
        {"robotRadius", 0, 100, "a seed disc of at most 100 m"},
        {"centroidSearchRadius", 0, 100, "expansion radius of at most 100 m (each search may return every cell)"},
        {"cellSizeX", 0.05, 100, "cells of 0.05 to 100 m across"},
        {"cellSizeY", 0.05, 100, "cells of 0.05 to 100 m across"},
        {"minPointsPerCell", 3, 1000000, "at most 10^6 points per cell"},
        {"minPointsForPca", 3, 1000000, "at most 10^6 points per cell"},
    };
    return limits;
}

LoadedConfig loadConfigFromYaml(const ::mrpt::containers::yaml& root, const std::string& where) {
    LoadedConfig cfg = defaultConfig();
    if (root.isNullNode()) {
        finish(cfg, where);
        return cfg;
    }
    if (!root.isMap()) throw std::runtime_error(where + ": expected a map of 'key: value' lines");
    const auto& top = root.asMap();
    const auto sectionOf = [](const std::string& key) {
        const SectionName* s = sectionMap(key);
        return s && s->section != Section::Params ? s : nullptr;
    };
    const ::mrpt::containers::yaml::map_t* params = &top;
    const auto nested = top.find(::mrpt::containers::yaml::node_t(std::string("gseg")));
    if (nested != top.end() && nested->second.isMap()) {
        for (const auto& [k, v] : top)
            if (k.as<std::string>() != "gseg" && !sectionOf(k.as<std::string>()))
                throw std::runtime_error(where + ": '" + k.as<std::string>() +
                                         "' beside the 'gseg:' map: put every parameter inside it, or drop 'gseg:'");
        params = &nested->second.asMap();
    }
    const auto applyMap = [&](const ::mrpt::containers::yaml::map_t& map, Section section) {
        const bool isTop = &map == &top;  // the top level also holds the maps, read on their own
        for (const auto& [k, v] : map) {
            const std::string key = k.as<std::string>();
            if (isTop && (key == "gseg" || sectionOf(key)) && v.isMap()) continue;
            if (!v.isScalar()) throw std::runtime_error(where + ": parameter '" + key + "' must be a single value");
            apply(cfg, section, key, v.as<std::string>(), where);
        }
    };
    applyMap(*params, Section::Params);
    for (const auto& [k, v] : top)
        if (const SectionName* s = sectionOf(k.as<std::string>()); s && v.isMap()) applyMap(v.asMap(), s->section);
    finish(cfg, where);
    return cfg;
}

LoadedConfig loadConfigFromIni(const ::mrpt::config::CConfigFileBase& ini, const IniSections& sections,
                               const std::string& where) {
    std::string text, name = where;
    bool haveText = false;
    if (const auto* file = dynamic_cast<const ::mrpt::config::CConfigFile*>(&ini)) {
        if (name.empty()) name = file->getAssociatedFile();
        try {
            const std::vector<std::uint8_t> bytes = gseg::io::readFileBytes(file->getAssociatedFile());
            text.assign(bytes.begin(), bytes.end()), haveText = true;
        } catch (const std::exception&) {  // MRPT read it: go on without the repeated-key check
        }
    }  // a CConfigFileMemory's content has repeated keys merged already: nothing to scan
    return loadIni(ini, sections, name.empty() ? "INI" : name, haveText ? &text : nullptr);
}

LoadedConfig loadConfigFromText(const std::string& text, ConfigFormat format, const std::string& where) {
    if (const std::size_t nul = text.find('\0'); nul != std::string::npos)
        throw std::runtime_error(where + ": a NUL byte at offset " + std::to_string(nul) +
                                 ": not a text configuration file");
    if (format == ConfigFormat::Yaml) {
        LoadedConfig cfg = defaultConfig();
        for (const YamlEntry& e : parseFlatYaml(text, where))
            apply(cfg, e.section, e.key, e.value, where + ":" + std::to_string(e.line));
        finish(cfg, where);
        return cfg;
    }
    refuseUnboundedIni(text, where);
    ::mrpt::config::CConfigFileMemory ini;
    try {
        ini.setContent(text);
    } catch (const std::exception& e) {  // the preprocessor's $eval{}, ${} and $env{} errors
        throw std::runtime_error(where + ": " + errorReason(e));
    }
    if (!ini.sectionExists("gseg")) throw std::runtime_error(where + ": no [gseg] section");
    std::vector<std::string> sections;
    ini.getAllSections(sections);
    for (const std::string& name : sections)
        if (std::none_of(std::begin(kSectionMaps), std::end(kSectionMaps), [&](const SectionName& s) { return name == s.name; }))
            throw std::runtime_error(where + ": unknown section [" + name + "] (gseg reads [gseg], [sensorHeight] and [traversability])");
    return loadIni(ini, IniSections(), where, &text);
}

LoadedConfig defaultConfig() {
    LoadedConfig cfg;
    cfg.distToGroundAuto = true;  // any sensor at any height; a file's number fixes it
    return cfg;
}

LoadedConfig loadConfigOrDefault(const std::string& path) { return path.empty() ? defaultConfig() : loadConfig(path); }

LoadedConfig loadConfig(const std::string& path) {
    const std::string ext = lowercase(path);
    ConfigFormat format;
    if (endsWith(ext, ".yaml") || endsWith(ext, ".yml")) format = ConfigFormat::Yaml;
    else if (endsWith(ext, ".ini") || endsWith(ext, ".cfg")) format = ConfigFormat::Ini;
    else throw std::runtime_error(path + ": unknown configuration format (use .yaml/.yml or .ini/.cfg)");
    std::vector<std::uint8_t> bytes;
    try {
        bytes = gseg::io::readFileBytes(path);
    } catch (const std::exception& e) {
        throw std::runtime_error(path + ": cannot open the configuration file (" +
                                 std::string(e.what()).substr(path.size() + 2) + ")");
    }
    if (bytes.size() > (1u << 20)) throw std::runtime_error(path + ": larger than 1 MiB: not a configuration file");
    return loadConfigFromText(std::string(bytes.begin(), bytes.end()), format, path);
}

std::string toYaml(const LoadedConfig& config) {
    std::string out;
    for (const std::string& key : gseg::Params::keys())
        out += key + ": " + (key == "distToGround" && config.distToGroundAuto ? "auto" : config.params.get(key)) + "\n";
    const auto section = [&out](const char* name, const auto& options) {
        out += std::string(name) + ":\n";
        for (const std::string& key : options.keys()) {
            const auto [unit, meaning] = options.describe(key);
            out += "  " + key + ": " + options.get(key) + "  # [" + unit + "] " + meaning + "\n";
        }
    };
    section("sensorHeight", config.sensorHeight);
    section("traversability", config.traversability);
    return out;
}

}  // namespace gseg::mrpt
