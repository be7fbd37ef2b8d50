#include <gseg/mrpt/rawlog_io.hpp>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/serialization/CArchive.h>

#include <stdexcept>

namespace gseg::mrpt {

void forEachRawlogEntry(
    const std::string& path,
    const std::function<bool(std::size_t, const std::shared_ptr<::mrpt::serialization::CSerializable>&)>& visit) {
    ::mrpt::io::CFileGZInputStream file;
    bool opened = false;
    try {
        opened = file.open(path);
    } catch (const std::exception&) {  // MRPT reports a missing file with a multi-line trace
    }
    if (!opened) throw std::runtime_error(path + ": cannot open the rawlog");
    auto archive = ::mrpt::serialization::archiveFrom(file);
    for (std::size_t index = 0;; ++index) {
        ::mrpt::serialization::CSerializable::Ptr obj;
        try {
            archive >> obj;
        } catch (const ::mrpt::serialization::CExceptionEOF&) {
            return;  // clean end of the file
        } catch (const std::exception& e) {
            std::string what = e.what();
            const auto nl = what.find('\n');
            throw std::runtime_error(path + ": entry " + std::to_string(index) +
                                     " is corrupt or truncated (" + what.substr(0, nl) + ")");
        }
        if (!visit(index, obj)) return;
    }
}

}  // namespace gseg::mrpt
