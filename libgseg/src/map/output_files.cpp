#include <gseg/map/output_files.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace gseg::map {
namespace {

std::string besideWithPrefix(const std::string& path, const std::string& tag) {
    const auto slash = path.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
    const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
    return dir + "." + tag + std::to_string(::getpid()) + "_" + name;
}

std::string reason() { return std::strerror(errno); }

bool exists(const std::string& path) {
    struct stat st {};
    return ::lstat(path.c_str(), &st) == 0;
}

}  // namespace

std::string temporaryPathFor(const std::string& path) { return besideWithPrefix(path, "tmp"); }

void writeFileChecked(const std::string& path, const std::string& bytes) {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) throw std::runtime_error(path + ": cannot create (" + reason() + ")");
    const bool written = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size() && std::fflush(f) == 0;
    const std::string why = written ? "" : reason();
    const bool closed = std::fclose(f) == 0;
    if (!written || !closed) {
        const std::string detail = written ? reason() : why;
        std::remove(path.c_str());
        throw std::runtime_error(path + ": write failed (" + detail + ")");
    }
}

void writeFileChecked(const std::string& path, const std::function<void(std::ostream&)>& fill) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(path + ": cannot create (" + reason() + ")");
    errno = 0;
    fill(out);
    out.flush();
    const std::string why = errno ? reason() : "stream error";
    out.close();
    if (!out) {
        std::remove(path.c_str());
        throw std::runtime_error(path + ": write failed (" + why + ")");
    }
}

AtomicFiles::AtomicFiles(std::vector<std::string> paths) : paths_(std::move(paths)) {
    for (const auto& p : paths_) {
        temps_.push_back(temporaryPathFor(p));
        registered_.emplace_back(temps_.back());
    }
}

AtomicFiles::~AtomicFiles() {
    if (!committed_)
        for (const auto& t : temps_) std::remove(t.c_str());
}

void AtomicFiles::commit() {
    const std::size_t n = paths_.size();
    std::vector<std::string> backups(n);
    auto dropBackups = [&] {
        for (const auto& b : backups)
            if (!b.empty()) std::remove(b.c_str());
    };
    for (std::size_t i = 0; i < n; ++i) {  // keep the previous versions aside, nothing changed yet
        if (!exists(paths_[i])) continue;
        const std::string b = besideWithPrefix(paths_[i], "bak");
        if (::link(paths_[i].c_str(), b.c_str()) != 0) {
            const std::string why = reason();
            dropBackups();
            throw std::runtime_error(paths_[i] + ": cannot keep the previous version aside (" + why + "); nothing was replaced");
        }
        backups[i] = b;
    }
    for (std::size_t i = 0; i < n; ++i) {
        if (std::rename(temps_[i].c_str(), paths_[i].c_str()) == 0) continue;
        const std::string why = reason();
        for (std::size_t j = 0; j < i; ++j) {  // put back what was there before
            if (backups[j].empty()) std::remove(paths_[j].c_str());
            else if (std::rename(backups[j].c_str(), paths_[j].c_str()) == 0) backups[j].clear();
        }
        dropBackups();
        throw std::runtime_error(paths_[i] + ": cannot rename the temporary file into place (" + why +
                                 "); the previous files are unchanged");
    }
    committed_ = true;
    dropBackups();
}

}  // namespace gseg::map
