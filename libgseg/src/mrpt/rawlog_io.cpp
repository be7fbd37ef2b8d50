#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/gzip_stream.hpp>
#include <gseg/mrpt/rawlog_io.hpp>
#include <gseg/ordered_pipeline.hpp>

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/io/CStream.h>
#include <mrpt/serialization/CArchive.h>

#include <libdeflate.h>
#include <sys/mman.h>
#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <sys/stat.h>
#include <thread>

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

// ---- Rawlogs of gzip members (GzipOutputStream's rawlog layout), decoded several at once ----
namespace {

using ObjectPtr = ::mrpt::serialization::CSerializable::Ptr;
constexpr std::size_t kHeader = GzipOutputStream::kMemberHeaderBytes;

std::uint32_t le32(const unsigned char* p) { return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[3]) << 24; }

/// The size and entry count of gseg's member header `h` (kHeader bytes), or false if it is none:
/// gzip, deflate, FLG exactly FEXTRA, XLEN 12 holding the one subfield 'G','S' of LEN 8.
bool memberHeader(const unsigned char* h, std::uint32_t& size, std::uint32_t& entries) {
    static const unsigned char lead[4] = {0x1f, 0x8b, 8, 4}, sub[6] = {12, 0, 'G', 'S', 8, 0};
    if (std::memcmp(h, lead, 4) != 0 || std::memcmp(h + 10, sub, 6) != 0) return false;
    size = le32(h + 16), entries = le32(h + 20);
    return true;
}

/// Bytes in pages of their own (mmap), returned to the system when freed, and reused while the
/// reader reads (PagePool): the members' bytes are made on one thread and freed on another, and
/// glibc's per-thread heaps kept them (rawlog-octomap's peak was 15-25 MB higher on a 10-scan
/// drive); fresh pages for every member cost their page faults (reading took twice as long).
struct Unmap {
    std::size_t bytes = 0;
    void operator()(unsigned char* p) const { ::munmap(p, bytes); }
};
using Pages = std::unique_ptr<unsigned char[], Unmap>;

Pages mapPages(std::size_t bytes) {
    bytes = std::max<std::size_t>(bytes, 1);
    void* p = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    return Pages(static_cast<unsigned char*>(p), Unmap{bytes});
}

/// The buffers of the members in flight, reused: no more than were in flight at once.
class PagePool {
public:
    /// A buffer of at least `bytes`.
    Pages take(std::size_t bytes) {
        std::lock_guard<std::mutex> lock(m_);
        for (auto it = free_.begin(); it != free_.end(); ++it)
            if (it->get_deleter().bytes >= bytes) {
                Pages p = std::move(*it);
                free_.erase(it);
                return p;
            }
        if (!free_.empty()) free_.pop_back();  // too small: unmapped, a bigger one instead
        return mapPages(bytes + bytes / 4);
    }
    void give(Pages p) {
        if (!p) return;
        std::lock_guard<std::mutex> lock(m_);
        free_.push_back(std::move(p));
    }
    /// Unmaps the buffers not in use (at the end of the file).
    void clear() {
        std::lock_guard<std::mutex> lock(m_);
        free_.clear();
    }

private:
    std::mutex m_;
    std::vector<Pages> free_;
};

/// One gzip member as read from the file (compressed).
struct Member {
    Pages bytes;
    std::size_t size = 0;      ///< [bytes] of `bytes`
    std::uint64_t offset = 0;  ///< [bytes] where it starts in the file
    std::size_t first = 0;     ///< index of its first entry in the file
    std::uint32_t entries = 0;
};

/// A member inflated (on a decode thread), or what was wrong with it.
struct Decoded {
    Pages data;                             ///< its serialised entries
    std::size_t size = 0;                   ///< [bytes] of them
    Member member;                          ///< its place and size in the file (without its compressed bytes)
    std::string error;                      ///< the whole message, naming its first entry
};

std::string entryError(const std::string& name, std::size_t index, const std::string& reason) {
    return name + ": entry " + std::to_string(index) + " is corrupt or truncated (" + reason + ")";
}

/// Reads the members of a rawlog in gseg's layout one after the other: the compressed bytes only.
class MemberFile {
public:
    MemberFile(std::FILE* f, std::string name, std::uint64_t fileSize) : f_(f), name_(std::move(name)), fileSize_(fileSize) {}
    PagePool* pool = nullptr;  ///< where the members' buffers come from
    ~MemberFile() { std::fclose(f_); }
    MemberFile(const MemberFile&) = delete;
    MemberFile& operator=(const MemberFile&) = delete;

