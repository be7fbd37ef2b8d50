#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/rawlog_io.hpp>

#include <mrpt/io/CStream.h>
#include <mrpt/serialization/CArchive.h>

#include <zlib.h>

#include <algorithm>
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

}  // namespace

void forEachRawlogEntry(::mrpt::io::CStream& stream, const std::string& name, const RawlogVisitor& visit) {
    auto archive = ::mrpt::serialization::archiveFrom(stream);
    for (std::size_t index = 0;; ++index) {
        ::mrpt::serialization::CSerializable::Ptr obj;
        gseg::io::setActivity("reading entry " + std::to_string(index) + " of " + name);
        try {
            archive >> obj;
        } catch (const ::mrpt::serialization::CExceptionEOF&) {
            return;  // clean end of the file
        } catch (const std::exception& e) {
            const std::string cls = classBeingRead(e.what());
            throw std::runtime_error(name + ": entry " + std::to_string(index) + (cls.empty() ? "" : " (" + cls + ")") +
                                     (index == 0 ? " is unreadable, not an MRPT rawlog? (" : " is corrupt or truncated (") +
                                     errorReason(e) + ")");
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
