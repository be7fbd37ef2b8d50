#include <gseg/mrpt/errors.hpp>
#include <gseg/text.hpp>

#include <sstream>

namespace gseg::mrpt {
std::string errorReason(const std::string& what) {
    // The innermost reason is the last "Message: ..." or the first line of a non-MRPT exception
    // that MRPT wrapped ("Original exception:" then its text).
    std::istringstream in(what);
    std::string line, reason, other;
    bool mrpt = false, afterOriginal = false;
    while (std::getline(in, line)) {
        line = trim(line);
        if (line.empty()) continue;
        if (startsWith(line, "==== MRPT exception ====")) {
            mrpt = true;
            afterOriginal = false;
            continue;
        }
        if (!mrpt) return line;  // not MRPT's format: the first line is the message
        if (startsWith(line, "Message:")) {
            reason = trim(line.substr(8));
        } else if (startsWith(line, "Original exception")) {
            afterOriginal = true;
            continue;
        } else if (afterOriginal) {
            reason = line;
        } else if (other.empty() && !startsWith(line, "Location:") && !startsWith(line, "Call stack backtrace") &&
                   !startsWith(line, "[")) {
            other = line;
        }
        afterOriginal = false;
    }
    if (!reason.empty()) return reason;
    return other.empty() ? "unknown error (no message)" : other;
}

std::string errorReason(const std::exception& e) { return errorReason(std::string(e.what())); }

}  // namespace gseg::mrpt
