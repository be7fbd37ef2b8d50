#pragma once
/// \file png.hpp
/// The PNG encoder of every gseg picture (zlib): MRPT's CImage::saveToFile reports success on a
/// truncated file.

#include <string>

namespace mrpt::img {
class CImage;
}

namespace gseg::mrpt {

/// PNG bytes of an 8-bit grey or colour image, encoded by gseg (zlib).
std::string encodePng(const ::mrpt::img::CImage& image);

/// Writes `image` as a PNG through gseg::io::AtomicFile: every write and the close checked, so a
/// full disk is an error and leaves nothing (MRPT's CImage::saveToFile reports success on a
/// truncated file). Throws std::runtime_error naming `path`.
void writePng(const std::string& path, const ::mrpt::img::CImage& image);

}  // namespace gseg::mrpt
