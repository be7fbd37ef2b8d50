#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/gzip_stream.hpp>

#include <mrpt/serialization/CArchive.h>

#include <libdeflate.h>

#include <algorithm>
#include <stdexcept>

namespace gseg::mrpt {

GzipOutputStream::GzipOutputStream(Sink sink, std::string name, std::size_t memberBytes)
    : sink_(std::move(sink)), name_(std::move(name)), memberBytes_(memberBytes) {
    compressor_ = libdeflate_alloc_compressor(1);  // level 1, as MRPT writes
    if (!compressor_) throw std::runtime_error(name_ + ": cannot start the gzip compressor");
    in_.reserve(memberBytes_ > 0 ? memberBytes_ + (memberBytes_ >> 2) : kMemberBytes);
}

GzipOutputStream::GzipOutputStream(gseg::io::AtomicFile& file, std::size_t memberBytes)
    : GzipOutputStream([&file](const void* d, std::size_t n) { file.write(d, n); }, file.path(), memberBytes) {}

GzipOutputStream::~GzipOutputStream() { libdeflate_free_compressor(static_cast<libdeflate_compressor*>(compressor_)); }

// One member: the gzip header (no name, no time stamp; XFL 4, the fastest level, and OS 3, Unix, as
// zlib writes them), in the rawlog layout with the subfield 'G','S' (the member's size in bytes and
// its entry count), then the deflate stream of in_, its CRC-32 and its size.
void GzipOutputStream::closeMember() {
    const bool rawlog = memberBytes_ > 0;
    if (rawlog && in_.size() > 0xffffffffu)
        throw std::runtime_error(name_ + ": an entry of more than 4 GiB, more than a rawlog's gzip member holds");
    auto* c = static_cast<libdeflate_compressor*>(compressor_);
    const std::size_t header = rawlog ? kMemberHeaderBytes : 10;
    out_.resize(header + libdeflate_deflate_compress_bound(c, in_.size()) + 8);
    const std::size_t packed = libdeflate_deflate_compress(c, in_.data(), in_.size(), out_.data() + header, out_.size() - header - 8);
    if (packed == 0) throw std::runtime_error(name_ + ": gzip compression failed");
    out_.resize(header + packed + 8);
    const auto put32 = [this](std::size_t at, std::uint64_t v) {
        for (int i = 0; i < 4; ++i) out_[at + std::size_t(i)] = static_cast<unsigned char>(v >> (8 * i));
    };
    const unsigned char plain[10] = {0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 4, 3};
    std::copy(plain, plain + 10, out_.begin());
    if (rawlog) {
        if (out_.size() > 0xffffffffu)
            throw std::runtime_error(name_ + ": an entry of more than 4 GiB, more than a rawlog's gzip member holds");
        out_[3] = 4;  // FLG: FEXTRA
        const unsigned char extra[6] = {12, 0, 'G', 'S', 8, 0};  // XLEN 12; SI1 SI2, LEN 8
        std::copy(extra, extra + 6, out_.begin() + 10);
        put32(16, out_.size());
        put32(20, memberEntries_);
    }
    put32(header + packed, libdeflate_crc32(0, in_.data(), in_.size()));
    put32(header + packed + 4, in_.size());  // ISIZE: the size modulo 2^32
    sink_(out_.data(), out_.size());
    in_.clear();
    memberEntries_ = 0;
}

void GzipOutputStream::endEntry() {
    if (memberBytes_ == 0) return;
    ++memberEntries_;
    if (in_.size() >= memberBytes_) closeMember();
}

size_t GzipOutputStream::Write(const void* buffer, size_t count) {
    if (finished_) throw std::logic_error(name_ + ": write after the gzip stream was finished");
    const auto* p = static_cast<const unsigned char*>(buffer);
    written_ += count;
    if (memberBytes_ > 0) {  // the rawlog layout: a member holds whole entries (endEntry())
        in_.insert(in_.end(), p, p + count);
        return count;
    }
    for (std::size_t left = count; left > 0;) {
        const std::size_t n = std::min(left, kMemberBytes - in_.size());
        in_.insert(in_.end(), p, p + n);
        p += n, left -= n;
        if (in_.size() == kMemberBytes) closeMember();
    }
    return count;
}

void GzipOutputStream::finish() {
    if (finished_) return;
    if (memberBytes_ > 0) {
        if (memberEntries_ > 0 || !in_.empty()) closeMember();
        closeMember();  // the empty member that marks the end: a file cut at a member's end is not whole
    } else if (!in_.empty() || written_ == 0) {
        closeMember();  // (an empty stream is one empty member)
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
