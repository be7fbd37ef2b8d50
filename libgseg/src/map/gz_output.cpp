#include <gseg/map/gz_output.hpp>

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace gseg::map {

CheckedGzOutput::CheckedGzOutput(const std::string& path, const std::string& name) : name_(name.empty() ? path : name) {
    errno = 0;
    gz_ = gzopen(path.c_str(), "wb1");
    if (!gz_) throw std::runtime_error(name_ + ": cannot create (" + (errno ? std::strerror(errno) : "zlib") + ")");
}

CheckedGzOutput::~CheckedGzOutput() {
    if (gz_) gzclose(static_cast<gzFile>(gz_));
}

void CheckedGzOutput::fail(const std::string& what) {
    int zerr = 0;
    const char* zmsg = gz_ ? gzerror(static_cast<gzFile>(gz_), &zerr) : "";
    const std::string why = zerr == Z_ERRNO || zerr == 0 ? std::strerror(errno) : zmsg;
    throw std::runtime_error(name_ + ": " + what + " (" + why + ")");
}

size_t CheckedGzOutput::Write(const void* buffer, size_t count) {
    if (!gz_) fail("write after close");
    const auto* p = static_cast<const char*>(buffer);
    for (size_t left = count; left > 0;) {  // gzwrite takes an unsigned int
        const unsigned chunk = unsigned(std::min<size_t>(left, 1u << 30));
        errno = 0;
        if (gzwrite(static_cast<gzFile>(gz_), p, chunk) != int(chunk)) fail("write failed");
        p += chunk, left -= chunk;
    }
    written_ += count;
    return count;
}

void CheckedGzOutput::close() {
    if (!gz_) return;
    errno = 0;
    const int rc = gzclose(static_cast<gzFile>(gz_));
    gz_ = nullptr;
    if (rc != Z_OK) throw std::runtime_error(name_ + ": write failed on close (" + (rc == Z_ERRNO ? std::strerror(errno) : "zlib error") + ")");
}

size_t CheckedGzOutput::Read(void*, size_t) { throw std::logic_error(name_ + ": CheckedGzOutput is write-only"); }

uint64_t CheckedGzOutput::Seek(int64_t, CStream::TSeekOrigin) { throw std::logic_error(name_ + ": CheckedGzOutput cannot seek"); }

}  // namespace gseg::map
