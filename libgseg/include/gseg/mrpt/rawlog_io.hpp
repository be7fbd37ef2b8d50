#pragma once
/// \file rawlog_io.hpp
/// Streaming access to MRPT rawlogs (plain or gzip, both layouts: observations only, and
/// CSensoryFrame + CActionCollection pairs). Objects are read one at a time: constant memory.

#include <cstddef>
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

}  // namespace gseg::mrpt
