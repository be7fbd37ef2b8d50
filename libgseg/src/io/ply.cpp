#include <gseg/io/kitti.hpp>
#include <gseg/io/ply.hpp>

#include <algorithm>
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

Header parseHeader(const std::vector<std::uint8_t>& bytes, const std::string& path) {
    Header h;
    std::size_t pos = 0;
    bool inVertex = false, sawVertex = false, sawFormat = false;
    auto nextLine = [&]() -> std::string {
        const std::size_t end = std::find(bytes.begin() + pos, bytes.end(), '\n') - bytes.begin();
        if (end >= bytes.size()) throw std::runtime_error(path + ": PLY header has no end_header line");
        std::string line(bytes.begin() + pos, bytes.begin() + end);
        pos = end + 1;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        return line;
    };
    if (nextLine() != "ply") throw std::runtime_error(path + ": not a PLY file (no 'ply' magic line)");
    for (;;) {
        std::istringstream in(nextLine());
        std::string word;
        in >> word;
        if (word == "end_header") break;
        if (word == "format") {
            std::string fmt;
            in >> fmt;
            if (fmt == "binary_little_endian") h.binary = true;
            else if (fmt != "ascii") throw std::runtime_error(path + ": unsupported PLY format '" + fmt + "'");
            sawFormat = true;
        } else if (word == "element") {
            std::string name;
            long long count = -1;
            in >> name >> count;
            if (!in || count < 0) throw std::runtime_error(path + ": malformed PLY element line");
            inVertex = name == "vertex";
            if (inVertex) h.vertices = std::size_t(count), sawVertex = true;
            else if (!sawVertex) throw std::runtime_error(path + ": the PLY vertex element must come first");
        } else if (word == "property" && inVertex) {
            std::string type, name;
            in >> type >> name;
            if (type == "list") throw std::runtime_error(path + ": list properties on vertices are not supported");
            h.props.push_back(makeProperty(type, name, path));
        }
    }
    if (!sawFormat || !sawVertex) throw std::runtime_error(path + ": PLY header lacks a format or a vertex element");
    h.dataOffset = pos;
    return h;
}

int indexOf(const Header& h, const char* name) {
    for (std::size_t i = 0; i < h.props.size(); ++i)
        if (h.props[i].name == name) return int(i);
    return -1;
}

}  // namespace

std::vector<float> readPly(const std::string& path) {
    const std::vector<std::uint8_t> bytes = readFileBytes(path);
    if (bytes.empty()) throw std::runtime_error(path + ": empty file");
    const Header h = parseHeader(bytes, path);
    const int ix = indexOf(h, "x"), iy = indexOf(h, "y"), iz = indexOf(h, "z"), ii = indexOf(h, "intensity");
    if (ix < 0 || iy < 0 || iz < 0) throw std::runtime_error(path + ": PLY vertices lack x, y or z");
    std::vector<float> out(4 * h.vertices, 0.f);
    std::vector<double> values(h.props.size());
    const int wanted[4] = {ix, iy, iz, ii};
    if (h.binary) {
        std::size_t stride = 0;
        for (const Property& p : h.props) stride += std::size_t(p.size);
        if (bytes.size() - h.dataOffset < stride * h.vertices)
            throw std::runtime_error(path + ": truncated PLY: " + std::to_string(h.vertices) + " vertices of " +
                                     std::to_string(stride) + " bytes announced, " +
                                     std::to_string(bytes.size() - h.dataOffset) + " bytes present");
        const std::uint8_t* p = bytes.data() + h.dataOffset;
        for (std::size_t v = 0; v < h.vertices; ++v) {
            for (std::size_t k = 0; k < h.props.size(); ++k) values[k] = decode(p, h.props[k]), p += h.props[k].size;
            for (int a = 0; a < 4; ++a)
                if (wanted[a] >= 0) out[4 * v + a] = float(values[std::size_t(wanted[a])]);
        }
    } else {
        std::istringstream in(std::string(bytes.begin() + long(h.dataOffset), bytes.end()));
        in.imbue(std::locale::classic());
        for (std::size_t v = 0; v < h.vertices; ++v) {
            for (double& value : values)
                if (!(in >> value))
                    throw std::runtime_error(path + ": truncated or malformed PLY at vertex " + std::to_string(v));
            for (int a = 0; a < 4; ++a)
                if (wanted[a] >= 0) out[4 * v + a] = float(values[std::size_t(wanted[a])]);
        }
    }
    return out;
}

void writeLabelledPly(const std::string& path, const PointCloudView& cloud, const std::vector<std::uint8_t>& labels,
                      const PlyColours& colours) {
    if (labels.size() != cloud.size())
        throw std::invalid_argument("writeLabelledPly: " + std::to_string(labels.size()) + " labels for " +
                                    std::to_string(cloud.size()) + " points");
    std::string out = "ply\nformat binary_little_endian 1.0\ncomment gseg ground segmentation: green ground, red "
                      "non-ground\nelement vertex " + std::to_string(cloud.size()) +
                      "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar "
                      "green\nproperty uchar blue\nend_header\n";
    const std::size_t header = out.size();
    out.resize(header + cloud.size() * 15);
    char* p = out.data() + header;
    for (std::size_t i = 0; i < cloud.size(); ++i, p += 15) {
        std::memcpy(p, cloud.point(i), 12);
        std::memcpy(p + 12, labels[i] ? colours.ground : colours.nonGround, 3);
    }
    writeFileAtomic(path, out.data(), out.size());
}

}  // namespace gseg::io
