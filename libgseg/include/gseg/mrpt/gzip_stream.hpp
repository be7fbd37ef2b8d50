#pragma once
/// \file gzip_stream.hpp
/// The one gzip writer: an MRPT output stream that compresses what MRPT serialises (rawlogs,
/// .3Dscene, .simplemap) with zlib into a sink, an AtomicFile or memory, checking every write.
/// MRPT 2.5.8's CFileGZOutputStream does not report a failed final flush, so a full disk gave a
/// truncated file and exit code 0. Level 1 and no time stamp, as MRPT writes: the same objects
/// give the same bytes.

#include <mrpt/io/CStream.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace mrpt::serialization {
class CSerializable;
}
namespace gseg::io {
class AtomicFile;
}

namespace gseg::mrpt {

class GzipOutputStream : public ::mrpt::io::CStream {
public:
    using Sink = std::function<void(const void*, std::size_t)>;
    /// Compresses into `sink` (which throws on failure); `name` stands for it in messages.
    GzipOutputStream(Sink sink, std::string name);
    /// Compresses into `file` (not committed here: finish(), then commit the file or its set).
    explicit GzipOutputStream(gseg::io::AtomicFile& file);
    ~GzipOutputStream() override;
    GzipOutputStream(const GzipOutputStream&) = delete;
    GzipOutputStream& operator=(const GzipOutputStream&) = delete;

    size_t Write(const void* buffer, size_t count) override;
    /// Ends the gzip stream (its last block and trailer go to the sink). Throws std::runtime_error.
    void finish();

    size_t Read(void*, size_t) override;                                     ///< throws: write-only
    uint64_t Seek(int64_t, CStream::TSeekOrigin = sFromBeginning) override;  ///< throws: not seekable
    uint64_t getTotalBytesCount() const override { return written_; }       ///< uncompressed bytes written
    uint64_t getPosition() const override { return written_; }
    std::string getStreamDescription() const override { return "gzip " + name_; }

private:
    void pump(const void* data, std::size_t size, int flush);
    void flushPending();
    static constexpr std::size_t kPending = 1 << 16;  ///< [bytes] gathered before deflate()
    Sink sink_;
    std::string name_;
    void* z_ = nullptr;  ///< z_stream
    /// Input gathered before it goes to zlib: MRPT serialises a scene field by field (about 36
    /// writes of 1-4 bytes per triangle), and one deflate() call per write cost more than the
    /// compression (drive 09's scene: 1.5 G instructions, most of them in deflate()'s entry).
    std::vector<char> pending_;
    uint64_t written_ = 0;
    bool finished_ = false;
};

/// Serialises `object` (a scene, a simple map) gzip-compressed into `file` (not committed).
void writeGzipObject(gseg::io::AtomicFile& file, const ::mrpt::serialization::CSerializable& object);

}  // namespace gseg::mrpt
