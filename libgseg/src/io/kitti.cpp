#include <gseg/io/kitti.hpp>

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <stdexcept>
#include <sys/stat.h>
#include <unistd.h>

namespace gseg::io {

namespace {

/// What a file that is not a regular file is, for the message.
const char* kindOf(mode_t mode) {
    if (S_ISDIR(mode)) return "a folder";
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISCHR(mode)) return "a character device";
    if (S_ISBLK(mode)) return "a block device";
    if (S_ISSOCK(mode)) return "a socket";
    return "not a file";
}

void requireRegular(const std::string& path, const struct stat& st) {
    if (!S_ISREG(st.st_mode)) throw std::runtime_error(path + ": not a regular file (" + kindOf(st.st_mode) + ")");
}

}  // namespace

std::uint64_t regularFileSize(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) throw std::runtime_error(path + ": cannot open (" + std::strerror(errno) + ")");
    requireRegular(path, st);
    return std::uint64_t(st.st_size);
}

std::vector<std::uint8_t> readFileBytes(const std::string& path, std::uint64_t maxBytes) {
    regularFileSize(path);  // before open(): a FIFO would block it
    // O_NONBLOCK: should the path turn into a FIFO between stat() and open(), open() still returns.
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) throw std::runtime_error(path + ": cannot open (" + std::strerror(errno) + ")");
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    struct stat st {};
    if (::fstat(fd, &st) != 0) throw std::runtime_error(path + ": cannot read its size (" + std::strerror(errno) + ")");
    requireRegular(path, st);
    if (std::uint64_t(st.st_size) > maxBytes)
        throw std::runtime_error(path + ": " + std::to_string(st.st_size) + " bytes, more than the " + std::to_string(maxBytes) +
                                 " this file may have");
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(st.st_size));
    std::size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) throw std::runtime_error(path + ": read failed (" + std::strerror(errno) + ")");
        if (n == 0) throw std::runtime_error(path + ": shorter than its size (changed while reading?)");
        done += std::size_t(n);
    }
    return bytes;
}

std::vector<float> parseKittiBin(const std::uint8_t* data, std::size_t size, const std::string& name) {
    if (size == 0) throw std::runtime_error(name + ": empty scan file");
    if (size % 16 != 0)
        throw std::runtime_error(name + ": size " + std::to_string(size) +
                                 " bytes is not a multiple of 16 (KITTI float32 x, y, z, intensity); truncated?");
    std::vector<float> out(size / sizeof(float));
    std::memcpy(out.data(), data, size);
    return out;
}

std::vector<float> readKittiBin(const std::string& path) {
    const std::vector<std::uint8_t> bytes = readFileBytes(path);
    return parseKittiBin(bytes.data(), bytes.size(), path);
}

std::vector<std::uint32_t> parseKittiLabels(const std::uint8_t* data, std::size_t size, const std::string& name,
                                            std::size_t expectedPoints) {
    if (size % 4 != 0)
        throw std::runtime_error(name + ": size " + std::to_string(size) +
                                 " bytes is not a multiple of 4 (uint32 per point); truncated?");
    std::vector<std::uint32_t> out(size / 4);
    if (!out.empty()) std::memcpy(out.data(), data, size);
    if (expectedPoints != SIZE_MAX && out.size() != expectedPoints)
        throw std::runtime_error(name + ": " + std::to_string(out.size()) + " labels for " +
                                 std::to_string(expectedPoints) + " points");
    return out;
}

std::vector<std::uint32_t> readKittiLabels(const std::string& path, std::size_t expectedPoints) {
    const std::vector<std::uint8_t> bytes = readFileBytes(path);
    return parseKittiLabels(bytes.data(), bytes.size(), path, expectedPoints);
}

}  // namespace gseg::io
