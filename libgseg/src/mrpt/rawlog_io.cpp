#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/rawlog_io.hpp>

#include <mrpt/io/CStream.h>
#include <mrpt/serialization/CArchive.h>

#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <sys/stat.h>

namespace gseg::mrpt {
namespace {

// The class MRPT was reading when an entry failed: the first "parsing typed object 'X'" of its
// nested messages that names a class rather than the stream.
std::string classBeingRead(const std::string& what) {
    const std::string tag = "parsing typed object '";
    for (std::size_t at = what.find(tag); at != std::string::npos; at = what.find(tag, at + 1)) {
        const std::size_t b = at + tag.size(), e = what.find('\'', b);
        const std::string name = what.substr(b, e == std::string::npos ? 0 : e - b);
        if (!name.empty() && name.find(' ') == std::string::npos) return name;
    }
    return "";
}

// The class named by MRPT's "Stored object has class 'X' which is not registered", if X looks
// like a C++ class name (a rawlog with a class this program does not link); "" otherwise (random
// bytes read as a name).
std::string unknownClass(const std::string& what) {
    const std::string tag = "has class '";
    const std::size_t at = what.find(tag);
    if (at == std::string::npos || what.find("not registered") == std::string::npos) return "";
    const std::size_t b = at + tag.size(), e = what.find('\'', b);
    const std::string name = what.substr(b, e == std::string::npos ? 0 : e - b);
    const bool looksLikeOne = !name.empty() && name.size() < 200 && (std::isalpha(static_cast<unsigned char>(name[0])) || name[0] == '_') &&
                              std::all_of(name.begin(), name.end(), [](char c) {
                                  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == ':';
                              });
    return looksLikeOne ? name : "";
}

}  // namespace

std::string rawlogReadError(const std::string& name, std::size_t index, const std::exception& e) {
    const std::string what = e.what(), cls = classBeingRead(what), unknown = unknownClass(what);
    const std::string entry = name + ": entry " + std::to_string(index);
    if (!unknown.empty())
        return entry + " is a " + unknown + ", a class this program does not know (" + errorReason(e) + ")";
    const bool truncated = what.find("ends inside an entry") != std::string::npos;
    if (index == 0 && cls.empty() && !truncated)
        return name + ": not an MRPT rawlog (a rawlog is a stream of serialized MRPT objects, optionally gzip-compressed; "
                      "this file does not start with one)";
    return entry + (cls.empty() ? "" : " (" + cls + ")") + " is corrupt or truncated (" + errorReason(e) + ")";
}

namespace {

// Reads that deliver everything asked for, or nothing at a clean end. MRPT 2.5.8's
// CArchive::ReadBuffer only fails when a read returns 0 bytes: a file cut inside a size field
// returns the few bytes left, and the rest of the field stays garbage (found by fuzz_rawlog: a
// cut CActionCollection asked for 2.8 GB). Here a short read is an error.
class ExactReads : public ::mrpt::io::CStream {
public:
    explicit ExactReads(::mrpt::io::CStream& inner) : inner_(inner) {}

    size_t Read(void* buffer, size_t count) override {
        size_t done = 0;
        while (done < count) {
            const size_t n = inner_.Read(static_cast<char*>(buffer) + done, count - done);
            if (n == 0) break;
            done += n;
        }
        if (done != 0 && done < count)
            throw std::runtime_error("the file ends inside an entry (" + std::to_string(done) + " of " +
                                     std::to_string(count) + " bytes of a field): truncated");
        return done;
    }
    size_t Write(const void*, size_t) override { throw std::logic_error("ExactReads is read-only"); }
    uint64_t Seek(int64_t, TSeekOrigin) override { throw std::logic_error("ExactReads cannot seek"); }
    uint64_t getTotalBytesCount() const override { return inner_.getTotalBytesCount(); }
    uint64_t getPosition() const override { return inner_.getPosition(); }

private:
    ::mrpt::io::CStream& inner_;
};

}  // namespace

void forEachRawlogEntry(::mrpt::io::CStream& stream, const std::string& name, const RawlogVisitor& visit) {
    ExactReads exact(stream);
    auto archive = ::mrpt::serialization::archiveFrom(exact);
    for (std::size_t index = 0;; ++index) {
        ::mrpt::serialization::CSerializable::Ptr obj;
        gseg::io::setActivity("reading entry " + std::to_string(index) + " of " + name);
        try {
            archive >> obj;
        } catch (const ::mrpt::serialization::CExceptionEOF&) {
            return;  // clean end of the file
        } catch (const std::exception& e) {
            throw std::runtime_error(rawlogReadError(name, index, e));
        }
        if (!obj) throw std::runtime_error(name + ": entry " + std::to_string(index) + " is an empty object");
        if (!visit(index, obj)) return;
    }
}

namespace {

// An MRPT input stream over zlib's gzread: gzip or plain files, and pipes (MRPT's
// CFileGZInputStream refuses a named pipe or /dev/stdin).
class GzipInputStream : public ::mrpt::io::CStream {
public:
    explicit GzipInputStream(const std::string& path) : path_(path), file_(gzopen(path.c_str(), "rb")) {
        if (!file_) throw std::runtime_error(path + ": cannot open the rawlog (" + std::strerror(errno) + ")");
        gzbuffer(file_, 1 << 17);
    }
    ~GzipInputStream() override { gzclose_r(file_); }