    /// The next member; false at the end of the file after the empty end member. Throws
    /// std::runtime_error naming the entry if the file ends early or a member has no size field.
    bool read(Member& m) {
        unsigned char header[kHeader];
        const std::size_t got = std::fread(header, 1, kHeader, f_);
        if (got == 0 && std::feof(f_)) {
            if (atEndMember_) return false;
            throw std::runtime_error(entryError(name_, first_, "the file ends at byte " + std::to_string(offset_) +
                                                                    " without its end member: truncated"));
        }
        std::uint32_t size = 0;
        if (got < kHeader) fail("the file ends inside a gzip member header at byte " + std::to_string(offset_) + ": truncated");
        if (!memberHeader(header, size, m.entries))
            fail("byte " + std::to_string(offset_) + " is not the start of a gzip member with gseg's size field");
        const std::string at = "the gzip member at byte " + std::to_string(offset_) + " has a size field of " + std::to_string(size) + " bytes";
        if (size < kHeader + 10) fail(at + ": a wrong size field");
        if (offset_ + size > fileSize_)  // never allocated: the file is not that long
            fail(at + ", past the file's end at byte " + std::to_string(fileSize_) + ": truncated, or a wrong size field");
        m.bytes = pool->take(size), m.size = size;
        std::memcpy(m.bytes.get(), header, kHeader);
        if (std::fread(m.bytes.get() + kHeader, 1, size - kHeader, f_) != size - kHeader)
            fail(std::ferror(f_) ? std::string("read failed: ") + std::strerror(errno)
                                 : "the file ends inside the gzip member at byte " + std::to_string(offset_) + ": truncated");
        m.offset = offset_, m.first = first_;
        offset_ += size, first_ += m.entries;
        atEndMember_ = m.entries == 0;
        return true;
    }

private:
    [[noreturn]] void fail(const std::string& reason) const { throw std::runtime_error(entryError(name_, first_, reason)); }
    std::FILE* f_;
    std::string name_;
    std::uint64_t fileSize_;
    std::uint64_t offset_ = 0;
    std::size_t first_ = 0;
    bool atEndMember_ = false;
};

/// Inflates `m` into `out` (libdeflate, which checks the trailer's CRC-32 and size); "" or what is wrong.
std::string inflateMember(const Member& m, PagePool& pool, Pages& out, std::size_t& size) {
    size = le32(m.bytes.get() + m.size - 4);
    if (size / 1100 > m.size) return "its trailer gives " + std::to_string(size) + " bytes, more than deflate makes of " + std::to_string(m.size);
    out = pool.take(size);
    std::unique_ptr<libdeflate_decompressor, void (*)(libdeflate_decompressor*)> d(libdeflate_alloc_decompressor(), libdeflate_free_decompressor);
    if (!d) throw std::bad_alloc();
    std::size_t in = 0, made = 0;
    const auto r = libdeflate_gzip_decompress_ex(d.get(), m.bytes.get(), m.size, out.get(), size, &in, &made);
    if (r == LIBDEFLATE_INSUFFICIENT_SPACE || (r == LIBDEFLATE_SUCCESS && made != size))
        return "it does not inflate to the " + std::to_string(size) + " bytes its trailer gives: damaged, or a wrong size field";
    if (r != LIBDEFLATE_SUCCESS) return "it does not inflate, or its CRC-32 does not match: damaged";
    if (in != m.size) return "its size field gives " + std::to_string(m.size) + " bytes, the gzip member ends after " + std::to_string(in);
    return "";
}

/// Inflates member `m` of the rawlog `name` (on a decode thread). Deserialising stays with next():
/// the objects are then allocated by the thread that frees them (glibc keeps a heap per thread, and
/// objects made on the decode threads raised rawlog-octomap's peak by 15-80 MB).
Decoded decodeMember(Member m, PagePool& pool, const std::string& name) {
    Decoded out;
    try {
        if (const std::string bad = inflateMember(m, pool, out.data, out.size); !bad.empty())
            out.error = entryError(name, m.first, "the gzip member at byte " + std::to_string(m.offset) + ": " + bad);
    } catch (const std::exception& e) {  // e.g. out of memory
        out.error = entryError(name, m.first, "the gzip member at byte " + std::to_string(m.offset) + ": " + e.what());
    }
    pool.give(std::move(m.bytes));  // the compressed bytes are done with
    out.member = std::move(m);
    return out;
}

