#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/gzip_stream.hpp>

#include <mrpt/serialization/CArchive.h>

#include <zlib.h>

#include <algorithm>
#include <stdexcept>

namespace gseg::mrpt {

GzipOutputStream::GzipOutputStream(Sink sink, std::string name) : sink_(std::move(sink)), name_(std::move(name)) {
    pending_.reserve(kPending);
    auto* z = new z_stream{};
    // windowBits 15 + 16: the gzip wrapper (no time stamp), which MRPT's readers detect; level 1 as MRPT writes.
    if (deflateInit2(z, 1, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
        delete z;
        throw std::runtime_error(name_ + ": cannot start the gzip compressor");
    }
    z_ = z;
}

GzipOutputStream::GzipOutputStream(gseg::io::AtomicFile& file)
    : GzipOutputStream([&file](const void* d, std::size_t n) { file.write(d, n); }, file.path()) {}

GzipOutputStream::~GzipOutputStream() {
    auto* z = static_cast<z_stream*>(z_);
    deflateEnd(z);
    delete z;
}

void GzipOutputStream::pump(const void* data, std::size_t size, int flush) {
    auto* z = static_cast<z_stream*>(z_);
    z->next_in = static_cast<Bytef*>(const_cast<void*>(data));
    z->avail_in = uInt(size);
    for (;;) {
        Bytef out[1 << 16];
        z->next_out = out;
        z->avail_out = sizeof out;
        const int r = deflate(z, flush);
        if (r == Z_STREAM_ERROR) throw std::runtime_error(name_ + ": gzip compression failed");
        if (const std::size_t n = sizeof out - z->avail_out) sink_(out, n);
        if (flush == Z_FINISH ? r == Z_STREAM_END : z->avail_out != 0) break;
    }
}

size_t GzipOutputStream::Write(const void* buffer, size_t count) {
    if (finished_) throw std::logic_error(name_ + ": write after the gzip stream was finished");
    const auto* p = static_cast<const char*>(buffer);
    written_ += count;
    if (pending_.size() + count <= kPending) {  // small writes: gathered (the same compressed bytes)
        pending_.insert(pending_.end(), p, p + count);
        return count;
    }
    flushPending();
    for (size_t left = count; left > 0;) {  // zlib counts in unsigned int
        const std::size_t chunk = std::min<size_t>(left, 1u << 30);
        pump(p, chunk, Z_NO_FLUSH);
        p += chunk, left -= chunk;
    }
    return count;
}

void GzipOutputStream::flushPending() {
    if (!pending_.empty()) pump(pending_.data(), pending_.size(), Z_NO_FLUSH);
    pending_.clear();
}

void GzipOutputStream::finish() {
    if (finished_) return;
    flushPending();
    pump(nullptr, 0, Z_FINISH);
    finished_ = true;
}

size_t GzipOutputStream::Read(void*, size_t) { throw std::logic_error(name_ + ": GzipOutputStream is write-only"); }

uint64_t GzipOutputStream::Seek(int64_t, CStream::TSeekOrigin) { throw std::logic_error(name_ + ": GzipOutputStream cannot seek"); }

void writeGzipObject(gseg::io::AtomicFile& file, const ::mrpt::serialization::CSerializable& object) {
    GzipOutputStream out(file);
    try {
        ::mrpt::serialization::archiveFrom(out) << object;
    } catch (const std::exception& e) {
        throw std::runtime_error(errorReason(e));  // MRPT wraps the file's error in its banner
    }
    out.finish();
}

}  // namespace gseg::mrpt
