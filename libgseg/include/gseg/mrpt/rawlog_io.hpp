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

namespace gseg::mrpt {

/// Called with the index and the object of each entry; returns false to stop.
using RawlogVisitor =
    std::function<bool(std::size_t, const std::shared_ptr<::mrpt::serialization::CSerializable>&)>;

/// Calls `visit(entryIndex, object)` for every top-level object of the rawlog, in order, until the
/// end of the file or until `visit` returns false. Throws std::runtime_error naming the file and
/// the entry index (and the class MRPT was reading, with its reason in one line) if the file cannot
/// be opened or an entry is corrupt or truncated. The entry being read is also the activity named
/// by the crash message of gseg::io::installTemporaryCleanup() (MRPT's deserializer trusts the size
/// fields of its input: a corrupt file can crash it).
void forEachRawlogEntry(const std::string& path, const RawlogVisitor& visit);

/// The same from an open stream (plain or already decompressed); `name` stands for it in messages.
void forEachRawlogEntry(::mrpt::io::CStream& stream, const std::string& name, const RawlogVisitor& visit);

/// The one-line message for entry `index` of the rawlog `name` that MRPT could not read (`e`). A
/// file whose first entry is no serialized MRPT object at all (a text file, another format) "is
/// not an MRPT rawlog"; otherwise the entry, the class being read and MRPT's reason ("corrupt or
/// truncated", or a class this program does not know).
std::string rawlogReadError(const std::string& name, std::size_t index, const std::exception& e);

/// A gzip rawlog written completely or not at all: objects are serialized by MRPT, compressed
/// with zlib and written through gseg::io::AtomicFile, so every write and the close are checked
/// (MRPT's CFileGZOutputStream ignores a failed final flush: a full disk gave a truncated file and
/// exit 0). Nothing appears at `path` before commit(); a writer destroyed without commit() leaves
/// nothing behind.
class RawlogWriter {
public:
    /// Creates the temporary output; throws std::runtime_error naming `path` if it cannot.
    explicit RawlogWriter(const std::string& path);
    ~RawlogWriter();
    RawlogWriter(const RawlogWriter&) = delete;
    RawlogWriter& operator=(const RawlogWriter&) = delete;

    /// Appends one object (an observation, a sensory frame, an action collection, ...). Throws
    /// std::runtime_error naming the file and the reason (e.g. "No space left on device").
    void write(const ::mrpt::serialization::CSerializable& object);

    /// Finishes the gzip stream and renames the file into place. Throws std::runtime_error.
    void commit();

    std::size_t entries() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace gseg::mrpt
