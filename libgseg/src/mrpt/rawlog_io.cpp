#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/errors.hpp>
#include <gseg/mrpt/rawlog_io.hpp>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/serialization/CArchive.h>

#include <stdexcept>
#include <sys/stat.h>

namespace gseg::mrpt {
namespace {

// The class MRPT was reading when an entry failed: the first "parsing typed object 'X'" of its
// nested messages that names a class rather than the stream.
std::string classBeingRead(const std::string& what) {
    const std::string tag = "parsing typed object '";
    for (std::size_t at = what.find(tag); at != std::string::npos; at = what.find(tag, at + 1)) {
        const std::size_t b = at + tag.size(), e = what.find('\'', b);
        const std::string name = what.substr(b, e == std::string::npos ? 0 : e - b);
        if (!name.empty() && name.find(' ') == std::string::npos) return name;
    }
    return "";
}

}  // namespace

void forEachRawlogEntry(::mrpt::io::CStream& stream, const std::string& name, const RawlogVisitor& visit) {
    auto archive = ::mrpt::serialization::archiveFrom(stream);
    for (std::size_t index = 0;; ++index) {
        ::mrpt::serialization::CSerializable::Ptr obj;
        gseg::io::setActivity("reading entry " + std::to_string(index) + " of " + name);
        try {
            archive >> obj;
        } catch (const ::mrpt::serialization::CExceptionEOF&) {
            return;  // clean end of the file
        } catch (const std::exception& e) {
            const std::string cls = classBeingRead(e.what());
            throw std::runtime_error(name + ": entry " + std::to_string(index) + (cls.empty() ? "" : " (" + cls + ")") +
                                     (index == 0 ? " is unreadable, not an MRPT rawlog? (" : " is corrupt or truncated (") +
                                     errorReason(e) + ")");
        }
        if (!obj) throw std::runtime_error(name + ": entry " + std::to_string(index) + " is an empty object");
        if (!visit(index, obj)) return;
    }
}

void forEachRawlogEntry(const std::string& path, const RawlogVisitor& visit) {
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) throw std::runtime_error(path + ": is a folder, not a rawlog");
    ::mrpt::io::CFileGZInputStream file;
    bool opened = false;
    try {
        opened = file.open(path);
    } catch (const std::exception&) {  // MRPT reports a missing file with a multi-line trace
    }
    if (!opened) throw std::runtime_error(path + ": cannot open the rawlog");
    forEachRawlogEntry(file, path, visit);
}

}  // namespace gseg::mrpt
