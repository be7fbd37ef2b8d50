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

namespace gseg::mrpt {

/// Calls `visit(entryIndex, object)` for every top-level object of the rawlog, in order, until the
/// end of the file or until `visit` returns false. Throws std::runtime_error naming the file and
/// the entry index if the file cannot be opened or an entry is corrupt or truncated.
void forEachRawlogEntry(const std::string& path,
                        const std::function<bool(std::size_t, const std::shared_ptr<::mrpt::serialization::CSerializable>&)>& visit);

}  // namespace gseg::mrpt
