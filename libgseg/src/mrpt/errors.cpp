#include <gseg/mrpt/errors.hpp>

#include <sstream>

namespace gseg::mrpt {
namespace {

std::string trim(const std::string& s) {
    const auto b = s.find_first_not_of(" \t\r");
    if (b == std::string::npos) return "";
    return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

bool startsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

}  // namespace

std::string errorReason(const std::string& what) {
    std::istringstream in(what);
    std::string line, message, other;
    bool mrpt = false;
    while (std::getline(in, line)) {
        line = trim(line);
        if (line.empty()) continue;
        if (startsWith(line, "==== MRPT exception ====")) {
            mrpt = true;
            continue;
        }
        if (!mrpt) return line;  // not MRPT's format: the first line is the message
        if (startsWith(line, "Message:")) message = trim(line.substr(8));
        else if (other.empty() && !startsWith(line, "Location:") && !startsWith(line, "Call stack backtrace") &&
                 !startsWith(line, "Original exception") && !startsWith(line, "["))
            other = line;
    }
    if (!message.empty()) return message;
    return other.empty() ? "unknown error (no message)" : other;
}

std::string errorReason(const std::exception& e) { return errorReason(std::string(e.what())); }

}  // namespace gseg::mrpt
