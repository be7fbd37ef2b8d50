#pragma once
/// \file png.hpp
/// The PNG encoder of every gseg picture (zlib): MRPT's CImage::saveToFile reports success on a
/// truncated file.

#include <string>

namespace mrpt::img {
class CImage;
}

namespace gseg::mrpt {

/// PNG bytes of an 8-bit grey or colour image, encoded by gseg (zlib). Written to a file with
/// gseg::io::writeFileAtomic() or an AtomicFile: every write and the close checked, so a full
/// disk is an error and leaves nothing.
std::string encodePng(const ::mrpt::img::CImage& image);

}  // namespace gseg::mrpt
