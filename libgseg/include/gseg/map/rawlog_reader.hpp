#pragma once
/// \file rawlog_reader.hpp
/// Pulls the top-level objects of an MRPT rawlog (plain or gzip, both layouts) one at a time, and
/// says how far into the file it is: the map tools stream drives of any length in constant memory
/// and estimate the time left from it.

#include <cstddef>
#include <memory>
#include <string>

namespace mrpt::serialization {
class CSerializable;
}

namespace gseg::map {

class RawlogReader {
public:
    /// Throws std::runtime_error naming the file if it cannot be opened.
    explicit RawlogReader(const std::string& path);
    ~RawlogReader();

    /// The next object, or nullptr at the end of the file. Throws std::runtime_error naming the
    /// file and the entry index if an entry is corrupt or truncated.
    std::shared_ptr<::mrpt::serialization::CSerializable> next();
    /// Index of the object next() returned last (0-based).
    std::size_t index() const { return index_ - 1; }
    /// Fraction of the file read so far (compressed bytes for gzip), 0..1.
    double fraction() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::string path_;
    std::size_t index_ = 0;
};

}  // namespace gseg::map
