#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/gzip_stream.hpp>

#include <mrpt/serialization/CArchive.h>

#include <zlib.h>

#include <algorithm>
#include <stdexcept>

namespace gseg::mrpt {

GzipOutputStream::GzipOutputStream(Sink sink, std::string name, std::size_t memberBytes)
    : sink_(std::move(sink)), name_(std::move(name)), memberBytes_(memberBytes) {
    pending_.reserve(kPending);
    auto* z = new z_stream{};
    // windowBits 15 + 16: the gzip wrapper (no time stamp), which MRPT's readers detect; level 1 as MRPT writes.
    if (deflateInit2(z, 1, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
        delete z;
        throw std::runtime_error(name_ + ": cannot start the gzip compressor");
    }
    z_ = z;
    if (memberBytes_ > 0) {
        header_ = new gz_header{};
        startMember();
    }
}

GzipOutputStream::GzipOutputStream(gseg::io::AtomicFile& file, std::size_t memberBytes)
    : GzipOutputStream([&file](const void* d, std::size_t n) { file.write(d, n); }, file.path(), memberBytes) {}

GzipOutputStream::~GzipOutputStream() {
    auto* z = static_cast<z_stream*>(z_);
    deflateEnd(z);
    delete z;
    delete static_cast<gz_header*>(header_);
}

void GzipOutputStream::emit(const void* data, std::size_t size) {
    if (memberBytes_ == 0) return sink_(data, size);
    const auto* p = static_cast<const unsigned char*>(data);
    member_.insert(member_.end(), p, p + size);
}

// A new member: its header carries the subfield 'G','S' whose size and entry count closeMember()
// fills in (zlib writes the header: FLG FEXTRA, no time stamp, XFL and OS as without one).
void GzipOutputStream::startMember() {
    auto* z = static_cast<z_stream*>(z_);
    extra_ = {'G', 'S', 8, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    auto* h = static_cast<gz_header*>(header_);
    *h = gz_header{};
    h->os = 3;  // Unix, zlib's own choice here
    h->extra = extra_.data();
    h->extra_len = uInt(extra_.size());
    if (deflateReset(z) != Z_OK || deflateSetHeader(z, h) != Z_OK) throw std::runtime_error(name_ + ": cannot start a gzip member");
    memberStart_ = written_;
    memberEntries_ = 0;
}

void GzipOutputStream::closeMember() {
    flushPending();
    pump(nullptr, 0, Z_FINISH);
    const std::uint64_t size = member_.size();
    if (size > 0xffffffffu || written_ - memberStart_ > 0xffffffffu)
        throw std::runtime_error(name_ + ": an entry of more than 4 GiB, more than a rawlog's gzip member holds");
    const auto put32 = [this](std::size_t at, std::uint64_t v) {
        for (int i = 0; i < 4; ++i) member_[at + std::size_t(i)] = static_cast<unsigned char>(v >> (8 * i));
    };
    put32(16, size);  // 10 bytes of header, XLEN, SI1 SI2 LEN: then the subfield's data
    put32(20, memberEntries_);
    sink_(member_.data(), member_.size());
    member_.clear();
    startMember();
}

void GzipOutputStream::endEntry() {
    if (memberBytes_ == 0) return;
    ++memberEntries_;
    if (written_ - memberStart_ >= memberBytes_) closeMember();
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
        if (const std::size_t n = sizeof out - z->avail_out) emit(out, n);
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
    if (memberBytes_ > 0) {
        if (memberEntries_ > 0 || written_ > memberStart_) closeMember();
        closeMember();  // the empty member that marks the end: a file cut at a member's end is not whole
    } else {
        flushPending();
        pump(nullptr, 0, Z_FINISH);
    }
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
