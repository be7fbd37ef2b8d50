#include <gseg/io/kitti.hpp>  // readFileBytes, regularFileSize
#include <gseg/io/ros_map.hpp>
#include <gseg/text.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

namespace gseg::io {

namespace {

std::string unquote(const std::string& s) {
    if (s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front()) return s.substr(1, s.size() - 2);
    return s;
}

[[noreturn]] void fail(const std::string& file, int line, const std::string& what) {
    throw std::runtime_error(file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + what);
}

double number(const std::string& file, int line, const std::string& key, const std::string& text) {
    const std::string t = trim(text);
    const std::optional<double> v = parseNumber<double>(t);
    if (!v || !std::isfinite(*v)) fail(file, line, key + ": '" + t + "' is not a finite number");
    return *v;
}

std::string folderOf(const std::string& path) {
    const auto slash = path.find_last_of('/');
    return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

// The next header token of a PGM, skipping white space and '#' comments.
std::string pgmToken(const std::string& bytes, std::size_t& i, const std::string& file) {
    for (;;) {
        while (i < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[i]))) ++i;
        if (i < bytes.size() && bytes[i] == '#') {
            while (i < bytes.size() && bytes[i] != '\n') ++i;
            continue;
        }
        break;
    }
    const std::size_t b = i;
    while (i < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[i]))) ++i;
    if (b == i) fail(file, 0, "truncated PGM header");
    return bytes.substr(b, i - b);
}

long pgmNumber(const std::string& bytes, std::size_t& i, const std::string& file, const char* what, long lo, long hi) {
    const std::string t = pgmToken(bytes, i, file);
    long v = 0;
    for (char c : t) {
        if (!std::isdigit(static_cast<unsigned char>(c))) fail(file, 0, std::string("PGM ") + what + " '" + t + "' is not a number");
        v = v * 10 + (c - '0');
        if (v > hi) break;
    }
    if (v < lo || v > hi)
        fail(file, 0, std::string("PGM ") + what + " " + t + " is outside " + std::to_string(lo) + " to " + std::to_string(hi));
    return v;
}

/// [pixels] the largest map image read (1 GiB of grey values): a header claiming more is refused
/// before anything is allocated.
constexpr std::uint64_t kMaxPixels = std::uint64_t(1) << 30;
/// [bytes] the largest map YAML read (a map_server YAML is a few hundred bytes).
constexpr std::uint64_t kMaxYamlBytes = std::uint64_t(1) << 20;

void readPgm(const std::string& file, RosMap& map) {
    // stat first: a FIFO, a device (/dev/zero) or a folder is refused before open() could block
    // or a read could run without end.
    std::uint64_t size = 0;
    try {
        size = regularFileSize(file);
    } catch (const std::exception& e) {
        const std::string what = e.what(), head = file + ": ";
        fail(file, 0, (what.rfind(head, 0) == 0 ? what.substr(head.size()) : what) + "; the map image must be a PGM file");
    }
    std::ifstream in(file, std::ios::binary);
    if (!in) fail(file, 0, "cannot open the map image");
    // The header only (at most 64 KiB, comments included): the pixels are read once their count is
    // known to fit the file and the bound.
    std::string bytes(std::size_t(std::min<std::uint64_t>(size, 1 << 16)), '\0');
    in.read(bytes.data(), std::streamsize(bytes.size()));
    if (in.bad() || std::size_t(in.gcount()) != bytes.size()) fail(file, 0, "cannot read the map image");
    std::size_t i = 0;
    const std::string magic = bytes.size() >= 2 ? bytes.substr(0, 2) : bytes;
    if (magic != "P5") fail(file, 0, "not a binary PGM (P5) image (gseg reads the PGM maps that map_saver and gseg write)");
    i = 2;
    map.width = int(pgmNumber(bytes, i, file, "width", 1, 1 << 20));
    map.height = int(pgmNumber(bytes, i, file, "height", 1, 1 << 20));
    pgmNumber(bytes, i, file, "maxval", 1, 255);
    if (i >= bytes.size() || !std::isspace(static_cast<unsigned char>(bytes[i]))) fail(file, 0, "truncated PGM header");
    ++i;  // the single white space before the pixels
    const std::uint64_t n = std::uint64_t(map.width) * std::uint64_t(map.height);
    if (n > kMaxPixels)
        fail(file, 0, "the header claims " + std::to_string(map.width) + " x " + std::to_string(map.height) + " pixels, more than the " +
                          std::to_string(kMaxPixels) + " of a map gseg reads");
    if (size - i < n) fail(file, 0, "truncated: " + std::to_string(size - i) + " of " + std::to_string(n) + " pixel bytes");
    map.pixels.resize(std::size_t(n));
    in.clear();
    in.seekg(std::streamoff(i));
    in.read(reinterpret_cast<char*>(map.pixels.data()), std::streamsize(n));
    if (!in || std::uint64_t(in.gcount()) != n) fail(file, 0, "cannot read the map image's pixels (changed while reading?)");
}

