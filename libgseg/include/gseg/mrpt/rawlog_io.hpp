#pragma once
/// \file rawlog_io.hpp
/// Streaming access to MRPT rawlogs (plain or gzip, both layouts: observations only, and
/// CSensoryFrame + CActionCollection pairs). Objects are read one at a time: constant memory.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace mrpt::serialization {
class CSerializable;
}
namespace mrpt::io {
class CStream;
}
namespace gseg::io {
class AtomicFile;
}

namespace gseg::mrpt {

/// The one rawlog reader: pulls the top-level objects of an MRPT rawlog (plain or gzip, both
/// layouts) one at a time, from a file, a pipe, a FIFO or /dev/stdin, in constant memory. A short
/// read inside an entry is an error (MRPT 2.5.8 trusts the size fields of a cut file: found by
/// fuzz_rawlog), never a smaller object. The entry being read is also the activity named by the
/// crash message of gseg::io::installTemporaryCleanup() (MRPT's deserializer trusts the size fields
/// of its input: a corrupt file can crash it).
///
/// A rawlog file written by RawlogWriter (gzip members with gseg's size field, gzip_stream.hpp) is
/// read member by member, its members are inflated (libdeflate, CRC-32 checked) on decode threads
/// ahead of next(), a few members in flight, and next() deserialises their objects from memory, in
/// file order. Other rawlogs (plain, one gzip stream, pipes) are read serially.
class RawlogReader {
public:
    /// Opens `path`. Throws std::runtime_error naming it if it cannot be opened or is a folder.
    /// `decodeThreads`: threads inflating gseg's gzip members; 0: the cores this process may use.
    explicit RawlogReader(const std::string& path, unsigned decodeThreads = 0);
    /// Reads from an open stream (plain or already decompressed); `name` stands for it in messages.
    RawlogReader(::mrpt::io::CStream& stream, std::string name);
    ~RawlogReader();
    RawlogReader(const RawlogReader&) = delete;
    RawlogReader& operator=(const RawlogReader&) = delete;

    /// The next object, or nullptr at the end of the file. Throws std::runtime_error naming the
    /// file and the entry index (and the class MRPT was reading, with its reason in one line) if an
    /// entry is corrupt or truncated (rawlogReadError()).
    std::shared_ptr<::mrpt::serialization::CSerializable> next();
    /// Index of the object next() returned last (0-based).
    std::size_t index() const { return index_ - 1; }
    /// Fraction of the file read so far (compressed bytes for gzip), 0..1; 0 for a pipe.
    double fraction() const;
    /// Threads inflating gzip members ahead of next(); 0 when the rawlog is read serially.
    unsigned decodeThreads() const;

private:
    std::shared_ptr<::mrpt::serialization::CSerializable> nextOfMembers();
    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::string name_;
    std::size_t index_ = 0;
};

/// Called with the index and the object of each entry; returns false to stop.
using RawlogVisitor =
    std::function<bool(std::size_t, const std::shared_ptr<::mrpt::serialization::CSerializable>&)>;

/// Calls `visit(entryIndex, object)` for every top-level object of the rawlog, in order, until the
/// end of the file or until `visit` returns false (a RawlogReader's loop). Throws as RawlogReader.
void forEachRawlogEntry(const std::string& path, const RawlogVisitor& visit);

/// The same from an open stream (plain or already decompressed); `name` stands for it in messages.
void forEachRawlogEntry(::mrpt::io::CStream& stream, const std::string& name, const RawlogVisitor& visit);

/// The one-line message for entry `index` of the rawlog `name` that MRPT could not read (`e`). A
/// file whose first entry is no serialized MRPT object at all (a text file, another format) "is
/// not an MRPT rawlog"; otherwise the entry, the class being read and MRPT's reason ("corrupt or
/// truncated", or a class this program does not know).
std::string rawlogReadError(const std::string& name, std::size_t index, const std::exception& e);

/// The one rawlog writer: a gzip rawlog written completely or not at all. Objects are serialized
/// by MRPT and compressed by GzipOutputStream into a gseg::io::AtomicFile, so every write and the
/// close are checked (MRPT's CFileGZOutputStream ignores a failed final flush: a full disk gave a
/// truncated file and exit 0). Nothing appears at `path` before commit(); a writer destroyed
/// without commit() leaves nothing behind. A pipe or /dev/stdout is streamed into.
class RawlogWriter {
public:
    /// Creates the temporary output; throws std::runtime_error naming `path` if it cannot.
    explicit RawlogWriter(const std::string& path);
    /// Writes into `file`, a member of a gseg::io::AtomicFileSet committed with others (e.g. the
    /// rawlog and the simple map of kitti2rawlog): finish() here, then commit the set.
    explicit RawlogWriter(gseg::io::AtomicFile& file);
    ~RawlogWriter();
    RawlogWriter(const RawlogWriter&) = delete;
    RawlogWriter& operator=(const RawlogWriter&) = delete;

    /// Appends one object (an observation, a sensory frame, an action collection, ...). Throws
    /// std::runtime_error naming the file and the reason (e.g. "No space left on device").
    void write(const ::mrpt::serialization::CSerializable& object);

    /// Ends the gzip stream. Throws std::runtime_error.
    void finish();
    /// finish(), then puts the file in place (a writer of its own file only). Throws std::runtime_error.
    void commit();

    std::size_t entries() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace gseg::mrpt
