#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/gzip_stream.hpp>
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

namespace {

// An MRPT input stream over zlib's gzread: gzip or plain files, and pipes (MRPT's
// CFileGZInputStream refuses a named pipe or /dev/stdin).
class GzipInputStream : public ::mrpt::io::CStream {
public:
    explicit GzipInputStream(const std::string& path) : path_(path), file_(gzopen(path.c_str(), "rb")) {
        if (!file_) throw std::runtime_error(path + ": cannot open the rawlog (" + std::strerror(errno) + ")");
        gzbuffer(file_, 1 << 17);
        struct stat st {};
        if (::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode)) size_ = double(st.st_size);
    }
    /// Compressed bytes read so far over the file's size; 0 for a pipe.
    double fraction() const { return size_ > 0 ? std::min(1.0, double(gzoffset(file_)) / size_) : 0.0; }
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
    double size_ = 0;
};

}  // namespace

struct RawlogReader::Impl {
    std::unique_ptr<GzipInputStream> file;  // when reading a path
    std::unique_ptr<ExactReads> exact;
    std::unique_ptr<::mrpt::serialization::CArchive> archive;
};

namespace {

std::unique_ptr<GzipInputStream> openRawlog(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) throw std::runtime_error(path + ": is a folder, not a rawlog");
    return std::make_unique<GzipInputStream>(path);
}

}  // namespace

RawlogReader::RawlogReader(const std::string& path) : impl_(std::make_unique<Impl>()), name_(path) {
    impl_->file = openRawlog(path);
    impl_->exact = std::make_unique<ExactReads>(*impl_->file);
    impl_->archive = std::make_unique<::mrpt::serialization::CArchiveStreamBase<ExactReads>>(*impl_->exact);
}

RawlogReader::RawlogReader(::mrpt::io::CStream& stream, std::string name) : impl_(std::make_unique<Impl>()), name_(std::move(name)) {
    impl_->exact = std::make_unique<ExactReads>(stream);
    impl_->archive = std::make_unique<::mrpt::serialization::CArchiveStreamBase<ExactReads>>(*impl_->exact);
}

RawlogReader::~RawlogReader() = default;

std::shared_ptr<::mrpt::serialization::CSerializable> RawlogReader::next() {
    ::mrpt::serialization::CSerializable::Ptr obj;
    gseg::io::setActivity("reading entry " + std::to_string(index_) + " of " + name_);
    try {
        *impl_->archive >> obj;
    } catch (const ::mrpt::serialization::CExceptionEOF&) {
        return nullptr;  // clean end of the file
    } catch (const std::exception& e) {
        throw std::runtime_error(rawlogReadError(name_, index_, e));
    }
    if (!obj) throw std::runtime_error(name_ + ": entry " + std::to_string(index_) + " is an empty object");
    ++index_;
    return obj;
}

double RawlogReader::fraction() const { return impl_->file ? impl_->file->fraction() : 0.0; }

namespace {

void visitAll(RawlogReader& reader, const RawlogVisitor& visit) {
    while (auto obj = reader.next())
        if (!visit(reader.index(), obj)) return;
}

}  // namespace

void forEachRawlogEntry(const std::string& path, const RawlogVisitor& visit) {
    RawlogReader reader(path);
    visitAll(reader, visit);
}

void forEachRawlogEntry(::mrpt::io::CStream& stream, const std::string& name, const RawlogVisitor& visit) {
    RawlogReader reader(stream, name);
    visitAll(reader, visit);
}

struct RawlogWriter::Impl {
    explicit Impl(gseg::io::AtomicFile& f) : stream(f), archive(::mrpt::serialization::archiveFrom(stream)) {}
    std::unique_ptr<gseg::io::AtomicFile> own;  // the writer's own file, or none (a member of a set)
    GzipOutputStream stream;
    ::mrpt::serialization::CArchiveStreamBase<GzipOutputStream> archive;
    std::size_t entries = 0;
};

RawlogWriter::RawlogWriter(const std::string& path) {
    auto file = std::make_unique<gseg::io::AtomicFile>(path);
    impl_ = std::make_unique<Impl>(*file);
    impl_->own = std::move(file);
}

RawlogWriter::RawlogWriter(gseg::io::AtomicFile& file) : impl_(std::make_unique<Impl>(file)) {}

RawlogWriter::~RawlogWriter() = default;

void RawlogWriter::write(const ::mrpt::serialization::CSerializable& object) {
    try {
        impl_->archive << object;
    } catch (const std::exception& e) {
        throw std::runtime_error(errorReason(e));  // MRPT wraps our AtomicFile error in its banner
    }
    ++impl_->entries;
}

void RawlogWriter::finish() { impl_->stream.finish(); }

void RawlogWriter::commit() {
    if (!impl_->own) throw std::logic_error("RawlogWriter::commit: the file belongs to a set; finish() and commit the set");
    finish();
    impl_->own->commit();
}

std::size_t RawlogWriter::entries() const { return impl_->entries; }

}  // namespace gseg::mrpt