/// The line without its YAML comment: '#' starts one at the line's start or after a blank, outside
/// quotes ("m#1.pgm" is a name, "m.pgm # the map" a name and a comment).
std::string withoutComment(const std::string& line) {
    char quote = 0;
    for (std::size_t k = 0; k < line.size(); ++k) {
        const char c = line[k];
        if (quote) {
            if (c == quote) quote = 0;
        } else if (c == '"' || c == '\'') {
            quote = c;
        } else if (c == '#' && (k == 0 || line[k - 1] == ' ' || line[k - 1] == '\t')) {
            return line.substr(0, k);
        }
    }
    return line;
}

}  // namespace

RosMap RosMap::unknown(int width, int height, double resolution, double originX, double originY) {
    RosMap m;
    m.width = width;
    m.height = height;
    m.resolution = resolution;
    m.originX = originX;
    m.originY = originY;
    m.pixels.assign(std::size_t(width) * std::size_t(height), kUnknown);
    return m;
}

RosCell RosMap::at(long long cx, long long cy) const {
    if (cx < 0 || cy < 0 || cx >= width || cy >= height) return RosCell::Unknown;
    const double v = value(int(cx), int(cy));
    if (mode == "raw" && v > 100) return RosCell::Unknown;
    const double p = mode == "raw" ? v / 100.0 : negate ? v / 255.0 : (255.0 - v) / 255.0;
    if (p > occupiedThresh) return RosCell::Occupied;
    if (p < freeThresh) return RosCell::Free;
    return RosCell::Unknown;
}

long long RosMap::cellX(double x) const { return (long long)std::floor((x - originX) / resolution); }
long long RosMap::cellY(double y) const { return (long long)std::floor((y - originY) / resolution); }

void validate(const RosMap& map) {
    if (!(std::isfinite(map.resolution) && map.resolution > 0)) throw std::invalid_argument("map resolution must be a positive number");
    if (!std::isfinite(map.originX) || !std::isfinite(map.originY) || !std::isfinite(map.originYaw))
        throw std::invalid_argument("map origin must be finite");
    if (map.width <= 0 || map.height <= 0) throw std::invalid_argument("map has no cells");
    if (map.pixels.size() != std::size_t(map.width) * std::size_t(map.height))
        throw std::invalid_argument("map has " + std::to_string(map.pixels.size()) + " pixels for " + std::to_string(map.width) +
                                    " x " + std::to_string(map.height) + " cells");
    if (!(map.freeThresh >= 0 && map.freeThresh < map.occupiedThresh && map.occupiedThresh <= 1))
        throw std::invalid_argument("map thresholds must satisfy 0 <= free_thresh < occupied_thresh <= 1");
    if (map.negate != 0 && map.negate != 1) throw std::invalid_argument("map negate must be 0 or 1");
    if (map.mode != "trinary" && map.mode != "scale" && map.mode != "raw")
        throw std::invalid_argument("map mode must be trinary, scale or raw, not '" + map.mode + "'");
}

