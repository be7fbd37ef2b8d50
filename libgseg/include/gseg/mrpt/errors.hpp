#pragma once
/// \file errors.hpp
/// One-line reasons from MRPT's exceptions. MRPT's `what()` starts with the banner line
/// `==== MRPT exception ====` and carries the reason on later lines (`Message: ...`), nested once
/// per rethrow, followed by locations and a backtrace; printing the first line says nothing.

#include <exception>
#include <string>

namespace gseg::mrpt {

/// The reason of `e` in one line: for an MRPT exception its innermost `Message:` (or the first line
/// that is neither banner, location nor backtrace); for any other exception its first line.
std::string errorReason(const std::exception& e);

/// The same for the text of an exception.
std::string errorReason(const std::string& what);

}  // namespace gseg::mrpt
