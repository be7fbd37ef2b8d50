#include <gseg/map/rawlog_reader.hpp>

#include <gseg/map/output_files.hpp>
#include <gseg/mrpt/rawlog_io.hpp>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/serialization/CArchive.h>

#include <stdexcept>

namespace gseg::map {

struct RawlogReader::Impl {
    ::mrpt::io::CFileGZInputStream file;
    std::unique_ptr<::mrpt::serialization::CArchive> archive;
    double size = 0;
};

RawlogReader::RawlogReader(const std::string& path) : impl_(std::make_unique<Impl>()), path_(path) {
    bool opened = false;
    try {
        opened = impl_->file.open(path);
    } catch (const std::exception&) {  // MRPT reports a missing file with a multi-line trace
    }
    if (!opened) throw std::runtime_error(path + ": cannot open the rawlog");
    impl_->archive = std::make_unique<::mrpt::serialization::CArchiveStreamBase<::mrpt::io::CFileGZInputStream>>(impl_->file);
    impl_->size = double(impl_->file.getTotalBytesCount());
}

RawlogReader::~RawlogReader() = default;

std::shared_ptr<::mrpt::serialization::CSerializable> RawlogReader::next() {
    ::mrpt::serialization::CSerializable::Ptr obj;
    try {
        *impl_->archive >> obj;
    } catch (const ::mrpt::serialization::CExceptionEOF&) {
        return nullptr;  // clean end of the file
    } catch (const std::exception& e) {
        throw std::runtime_error(gseg::mrpt::rawlogReadError(path_, index_, e));
    }
    ++index_;
    return obj;
}

double RawlogReader::fraction() const {
    return impl_->size > 0 ? std::min(1.0, double(impl_->file.getPosition()) / impl_->size) : 0.0;
}

}  // namespace gseg::map