RosMap readRosMap(const std::string& yamlPath) {
    std::string text;
    try {
        const std::vector<std::uint8_t> bytes = readFileBytes(yamlPath, kMaxYamlBytes);  // stat before open
        text.assign(bytes.begin(), bytes.end());
    } catch (const std::exception& e) {
        throw std::runtime_error(std::string(e.what()) + " (the map YAML)");
    }
    std::istringstream in(text);
    std::map<std::string, std::pair<std::string, int>> keys;  // value, line
    std::string line;
    int lineNo = 0;
    while (std::getline(in, line)) {
        ++lineNo;
        line = trim(withoutComment(line));
        if (line.empty() || line == "---") continue;
        const auto colon = line.find(':');
        if (colon == std::string::npos) fail(yamlPath, lineNo, "expected 'key: value', got '" + line + "'");
        const std::string key = trim(line.substr(0, colon));
        if (keys.count(key)) fail(yamlPath, lineNo, "key '" + key + "' repeated (first on line " + std::to_string(keys[key].second) + ")");
        keys[key] = {trim(line.substr(colon + 1)), lineNo};
    }
    const auto need = [&](const std::string& key) -> const std::pair<std::string, int>& {
        const auto it = keys.find(key);
        if (it == keys.end()) fail(yamlPath, 0, "no '" + key + "' key (a map_server map names image, resolution and origin)");
        return it->second;
    };
    RosMap map;
    const auto& res = need("resolution");
    map.resolution = number(yamlPath, res.second, "resolution", res.first);
    if (!(map.resolution >= 1e-4 && map.resolution <= 1e3))
        fail(yamlPath, res.second, "resolution: " + trim(res.first) + " m is outside 0.0001 to 1000 m per cell");
    const auto& origin = need("origin");
    {
        std::string t = trim(origin.first);
        if (t.size() < 2 || t.front() != '[' || t.back() != ']') fail(yamlPath, origin.second, "origin must be a list [x, y, yaw]");
        t = t.substr(1, t.size() - 2);
        std::vector<double> v;
        std::stringstream ss(t);
        std::string item;
        while (std::getline(ss, item, ',')) v.push_back(number(yamlPath, origin.second, "origin", item));
        if (v.size() != 3) fail(yamlPath, origin.second, "origin must hold three values [x, y, yaw]");
        map.originX = v[0];
        map.originY = v[1];
        map.originYaw = v[2];
        if (v[2] != 0) fail(yamlPath, origin.second, "a rotated map (origin yaw " + trim(origin.first) + ") is not supported");
    }
    if (keys.count("negate")) {
        const auto& n = keys["negate"];
        const double v = number(yamlPath, n.second, "negate", n.first);
        if (v != 0 && v != 1) fail(yamlPath, n.second, "negate must be 0 or 1");
        map.negate = int(v);
    }
    if (keys.count("occupied_thresh")) map.occupiedThresh = number(yamlPath, keys["occupied_thresh"].second, "occupied_thresh", keys["occupied_thresh"].first);
    if (keys.count("free_thresh")) map.freeThresh = number(yamlPath, keys["free_thresh"].second, "free_thresh", keys["free_thresh"].first);
    if (keys.count("mode")) map.mode = unquote(keys["mode"].first);
    const auto& image = need("image");
    const std::string name = unquote(image.first);
    if (name.empty()) fail(yamlPath, image.second, "image is empty");
    if (name.find('\0') != std::string::npos) fail(yamlPath, image.second, "image: the name holds a NUL byte");
    readPgm(name.front() == '/' ? name : folderOf(yamlPath) + name, map);
    try {
        validate(map);
    } catch (const std::invalid_argument& e) {
        fail(yamlPath, 0, e.what());
    }
    return map;
}


std::string encodePgm(const RosMap& map) {
    validate(map);
    char res[64];
    std::snprintf(res, sizeof res, "%.6g", map.resolution);
    std::string out = "P5\n# gseg map, " + std::string(res) + " m/pixel\n" + std::to_string(map.width) + " " +
                      std::to_string(map.height) + "\n255\n";
    out.append(reinterpret_cast<const char*>(map.pixels.data()), map.pixels.size());
    return out;
}

std::string encodeRosMapYaml(const RosMap& map, const std::string& imageName) {
    validate(map);
    const auto num = [](double v) {
        char b[64];
        std::snprintf(b, sizeof b, "%.9g", v);
        return std::string(b);
    };
    std::string out;
    out += "image: " + imageName + "\n";
    out += "mode: " + map.mode + "\n";
    out += "resolution: " + num(map.resolution) + "\n";
    out += "origin: [" + num(map.originX) + ", " + num(map.originY) + ", " + num(map.originYaw) + "]\n";
    out += "negate: " + std::to_string(map.negate) + "\n";
    out += "occupied_thresh: " + num(map.occupiedThresh) + "\n";
    out += "free_thresh: " + num(map.freeThresh) + "\n";
    return out;
}

}  // namespace gseg::io