    size_t Read(void* buffer, size_t count) override {
        size_t done = 0;
        while (done < count) {
            const int n = gzread(file_, static_cast<char*>(buffer) + done, unsigned(std::min<size_t>(count - done, 1u << 30)));
            if (n < 0) {
                int err = 0;
                const char* msg = gzerror(file_, &err);
                throw std::runtime_error(path_ + ": read failed (" + (err == Z_ERRNO ? std::strerror(errno) : msg) + ")");
            }
            if (n == 0) break;  // end of the data: MRPT turns a short read into its EOF exception
            done += size_t(n);
        }
        position_ += done;
        return done;
    }
    size_t Write(const void*, size_t) override { throw std::logic_error("GzipInputStream is read-only"); }
    uint64_t Seek(int64_t, TSeekOrigin) override { throw std::logic_error("GzipInputStream cannot seek"); }
    uint64_t getTotalBytesCount() const override { return 0; }
    uint64_t getPosition() const override { return position_; }
    std::string getStreamDescription() const override { return "rawlog " + path_; }

private:
    std::string path_;
    gzFile file_;
    uint64_t position_ = 0;
};

}  // namespace

void forEachRawlogEntry(const std::string& path, const RawlogVisitor& visit) {
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) throw std::runtime_error(path + ": is a folder, not a rawlog");
    GzipInputStream file(path);
    forEachRawlogEntry(file, path, visit);
}

namespace {

// An MRPT output stream that gzips into an AtomicFile.
class GzipAtomicStream : public ::mrpt::io::CStream {
public:
    explicit GzipAtomicStream(const std::string& path) : file_(path) {
        // windowBits 15 + 16: gzip wrapper, which MRPT's readers detect; level 1 as MRPT writes.
        if (deflateInit2(&z_, 1, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK)
            throw std::runtime_error(path + ": cannot start the gzip compressor");
    }
    ~GzipAtomicStream() override { deflateEnd(&z_); }

    size_t Read(void*, size_t) override { throw std::logic_error("GzipAtomicStream is write-only"); }
    size_t Write(const void* buffer, size_t count) override {
        const auto* p = static_cast<const Bytef*>(buffer);
        for (size_t left = count; left > 0;) {
            const uInt chunk = uInt(std::min<size_t>(left, 1u << 30));
            pump(p, chunk, Z_NO_FLUSH);
            p += chunk, left -= chunk;
        }
        position_ += count;
        return count;
    }
    uint64_t Seek(int64_t, TSeekOrigin) override { throw std::logic_error("GzipAtomicStream cannot seek"); }
    uint64_t getTotalBytesCount() const override { return position_; }
    uint64_t getPosition() const override { return position_; }
    std::string getStreamDescription() const override { return "gzip rawlog " + file_.path(); }

    void commit() {
        pump(nullptr, 0, Z_FINISH);
        file_.commit();
    }

private:
    void pump(const Bytef* data, uInt size, int flush) {
        z_.next_in = const_cast<Bytef*>(data);
        z_.avail_in = size;
        for (;;) {
            Bytef out[1 << 16];
            z_.next_out = out;
            z_.avail_out = sizeof out;
            const int r = deflate(&z_, flush);
            if (r == Z_STREAM_ERROR) throw std::runtime_error(file_.path() + ": gzip compression failed");
            file_.write(out, sizeof out - z_.avail_out);
            if (flush == Z_FINISH ? r == Z_STREAM_END : z_.avail_out != 0) break;
        }
    }

    gseg::io::AtomicFile file_;
    z_stream z_{};
    uint64_t position_ = 0;
};

}  // namespace

struct RawlogWriter::Impl {
    explicit Impl(const std::string& path) : stream(path), archive(::mrpt::serialization::archiveFrom(stream)) {}
    GzipAtomicStream stream;
    ::mrpt::serialization::CArchiveStreamBase<GzipAtomicStream> archive;
    std::size_t entries = 0;
};

RawlogWriter::RawlogWriter(const std::string& path) : impl_(std::make_unique<Impl>(path)) {}
RawlogWriter::~RawlogWriter() = default;

void RawlogWriter::write(const ::mrpt::serialization::CSerializable& object) {
    try {
        impl_->archive << object;
    } catch (const std::exception& e) {
        throw std::runtime_error(errorReason(e));  // MRPT wraps our AtomicFile error in its banner
    }
    ++impl_->entries;
}

void RawlogWriter::commit() { impl_->stream.commit(); }

std::size_t RawlogWriter::entries() const { return impl_->entries; }

}  // namespace gseg::mrpt
