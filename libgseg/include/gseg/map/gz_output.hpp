#pragma once
/// \file gz_output.hpp
/// A gzip output stream for MRPT archives that checks every write and the close. MRPT 2.5.8's
/// CFileGZOutputStream does not report a failed close, so a full disk gave a truncated rawlog and
/// exit code 0.

#include <mrpt/io/CStream.h>

#include <cstdint>
#include <string>

namespace gseg::map {

class CheckedGzOutput : public ::mrpt::io::CStream {
public:
    /// Creates `path` (gzip, level 1: fast); errors name `name` (default: the path; e.g. the final
    /// name of a temporary file). Throws std::runtime_error.
    explicit CheckedGzOutput(const std::string& path, const std::string& name = "");
    /// Closes without checking: call close() to know the file is complete.
    ~CheckedGzOutput() override;
    CheckedGzOutput(const CheckedGzOutput&) = delete;
    CheckedGzOutput& operator=(const CheckedGzOutput&) = delete;

    /// Throws std::runtime_error naming the file and the reason if not everything was written.
    size_t Write(const void* buffer, size_t count) override;
    /// Flushes and closes; throws std::runtime_error naming the file and the reason on failure.
    void close();

    size_t Read(void*, size_t) override;                       ///< throws: write-only
    uint64_t Seek(int64_t, CStream::TSeekOrigin = sFromBeginning) override;  ///< throws: not seekable
    uint64_t getTotalBytesCount() const override { return written_; }       ///< uncompressed bytes written
    uint64_t getPosition() const override { return written_; }

private:
    std::string name_;
    void* gz_ = nullptr;  ///< gzFile
    uint64_t written_ = 0;
    [[noreturn]] void fail(const std::string& what);
};

}  // namespace gseg::map
