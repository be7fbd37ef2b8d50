#include <gseg/io/kitti.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <unistd.h>

namespace gseg::io {

std::vector<std::uint8_t> readFileBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) throw std::runtime_error(path + ": cannot open (" + std::strerror(errno) + ")");
    const std::streamoff size = in.tellg();
    if (size < 0) throw std::runtime_error(path + ": cannot read its size");
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
    in.seekg(0);
    if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), size))
        throw std::runtime_error(path + ": read failed");
    return bytes;
}

std::vector<float> readKittiBin(const std::string& path) {
    const std::vector<std::uint8_t> bytes = readFileBytes(path);
    if (bytes.empty()) throw std::runtime_error(path + ": empty scan file");
    if (bytes.size() % 16 != 0)
        throw std::runtime_error(path + ": size " + std::to_string(bytes.size()) +
                                 " bytes is not a multiple of 16 (KITTI float32 x, y, z, intensity); truncated?");
    std::vector<float> out(bytes.size() / sizeof(float));
    std::memcpy(out.data(), bytes.data(), bytes.size());
    return out;
}

std::vector<std::uint32_t> readKittiLabels(const std::string& path, std::size_t expectedPoints) {
    const std::vector<std::uint8_t> bytes = readFileBytes(path);
    if (bytes.size() % 4 != 0)
        throw std::runtime_error(path + ": size " + std::to_string(bytes.size()) +
                                 " bytes is not a multiple of 4 (uint32 per point); truncated?");
    std::vector<std::uint32_t> out(bytes.size() / 4);
    if (!out.empty()) std::memcpy(out.data(), bytes.data(), bytes.size());
    if (expectedPoints != SIZE_MAX && out.size() != expectedPoints)
        throw std::runtime_error(path + ": " + std::to_string(out.size()) + " labels for " +
                                 std::to_string(expectedPoints) + " points");
    return out;
}

void writeFileAtomic(const std::string& path, const void* bytes, std::size_t size) {
    const std::string tmp = path + ".tmp" + std::to_string(::getpid());
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw std::runtime_error(path + ": cannot create (" + std::strerror(errno) + ")");
        out.write(static_cast<const char*>(bytes), std::streamsize(size));
        out.flush();
        if (!out) {
            std::remove(tmp.c_str());
            throw std::runtime_error(path + ": write failed");
        }
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        const std::string why = std::strerror(errno);
        std::remove(tmp.c_str());
        throw std::runtime_error(path + ": cannot rename the temporary file into place (" + why + ")");
    }
}

}  // namespace gseg::io
