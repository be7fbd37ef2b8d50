#include <support/paths.hpp>

#include <sys/stat.h>

namespace gseg::test {

std::string sharedData(const std::string& relative) {
    const std::string path = std::string(GSEG_SHARED_DIR) + "/data/" + relative;
    struct stat st {};
    return ::stat(path.c_str(), &st) == 0 ? path : std::string();
}

std::string missingDataMessage(const std::string& relative) {
    return "shared data " + std::string(GSEG_SHARED_DIR) + "/data/" + relative +
           " is absent (a checkout outside the project's workspace): skipped";
}

std::string tool(const std::string& name) { return std::string(GSEG_BINARY_DIR) + "/bin/" + name; }

}  // namespace gseg::test
