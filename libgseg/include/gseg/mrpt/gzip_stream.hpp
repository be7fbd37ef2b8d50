#pragma once
/// \file gzip_stream.hpp
/// The one gzip writer: an MRPT output stream that compresses what MRPT serialises (rawlogs,
/// .3Dscene, .simplemap) into a sink, an AtomicFile or memory, checking every write. MRPT 2.5.8's
/// CFileGZOutputStream does not report a failed final flush, so a full disk gave a truncated file
/// and exit code 0. Level 1 (as MRPT writes) and no time stamp: the same objects give the same
/// bytes. The output is a sequence of gzip members, each compressed in one call of libdeflate
/// (3.6 times faster than zlib's streaming deflate at level 1 on a drive's scene, and 8 % smaller);
/// zlib, zcat, MRPT's CFileGZInputStream and every gzip reader read concatenated members as one
/// stream.
///
/// Scenes and simple maps: members of kMemberBytes uncompressed bytes, with the plain header.
/// Rawlogs (RawlogWriter) are written as a sequence of gzip members of whole entries, each member's
/// header carrying gseg's FEXTRA subfield 'G','S' (LEN 8: uint32 LE size of the member in bytes,
/// header and trailer included; uint32 LE number of entries in it), the idea of BGZF's BSIZE. The
/// last member is an empty one (0 entries): the end mark. Concatenated members are one standard
/// gzip stream for every other reader (zlib, zcat, MRPT); gseg's RawlogReader finds the members
/// without inflating and decodes several at once.

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
    /// Compresses into `sink` (which throws on failure); `name` stands for it in messages;
    /// `memberBytes` as below.
    GzipOutputStream(Sink sink, std::string name, std::size_t memberBytes = 0);
    /// Compresses into `file` (not committed here: finish(), then commit the file or its set).
    /// `memberBytes` 0: one gzip member (scenes, simple maps); > 0: the rawlog layout, a member is
    /// closed at endEntry() once it holds at least this many uncompressed bytes.
    explicit GzipOutputStream(gseg::io::AtomicFile& file, std::size_t memberBytes = 0);
    ~GzipOutputStream() override;
    GzipOutputStream(const GzipOutputStream&) = delete;
    GzipOutputStream& operator=(const GzipOutputStream&) = delete;

    size_t Write(const void* buffer, size_t count) override;
    /// Ends the gzip stream (its last block and trailer go to the sink). Throws std::runtime_error.
    void finish();
    /// The rawlog layout: one entry (a whole object) has been written; closes the member if it is
    /// big enough. No-op for one member. Throws std::runtime_error (a member over 4 GiB).
    void endEntry();

    static constexpr std::size_t kRawlogMemberBytes = 1u << 20;  ///< [bytes] uncompressed, per rawlog member (members in flight: memory)
    static constexpr std::size_t kMemberHeaderBytes = 24;         ///< gzip header with gseg's subfield
    static constexpr std::size_t kMemberBytes = 4u << 20;         ///< [bytes] uncompressed, per member of a scene or simple map

    size_t Read(void*, size_t) override;                                     ///< throws: write-only
    uint64_t Seek(int64_t, CStream::TSeekOrigin = sFromBeginning) override;  ///< throws: not seekable
    uint64_t getTotalBytesCount() const override { return written_; }       ///< uncompressed bytes written
    uint64_t getPosition() const override { return written_; }
    std::string getStreamDescription() const override { return "gzip " + name_; }

private:
    void closeMember();
    Sink sink_;
    std::string name_;
    void* compressor_ = nullptr;        ///< libdeflate_compressor
    uint64_t written_ = 0;
    bool finished_ = false;
    std::size_t memberBytes_ = 0;       ///< 0: members of kMemberBytes; else the rawlog layout
    std::vector<unsigned char> in_;     ///< the member being gathered, uncompressed
    std::vector<unsigned char> out_;    ///< a member compressed (header, deflate stream, trailer)
    std::uint32_t memberEntries_ = 0;   ///< rawlog layout: entries in the member being gathered
};

/// Serialises `object` (a scene, a simple map) gzip-compressed into `file` (not committed).
void writeGzipObject(gseg::io::AtomicFile& file, const ::mrpt::serialization::CSerializable& object);

}  // namespace gseg::mrpt