struct Stopped {};

/// Reads the members on a thread of its own, inflates them on `threads` workers (gseg::runOrdered)
/// and hands them over in file order: at most threads + 2 members in memory (in the pipeline, one
/// inflated and waiting, the one next() deserialises).
class MemberPipeline {
public:
    MemberPipeline(std::unique_ptr<MemberFile> file, std::string name, unsigned threads)
        : thread_([this, file = std::move(file), name = std::move(name), threads]() mutable { run(*file, name, threads); }) {}
    ~MemberPipeline() {
        {
            std::lock_guard<std::mutex> lock(m_);
            closing_ = true;
        }
        changed_.notify_all();
        thread_.join();
    }
    MemberPipeline(const MemberPipeline&) = delete;
    MemberPipeline& operator=(const MemberPipeline&) = delete;

    /// Takes back the buffer of a member next() has read.
    void recycle(Pages p) { pool_.give(std::move(p)); }
    /// Unmaps the buffers kept for reuse: the reading is over.
    void release() { pool_.clear(); }

    /// The next member in file order; false at the end. Throws what reading the file threw.
    bool pop(Decoded& out) {
        std::unique_lock<std::mutex> lock(m_);
        changed_.wait(lock, [&] { return !ready_.empty() || done_; });
        if (ready_.empty()) {
            if (!error_.empty()) throw std::runtime_error(error_);
            return false;
        }
        out = std::move(ready_.front());
        ready_.pop_front();
        changed_.notify_all();
        return true;
    }

private:
    void run(MemberFile& file, const std::string& name, unsigned threads) {
        file.pool = &pool_;
        try {
            runOrdered<Member, Decoded>([&](Member& m) { return file.read(m); },
                                        [&](unsigned, Member& m) { return decodeMember(std::move(m), pool_, name); },
                                        [&](std::size_t, Decoded& d) { hand(d); }, PipelineOptions{threads, threads});
        } catch (const Stopped&) {
        } catch (const std::exception& e) {
            std::lock_guard<std::mutex> lock(m_);
            error_ = e.what();
        }
        std::lock_guard<std::mutex> lock(m_);
        done_ = true;
        changed_.notify_all();
    }
    void hand(Decoded& d) {
        std::unique_lock<std::mutex> lock(m_);
        changed_.wait(lock, [&] { return closing_ || ready_.empty(); });
        if (closing_) throw Stopped{};
        const bool failed = !d.error.empty();
        ready_.push_back(std::move(d));
        changed_.notify_all();
        if (failed) throw Stopped{};  // nothing after an unreadable entry is read
    }

    std::mutex m_;
    std::condition_variable changed_;
    std::deque<Decoded> ready_;  // decoded, not yet taken by pop(): one at most
    std::string error_;
    bool done_ = false, closing_ = false;
    PagePool pool_;
    std::thread thread_;  // last: starts once the rest is built
};

}  // namespace

struct RawlogReader::Impl {
    std::unique_ptr<GzipInputStream> file;  // when reading a path serially
    std::unique_ptr<ExactReads> exact;
    std::unique_ptr<::mrpt::serialization::CArchive> archive;
    // A rawlog of gseg's gzip members (a regular file): inflated ahead of next(), which
    // deserialises the member `current` through memory, exact and archive
    std::unique_ptr<MemberPipeline> members;
    Decoded current;
    std::unique_ptr<::mrpt::io::CMemoryStream> memory;
    std::uint32_t taken = 0;  // entries of `current` read
    std::string failed;       // the error next() threw: thrown again
    double size = 0;        // [bytes] of the file
    unsigned threads = 0;
};

namespace {

void refuseFolder(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) throw std::runtime_error(path + ": is a folder, not a rawlog");
}

/// `path` opened if it is a regular file that starts with gseg's member header; null otherwise.
std::unique_ptr<MemberFile> openMembers(const std::string& path, double& size) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return nullptr;
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) return nullptr;  // the serial path says why
    unsigned char h[kHeader];
    std::uint32_t memberSize = 0, entries = 0;
    if (std::fread(h, 1, kHeader, f) != kHeader || !memberHeader(h, memberSize, entries) || std::fseek(f, 0, SEEK_SET) != 0) {
        std::fclose(f);
        return nullptr;
    }
    size = double(st.st_size);
    return std::make_unique<MemberFile>(f, path, std::uint64_t(st.st_size));
}

}  // namespace

