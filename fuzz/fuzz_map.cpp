// libFuzzer target: the map reader of `gseg eval-map` (readRosMap(): a map_server YAML and the PGM
// image it names), on files written from the input. Input: two bytes (little-endian) giving the
// YAML's length, the YAML text, then the PGM's bytes (written as m.pgm beside it).
// Contract: a map that passes validate() with one pixel per cell, or std::runtime_error; never a
// hang or an allocation beyond the file's size (libFuzzer's -timeout, -malloc_limit_mb). A map
// read is written with encodePgm() / encodeRosMapYaml() and reads back the same.
#include "fuzz_input.hpp"

#include <gseg/io/ros_map.hpp>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>
#include <unistd.h>

namespace {

/// A folder of this process for the files (made once, removed at exit).
struct Folder {
    std::string path = "/tmp/gseg_fuzz_map_XXXXXX";
    Folder() {
        if (!::mkdtemp(path.data())) std::abort();
    }
    ~Folder() {
        for (const char* f : {"/m.yaml", "/m.pgm", "/back.yaml", "/back.pgm"}) ::unlink((path + f).c_str());
        ::rmdir(path.c_str());
    }
};

const std::string& folder() {
    static const Folder dir;
    return dir.path;
}

void writeFile(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
}

bool close(double a, double b) { return a == b || std::fabs(a - b) <= 1e-8 * std::fabs(a); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 2) return 0;
    const std::size_t yamlLength = std::min<std::size_t>(size - 2, std::size_t(data[0]) | std::size_t(data[1]) << 8);
    const std::string yaml(reinterpret_cast<const char*>(data + 2), yamlLength);
    const std::string pgm(reinterpret_cast<const char*>(data + 2 + yamlLength), size - 2 - yamlLength);
    // Only the image beside the YAML: a name with '/' could reach any file of the machine.
    if (yaml.find('/') != std::string::npos) return 0;
    const std::string dir = folder();
    writeFile(dir + "/m.yaml", yaml);
    writeFile(dir + "/m.pgm", pgm);
    gseg::io::RosMap map;
    try {
        map = gseg::io::readRosMap(dir + "/m.yaml");
    } catch (const std::runtime_error&) {
        return 0;
    }
    gseg::io::validate(map);  // throws (and the fuzzer reports it) if the reader let something through
    GSEG_FUZZ_CHECK(map.pixels.size() == std::size_t(map.width) * std::size_t(map.height));
    GSEG_FUZZ_CHECK(map.pixels.size() <= pgm.size());
    std::size_t known = 0;
    for (int cy = 0; cy < map.height; ++cy)
        for (int cx = 0; cx < map.width; ++cx) known += map.at(cx, cy) != gseg::io::RosCell::Unknown;
    GSEG_FUZZ_CHECK(known <= map.pixels.size());
    GSEG_FUZZ_CHECK(map.at(-1, 0) == gseg::io::RosCell::Unknown && map.at(map.width, 0) == gseg::io::RosCell::Unknown);
    // Written and read back: the same map.
    writeFile(dir + "/back.pgm", gseg::io::encodePgm(map));
    writeFile(dir + "/back.yaml", gseg::io::encodeRosMapYaml(map, "back.pgm"));
    const gseg::io::RosMap back = gseg::io::readRosMap(dir + "/back.yaml");
    GSEG_FUZZ_CHECK(back.width == map.width && back.height == map.height && back.pixels == map.pixels);
    GSEG_FUZZ_CHECK(back.mode == map.mode && back.negate == map.negate);
    GSEG_FUZZ_CHECK(close(back.resolution, map.resolution) && close(back.originX, map.originX) && close(back.originY, map.originY));
    return 0;
}
