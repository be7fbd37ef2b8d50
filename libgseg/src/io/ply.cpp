#include <gseg/io/float_cast.hpp>
#include <gseg/io/kitti.hpp>
#include <gseg/io/ply.hpp>

#include <algorithm>
#include <charconv>
#include <cstring>
#include <sstream>
#include <stdexcept>

namespace gseg::io {
namespace {

struct Property {
    std::string name;
    int size = 0;      // bytes in binary files
    char kind = 'f';   // 'f' float, 'd' double, 'i' signed, 'u' unsigned
};

Property makeProperty(const std::string& type, const std::string& name, const std::string& path) {
    static const struct {
        const char* type;
        int size;
        char kind;
    } types[] = {{"float", 4, 'f'}, {"float32", 4, 'f'}, {"double", 8, 'd'}, {"float64", 8, 'd'},
                 {"char", 1, 'i'},  {"int8", 1, 'i'},    {"uchar", 1, 'u'},  {"uint8", 1, 'u'},
                 {"short", 2, 'i'}, {"int16", 2, 'i'},   {"ushort", 2, 'u'}, {"uint16", 2, 'u'},
                 {"int", 4, 'i'},   {"int32", 4, 'i'},   {"uint", 4, 'u'},   {"uint32", 4, 'u'}};
    for (const auto& t : types)
        if (type == t.type) return {name, t.size, t.kind};
    throw std::runtime_error(path + ": unsupported PLY property type '" + type + "' of '" + name + "'");
}

double decode(const std::uint8_t* p, const Property& prop) {
    switch (prop.kind) {
        case 'f': { float v; std::memcpy(&v, p, 4); return v; }
        case 'd': { double v; std::memcpy(&v, p, 8); return v; }
        case 'i':
            if (prop.size == 1) return double(std::int8_t(p[0]));
            if (prop.size == 2) { std::int16_t v; std::memcpy(&v, p, 2); return v; }
            { std::int32_t v; std::memcpy(&v, p, 4); return v; }
        default:
            if (prop.size == 1) return double(p[0]);
            if (prop.size == 2) { std::uint16_t v; std::memcpy(&v, p, 2); return v; }
            { std::uint32_t v; std::memcpy(&v, p, 4); return v; }
    }
}

struct Header {
    bool binary = false;
    std::size_t vertices = 0;
    std::vector<Property> props;
    std::size_t dataOffset = 0;
};

// A vertex count: decimal digits only (no sign, exponent or trailing text), at most 2^62.
std::size_t parseCount(const std::string& text, const std::string& name) {
    unsigned long long v = 0;
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || v > (1ull << 62))
        throw std::runtime_error(name + ": malformed PLY element count '" + text + "'");
    return std::size_t(v);
}

Header parseHeader(const std::uint8_t* data, std::size_t size, const std::string& name) {
    constexpr std::size_t kMaxLine = 4096;
    Header h;
    std::size_t pos = 0;
    bool inVertex = false, sawVertex = false, sawFormat = false, sawElement = false;
    auto nextLine = [&]() -> std::string {
        const std::size_t end = std::size_t(std::find(data + pos, data + size, '\n') - data);
        if (end >= size) throw std::runtime_error(name + ": PLY header has no end_header line");
        if (end - pos > kMaxLine) throw std::runtime_error(name + ": PLY header line longer than 4096 bytes");
        std::string line(data + pos, data + end);
        pos = end + 1;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        return line;
    };
    if (nextLine() != "ply") throw std::runtime_error(name + ": not a PLY file (no 'ply' magic line)");
    for (;;) {
        std::istringstream in(nextLine());
        std::string word;
        in >> word;
        if (word == "end_header") break;
        if (word.empty() || word == "comment" || word == "obj_info") continue;
        if (word == "format") {
            std::string fmt;
            in >> fmt;
            if (sawFormat) throw std::runtime_error(name + ": a second PLY format line");
            if (fmt == "binary_little_endian") h.binary = true;
            else if (fmt != "ascii") throw std::runtime_error(name + ": unsupported PLY format '" + fmt + "'");
            sawFormat = true;
        } else if (word == "element") {
            std::string element, count;
            in >> element >> count;
            const std::size_t n = parseCount(count, name);
            inVertex = element == "vertex";
            sawElement = true;
            if (inVertex && sawVertex) throw std::runtime_error(name + ": a second 'element vertex' line");
            if (inVertex) h.vertices = n, sawVertex = true;
            else if (!sawVertex) throw std::runtime_error(name + ": the PLY vertex element must come first");
        } else if (word == "property") {
            if (!sawElement) throw std::runtime_error(name + ": PLY property before any element");
            if (!inVertex) continue;
            std::string type, prop;
            in >> type >> prop;
            if (type == "list") throw std::runtime_error(name + ": list properties on vertices are not supported");
            for (const Property& p : h.props)
                if (p.name == prop) throw std::runtime_error(name + ": PLY vertex property '" + prop + "' given twice");
            h.props.push_back(makeProperty(type, prop, name));
        } else {
            throw std::runtime_error(name + ": unknown PLY header line starting with '" + word + "'");
        }
    }
    if (!sawFormat || !sawVertex) throw std::runtime_error(name + ": PLY header lacks a format or a vertex element");
    h.dataOffset = pos;
    return h;
}

int indexOf(const Header& h, const char* name) {
    for (std::size_t i = 0; i < h.props.size(); ++i)
        if (h.props[i].name == name) return int(i);
    return -1;
}

bool isBlank(std::uint8_t c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

// Reads the next whitespace-separated number of an ascii PLY body; false at the end of the data.
bool nextNumber(const std::uint8_t*& p, const std::uint8_t* end, double& value) {
    while (p < end && isBlank(*p)) ++p;
    if (p == end) return false;
    const std::uint8_t* start = p;
    while (p < end && !isBlank(*p)) ++p;
    const char* first = reinterpret_cast<const char*>(start);
    const char* last = reinterpret_cast<const char*>(p);
    if (last - first > 1 && *first == '+') ++first;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    return ec == std::errc() && ptr == last;
}

}  // namespace

namespace {

/// Calls take(v, values) for every vertex of the file whose header is `h` (with at least one
/// property), `values` holding the vertex's properties in header order. Checks the size announced
/// in the header against the data first.
template <class Take>
void forEachVertex(const std::uint8_t* data, std::size_t size, const std::string& name, const Header& h, Take&& take) {
    const std::size_t remaining = size - h.dataOffset;
    std::size_t stride = 0;
    for (const Property& p : h.props) stride += std::size_t(p.size);
    // What the rest of the file can hold: `stride` bytes per binary vertex; in ascii at least one
    // character and one separator per value (the last value needs no separator).
    const std::size_t capacity = h.binary ? remaining / stride : (remaining + 1) / (2 * h.props.size());
    if (h.vertices > capacity)
        throw std::runtime_error(name + ": truncated PLY: " + std::to_string(h.vertices) + " vertices announced, the " +
                                 std::to_string(remaining) + " bytes after the header hold at most " +
                                 std::to_string(capacity));
    std::vector<double> values(h.props.size());
    const std::uint8_t* p = data + h.dataOffset;
    const std::uint8_t* const end = data + size;
    for (std::size_t v = 0; v < h.vertices; ++v) {
        for (std::size_t k = 0; k < h.props.size(); ++k) {
            if (h.binary) {
                values[k] = decode(p, h.props[k]);
                p += h.props[k].size;
            } else if (!nextNumber(p, end, values[k])) {
                throw std::runtime_error(name + ": truncated or malformed PLY at vertex " + std::to_string(v));
            }
        }
        take(v, values);
    }
}

}  // namespace

std::vector<float> parsePly(const std::uint8_t* data, std::size_t size, const std::string& name) {
    if (size == 0) throw std::runtime_error(name + ": empty file");
    const Header h = parseHeader(data, size, name);
    const int wanted[4] = {indexOf(h, "x"), indexOf(h, "y"), indexOf(h, "z"), indexOf(h, "intensity")};
    if (wanted[0] < 0 || wanted[1] < 0 || wanted[2] < 0) throw std::runtime_error(name + ": PLY vertices lack x, y or z");
    std::vector<float> out;
    forEachVertex(data, size, name, h, [&](std::size_t v, const std::vector<double>& values) {
        if (out.empty()) out.assign(4 * h.vertices, 0.f);  // once the size is known to fit the file
        for (int a = 0; a < 4; ++a)
            if (wanted[a] >= 0) out[4 * v + std::size_t(a)] = toFloat(values[std::size_t(wanted[a])]);
    });
    return out;
}

std::vector<double> parsePlyProperty(const std::uint8_t* data, std::size_t size, const std::string& name,
                                     const std::string& property) {
    if (size == 0) throw std::runtime_error(name + ": empty file");
    const Header h = parseHeader(data, size, name);
    const int k = indexOf(h, property.c_str());
    if (k < 0) throw std::runtime_error(name + ": PLY vertices have no property '" + property + "'");
    std::vector<double> out;
    forEachVertex(data, size, name, h, [&](std::size_t v, const std::vector<double>& values) {
        if (out.empty()) out.resize(h.vertices);  // once the size is known to fit the file
        out[v] = values[std::size_t(k)];
    });
    return out;
}

std::vector<double> readPlyProperty(const std::string& path, const std::string& property) {
    const std::vector<std::uint8_t> bytes = readFileBytes(path);
    return parsePlyProperty(bytes.data(), bytes.size(), path, property);
}

std::vector<float> readPly(const std::string& path) {
    const std::vector<std::uint8_t> bytes = readFileBytes(path);
    return parsePly(bytes.data(), bytes.size(), path);
}

std::string classScalarProperty(const PlyOptions&) { return "scalar_class"; }

std::string labelledPlyBytes(const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                             const PlyColours& colours, const PlyOptions& options) {
    if (labels.size() != cloud.size())
        throw std::invalid_argument("writeLabelledPly: " + std::to_string(labels.size()) + " labels for " +
                                    std::to_string(cloud.size()) + " points");
    if (options.intensity && cloud.strideBytes() < 4 * sizeof(float))
        throw std::invalid_argument("writeLabelledPly: intensity asked for, but the points are " +
                                    std::to_string(cloud.strideBytes()) + " bytes apart (x, y, z, intensity need 16)");
    // One convention in the file: 1 is the ground in every field (class, label); the class
    // field's other value is 2, as in the map's `class` layer.
    const std::string scalar = classScalarProperty(options);
    std::string out = "ply\nformat binary_little_endian 1.0\ncomment " + options.comment + "\ncomment " + scalar + ": 1 " +
                      options.groundName + ", 2 " + options.nonGroundName +
                      " (the map's class values; CloudCompare's first scalar field 'class', on its default ramp " +
                      options.groundName + " blue, " + options.nonGroundName + " red; its Colors: RGB shows the colours)" +
                      "\ncomment label: 1 " + options.groundName + ", 0 " + options.nonGroundName + " (as gseg's labels files)" +
                      "\ncomment red, green, blue: " + options.groundName + " " + colours.groundName + ", " +
                      options.nonGroundName + " " + colours.nonGroundName + "\nelement vertex " + std::to_string(cloud.size()) +
                      "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar " + scalar + "\n" +
                      (options.intensity ? "property float intensity\n" : "") +
                      "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar label\nend_header\n";
    const std::size_t header = out.size(), record = options.intensity ? 21 : 17;
    out.resize(header + cloud.size() * record);
    char* p = out.data() + header;
    for (std::size_t i = 0; i < cloud.size(); ++i, p += record) {
        const float* point = cloud.point(i);
        std::memcpy(p, point, 12);
        p[12] = char(labels[i] ? 1 : 2);
        if (options.intensity) std::memcpy(p + 13, point + 3, 4);
        char* rest = p + record - 4;
        std::memcpy(rest, labels[i] ? colours.ground : colours.nonGround, 3);
        rest[3] = char(labels[i] ? 1 : 0);
    }
    return out;
}

void writeLabelledPly(const std::string& path, const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                      const PlyColours& colours, const PlyOptions& options) {
    const std::string bytes = labelledPlyBytes(cloud, labels, colours, options);
    writeFileAtomic(path, bytes.data(), bytes.size());
}

}  // namespace gseg::io