RawlogReader::RawlogReader(const std::string& path, unsigned decodeThreads) : impl_(std::make_unique<Impl>()), name_(path) {
    refuseFolder(path);
    if (auto members = openMembers(path, impl_->size)) {
        impl_->threads = decodeThreads > 0 ? decodeThreads : gseg::usableCores();
        ::mrpt::rtti::registerAllPendingClasses();  // before the decode threads look classes up
        impl_->members = std::make_unique<MemberPipeline>(std::move(members), path, impl_->threads);
        return;
    }
    impl_->file = std::make_unique<GzipInputStream>(path);
    impl_->exact = std::make_unique<ExactReads>(*impl_->file);
    impl_->archive = std::make_unique<::mrpt::serialization::CArchiveStreamBase<ExactReads>>(*impl_->exact);
}

RawlogReader::RawlogReader(::mrpt::io::CStream& stream, std::string name) : impl_(std::make_unique<Impl>()), name_(std::move(name)) {
    impl_->exact = std::make_unique<ExactReads>(stream);
    impl_->archive = std::make_unique<::mrpt::serialization::CArchiveStreamBase<ExactReads>>(*impl_->exact);
}

RawlogReader::~RawlogReader() = default;

std::shared_ptr<::mrpt::serialization::CSerializable> RawlogReader::next() {
    if (impl_->members) return nextOfMembers();
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

std::shared_ptr<::mrpt::serialization::CSerializable> RawlogReader::nextOfMembers() {
    Impl& r = *impl_;
    auto fail = [&](const std::string& message) {
        r.failed = message;
        throw std::runtime_error(message);
    };
    if (!r.failed.empty()) throw std::runtime_error(r.failed);
    const auto at = [&] { return "the gzip member at byte " + std::to_string(r.current.member.offset); };
    while (r.taken == r.current.member.entries) {  // the member is read: the next one
        if (r.memory && r.memory->getPosition() != r.current.size)
            fail(entryError(name_, index_, at() + " holds more than the " + std::to_string(r.taken) + " entries its header counts"));
        r.memory.reset();
        r.members->recycle(std::move(r.current.data));
        if (!r.members->pop(r.current)) {
            r.members->release();
            return nullptr;
        }
        if (!r.current.error.empty()) fail(r.current.error);
        r.taken = 0;
        r.memory = std::make_unique<::mrpt::io::CMemoryStream>();
        r.memory->assignMemoryNotOwn(r.current.data.get(), r.current.size);
        r.exact = std::make_unique<ExactReads>(*r.memory);
        r.archive = std::make_unique<::mrpt::serialization::CArchiveStreamBase<ExactReads>>(*r.exact);
    }
    gseg::io::setActivity("reading entry " + std::to_string(index_) + " of " + name_);
    ::mrpt::serialization::CSerializable::Ptr obj;
    try {
        *r.archive >> obj;
    } catch (const ::mrpt::serialization::CExceptionEOF&) {
        fail(entryError(name_, index_, at() + " ends after " + std::to_string(r.taken) + " of the " + std::to_string(r.current.member.entries) +
                                           " entries its header counts"));
    } catch (const std::exception& e) {
        fail(rawlogReadError(name_, index_, e));
    }
    if (!obj) fail(name_ + ": entry " + std::to_string(index_) + " is an empty object");
    ++r.taken, ++index_;
    return obj;
}

double RawlogReader::fraction() const {
    const Impl& r = *impl_;
    if (!r.members) return r.file ? r.file->fraction() : 0.0;
    // Compressed bytes: the member's start, and of its bytes the share deserialised
    const double read = r.memory && r.current.size > 0 ? double(r.memory->getPosition()) / double(r.current.size) : 1.0;
    return r.size > 0 ? std::min(1.0, (double(r.current.member.offset) + double(r.current.member.size) * read) / r.size) : 0.0;
}

unsigned RawlogReader::decodeThreads() const { return impl_->threads; }

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
    explicit Impl(gseg::io::AtomicFile& f) : stream(f, GzipOutputStream::kRawlogMemberBytes), archive(::mrpt::serialization::archiveFrom(stream)) {}
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
        impl_->stream.endEntry();
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
