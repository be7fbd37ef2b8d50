#include <gseg/io/output_checks.hpp>
#include <gseg/io/temporary_cleanup.hpp>

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;

namespace gseg::io {
namespace {

std::string folderOf(const std::string& path) {
    const fs::path folder = fs::path(path).parent_path();
    return folder.empty() ? "." : folder.string();
}

bool isDirectory(const std::string& path) {
    struct stat st {};
    return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

// The paths a chain of symbolic links passes, `path` first; at most 41 (more: a loop). The last
// one is no link: an existing file, a missing one, or a "pipe:[N]" that /proc/self/fd/N names.
std::vector<std::string> linkChain(const std::string& path) {
    std::vector<std::string> chain = {path};
    for (int hop = 0; hop < 40; ++hop) {
        char buf[4096];
        const ssize_t n = ::readlink(chain.back().c_str(), buf, sizeof buf - 1);
        if (n <= 0) break;
        const std::string next(buf, std::size_t(n));
        chain.push_back(next[0] == '/' ? next : (fs::path(chain.back()).parent_path() / next).string());
    }
    return chain;
}

// Paths that reach a process's own descriptors (/dev/stdout -> /proc/self/fd/1 -> pipe:[N]):
// written in place, whatever they lead to.
bool viaDescriptor(const std::string& path) {
    for (const std::string& p : linkChain(path))
        if (p.rfind("/proc/", 0) == 0 || p.rfind("/dev/fd/", 0) == 0 || p == "/dev/stdout" || p == "/dev/stderr")
            return true;
    return false;
}

std::mutex g_newMutex;
std::set<std::string> g_new;  // outputs checked without -w, by absolute normal path

std::string key(const std::string& path) {
    std::error_code ec;
    const fs::path abs = fs::absolute(path, ec);
    return (ec ? fs::path(path) : abs).lexically_normal().string();
}

}  // namespace

OutputTarget resolveOutput(const std::string& given) {
    if (given.empty()) throw std::invalid_argument("an output has an empty file name");
    OutputTarget t;
    t.given = given;
    t.file = given;
    struct stat st {};
    if (::stat(given.c_str(), &st) == 0) {
        if (S_ISDIR(st.st_mode)) throw std::invalid_argument(given + " is a folder, not a file");
        t.exists = true;
        t.stream = !S_ISREG(st.st_mode) || viaDescriptor(given);
        if (!t.stream) {
            std::error_code ec;
            const fs::path real = fs::canonical(given, ec);  // the file the links lead to
            if (!ec) t.file = real.string();
        }
        return t;
    }
    const int err = errno;
    if (err == ELOOP) throw std::invalid_argument(given + " is a loop of symbolic links");
    if (err != ENOENT) throw std::invalid_argument(given + ": " + std::strerror(err));
    // Missing, or a dangling symbolic link: the file its last link names is created.
    const std::vector<std::string> chain = linkChain(given);
    if (chain.size() > 40) throw std::invalid_argument(given + " is a loop of symbolic links");
    const std::string& p = chain.back();
    t.file = p;
    if (!isDirectory(folderOf(p)))
        throw std::invalid_argument(given + ": the folder " + folderOf(p) + " does not exist" +
                                    (p == given ? "" : " (the symbolic link leads to " + p + ")"));
    return t;
}

void checkOutputPrefix(const std::string& prefix) {
    if (prefix.empty()) throw std::invalid_argument("the output prefix is empty (it starts the name of every file written)");
    const std::string example = " (a prefix starts every file's name: out/map gives out/map_ground.bt, ...)";
    if (prefix.back() == '/') throw std::invalid_argument("the output prefix " + prefix + " ends in '/'" + example);
    struct stat st {};
    if (::stat(prefix.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
        throw std::invalid_argument("the output prefix " + prefix + " is " + (S_ISDIR(st.st_mode) ? "a folder" : "not a regular file") +
                                    example);
}

bool mustBeNew(const std::string& path) {
    std::lock_guard<std::mutex> lock(g_newMutex);
    return g_new.count(key(path)) > 0;
}

void writtenByThisProcess(const std::string& path) {
    std::lock_guard<std::mutex> lock(g_newMutex);
    g_new.erase(key(path));
}

void checkOutputsAreNotInputs(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs) {
    // Each path is looked at once (a run may name thousands of inputs and outputs).
    using FileId = std::pair<dev_t, ino_t>;
    auto identity = [](const std::string& p, FileId& id) {
        struct stat st {};
        if (::stat(p.c_str(), &st) != 0) return false;
        id = {st.st_dev, st.st_ino};
        return true;
    };
    std::map<std::string, fs::path> folders;  // canonical form of each output folder, found once
    auto normal = [&](const std::string& p) {
        const fs::path path(p), folder = path.parent_path();
        auto known = folders.find(folder.string());
        if (known == folders.end()) {
            std::error_code ec;
            const fs::path c = fs::weakly_canonical(fs::absolute(folder.empty() ? fs::path(".") : folder, ec), ec);
            known = folders.emplace(folder.string(), ec ? folder.lexically_normal() : c).first;
        }
        return (known->second / path.filename()).lexically_normal().string();
    };
    std::map<FileId, const NamedPath*> inputIds, outputIds;
    for (const NamedPath& in : inputs)
        if (FileId id; !in.path.empty() && identity(in.path, id)) inputIds.emplace(id, &in);
    std::map<std::string, const NamedPath*> outputNames;
    auto twice = [](const NamedPath& out, const NamedPath& earlier) {
        return std::invalid_argument(out.argument + " and " + earlier.argument + " name the same file " + out.path);
    };
    for (const NamedPath& out : outputs) {
        if (out.path.empty()) continue;
        struct stat st {};
        const bool special = ::stat(out.path.c_str(), &st) == 0 && !S_ISREG(st.st_mode);  // /dev/null twice is fine
        if (FileId id; !special && identity(out.path, id)) {  // an existing file: by device and inode (links too)
            if (const auto in = inputIds.find(id); in != inputIds.end())
                throw std::invalid_argument(out.argument + " " + out.path + " is the " + in->second->argument + " " +
                                            in->second->path + " (the same file): refusing to overwrite an input");
            if (const auto seen = outputIds.find(id); seen != outputIds.end()) throw twice(out, *seen->second);
            outputIds.emplace(id, &out);
        }
        if (special) continue;
        if (const auto [seen, added] = outputNames.emplace(normal(out.path), &out); !added) throw twice(out, *seen->second);
    }
}

namespace {

/// Whether `folder` accepts a new file: one is made and removed. "" if so, else why not.
std::string cannotWriteIn(const std::string& folder) {
    const std::string probe = (fs::path(folder) / (".gseg-probe-" + std::to_string(::getpid()))).string();
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0600);
    if (fd < 0) return std::strerror(errno);
    ::close(fd);
    ::unlink(probe.c_str());
    return "";
}

}  // namespace

void checkOutputs(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs, OutputRules rules) {
    // First, what a killed run left at these outputs: a half-committed set rolled back to the old
    // one (its journal), its temporaries removed; then the outputs are what they were before it.
    for (const NamedPath& out : outputs)
        if (!out.path.empty()) removeStaleTemporaries(out.path);
    checkOutputsAreNotInputs(inputs, outputs);
    std::set<std::string> writable;  // folders tried already (a run may write thousands of files into many)
    for (const NamedPath& out : outputs) {
        if (out.path.empty()) continue;
        const std::string what = out.argument + " " + out.path;
        struct stat st {};
        std::string file = out.path;
        if (::stat(out.path.c_str(), &st) == 0) {
            if (S_ISDIR(st.st_mode)) throw std::invalid_argument(what + " is a folder, not a file");
            if (!S_ISREG(st.st_mode) || viaDescriptor(out.path)) continue;  // a pipe, terminal or device: written into
            if (!rules.overwrite) throw std::invalid_argument(what + " exists: give -w (--overwrite) to replace it");
            std::error_code ec;
            if (const fs::path real = fs::canonical(out.path, ec); !ec) file = real.string();
        } else if (errno == ELOOP) {
            throw std::invalid_argument(what + " is a loop of symbolic links");
        } else {
            struct stat lst {};
            if (::lstat(out.path.c_str(), &lst) == 0 && S_ISLNK(lst.st_mode)) {
                try {
                    file = resolveOutput(out.path).file;  // a dangling link: its destination is made
                } catch (const std::invalid_argument& e) {
                    throw std::invalid_argument(out.argument + " " + e.what());
                }
            }
        }
        if (!rules.overwrite) {
            std::lock_guard<std::mutex> lock(g_newMutex);
            g_new.insert(key(out.path));
        }
        fs::path folder = fs::path(file).parent_path();
        if (folder.empty()) folder = ".";
        if (writable.count(folder.string())) continue;
        const std::string given = folder.string();
        std::error_code ec;
        while (rules.makeFolders && !fs::exists(folder, ec) && folder.parent_path() != folder)  // the one to make it in
            folder = folder.parent_path().empty() ? fs::path(".") : folder.parent_path();
        if (!fs::exists(folder, ec))
            throw std::invalid_argument(what + ": the folder " + folder.string() + " does not exist");
        if (!fs::is_directory(folder, ec))
            throw std::invalid_argument(what + ": " + folder.string() + " is not a folder");
        if (const std::string why = cannotWriteIn(folder.string()); !why.empty())
            throw std::invalid_argument(what + ": cannot write in the folder " + folder.string() + " (" + why + ")");
        writable.insert(given);
    }
}

}  // namespace gseg::io
