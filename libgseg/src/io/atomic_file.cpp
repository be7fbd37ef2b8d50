#include <gseg/io/atomic_file.hpp>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace gseg::io {
namespace {

// --- The registry of temporaries, read by the signal handler ------------------------------------
// Fixed storage only: the handler may not allocate. A slot is 0 (free), 1 (being filled) or
// 2 (holds a path to remove).
constexpr int kSlots = 64;
constexpr std::size_t kPathBytes = 4096;
struct Slot {
    std::atomic<int> state{0};
    char path[kPathBytes];
};
Slot g_slots[kSlots];

int registerTemporary(const std::string& path) {
    if (path.size() >= kPathBytes) throw std::runtime_error(path + ": path too long for a temporary file");
    for (int i = 0; i < kSlots; ++i) {
        int expected = 0;
        if (g_slots[i].state.compare_exchange_strong(expected, 1)) {
            std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
            g_slots[i].state.store(2);
            return i;
        }
    }
    throw std::runtime_error(path + ": more than 64 temporary outputs open at once");
}

void unregisterTemporary(int slot) {
    if (slot >= 0) g_slots[slot].state.store(0);
}

// --- What the process is doing, and who it is (for the handler's message) -----------------------
char g_tool[64] = "gseg";
char g_activity[2][256] = {{0}, {0}};
std::atomic<int> g_activityIndex{0};
std::mutex g_activityMutex;

void put(const char* s) {
    const std::size_t n = std::strlen(s);
    ssize_t ignored = ::write(STDERR_FILENO, s, n);
    (void)ignored;
}

const char* signalName(int sig) {
    switch (sig) {
        case SIGINT: return "SIGINT";
        case SIGTERM: return "SIGTERM";
        case SIGHUP: return "SIGHUP";
        case SIGQUIT: return "SIGQUIT";
        case SIGPIPE: return "SIGPIPE";
        case SIGSEGV: return "SIGSEGV";
        case SIGBUS: return "SIGBUS";
        case SIGFPE: return "SIGFPE";
        case SIGILL: return "SIGILL";
        case SIGABRT: return "SIGABRT";
        default: return "a signal";
    }
}

const int kTerminationSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE};
const int kCrashSignals[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};

extern "C" void cleanupHandler(int sig) {
    const int savedErrno = errno;
    int removed = 0;
    for (Slot& s : g_slots)
        if (s.state.load() == 2 && ::unlink(s.path) == 0) ++removed;
    bool crash = false;
    for (int c : kCrashSignals) crash = crash || c == sig;
    put("\n");
    put(g_tool);
    put(crash ? ": crashed (" : ": interrupted (");
    put(signalName(sig));
    put(")");
    const char* activity = g_activity[g_activityIndex.load()];
    if (activity[0]) {
        put(" while ");
        put(activity);
    }
    put(removed ? "; temporary outputs removed\n" : "\n");
    errno = savedErrno;
    // SA_RESETHAND restored the default action; the signal is blocked until this handler returns,
    // then ends the process (a crash re-executes the faulting instruction and ends it as well).
    ::raise(sig);
}

std::once_flag g_installed;

}  // namespace

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
    const std::string base = path_ + ".tmp" + std::to_string(::getpid());
    for (int attempt = 0; fd_ < 0; ++attempt) {
        temp_ = attempt == 0 ? base : base + "." + std::to_string(attempt);
        slot_ = registerTemporary(temp_);
        fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd_ >= 0) break;
        const int err = errno;
        unregisterTemporary(slot_);
        slot_ = -1;
        if (err != EEXIST || attempt > 100)
            throw std::runtime_error(path_ + ": cannot create (" + std::strerror(err) + ")");
    }
}

AtomicFile::~AtomicFile() { discard(); }

TemporaryRegistration::TemporaryRegistration(const std::string& path) : slot_(registerTemporary(path)) {}

TemporaryRegistration::~TemporaryRegistration() { unregisterTemporary(slot_); }

void AtomicFile::discard() noexcept {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    if (slot_ >= 0) ::unlink(temp_.c_str());
    unregisterTemporary(slot_);
    slot_ = -1;
}

void AtomicFile::fail(const std::string& what, int err) {
    discard();
    throw std::runtime_error(path_ + ": " + what + " (" + std::strerror(err) + ")");
}

void AtomicFile::write(const void* data, std::size_t size) {
    if (fd_ < 0) throw std::logic_error(path_ + ": write after commit or failure");
    const char* p = static_cast<const char*>(data);
    while (size > 0) {
        const ssize_t n = ::write(fd_, p, size);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) fail("write failed after " + std::to_string(written_) + " bytes", n < 0 ? errno : EIO);
        p += n, size -= std::size_t(n), written_ += std::uint64_t(n);
    }
}

void AtomicFile::commit() {
    if (fd_ < 0) throw std::logic_error(path_ + ": commit after commit or failure");
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail("closing the written file failed", errno);
    if (std::rename(temp_.c_str(), path_.c_str()) != 0)
        fail("cannot rename the temporary file " + temp_ + " into place", errno);
    unregisterTemporary(slot_);
    slot_ = -1;
}

void writeFileAtomic(const std::string& path, const void* bytes, std::size_t size) {
    AtomicFile file(path);
    file.write(bytes, size);
    file.commit();
}

void installTemporaryCleanup(const std::string& toolName) {
    std::call_once(g_installed, [&] {
        std::strncpy(g_tool, toolName.c_str(), sizeof g_tool - 1);
        // A separate stack, so that a stack overflow still gets its temporaries removed.
        static char altStack[64 * 1024];
        stack_t ss{};
        ss.ss_sp = altStack;
        ss.ss_size = sizeof altStack;
        ::sigaltstack(&ss, nullptr);
        struct sigaction sa {};
        sa.sa_handler = cleanupHandler;
        sigemptyset(&sa.sa_mask);
        sa.sa_flags = SA_RESETHAND | SA_ONSTACK;
        for (int sig : kTerminationSignals) {
            struct sigaction old {};
            ::sigaction(sig, nullptr, &old);
            if (old.sa_handler != SIG_IGN) ::sigaction(sig, &sa, nullptr);
        }
        for (int sig : kCrashSignals) ::sigaction(sig, &sa, nullptr);
        ::signal(SIGXFSZ, SIG_IGN);
    });
}

void setActivity(const std::string& activity) {
    std::lock_guard<std::mutex> lock(g_activityMutex);
    const int next = 1 - g_activityIndex.load();
    const std::size_t n = std::min(activity.size(), sizeof g_activity[0] - 1);
    std::memcpy(g_activity[next], activity.data(), n);
    g_activity[next][n] = '\0';
    g_activityIndex.store(next);
}

std::vector<std::string> registeredTemporaries() {
    std::vector<std::string> out;
    for (const Slot& s : g_slots)
        if (s.state.load() == 2) out.emplace_back(s.path);
    return out;
}

void checkOutputsAreNotInputs(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs) {
    // Each path is looked at once (a run may name thousands of inputs and outputs).
    namespace fs = std::filesystem;
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
        if (FileId id; identity(out.path, id)) {  // an existing file: by device and inode (links too)
            if (const auto in = inputIds.find(id); in != inputIds.end())
                throw std::invalid_argument(out.argument + " " + out.path + " is the " + in->second->argument + " " +
                                            in->second->path + " (the same file): refusing to overwrite an input");
            if (const auto seen = outputIds.find(id); seen != outputIds.end()) throw twice(out, *seen->second);
            outputIds.emplace(id, &out);
        }
        if (const auto [seen, added] = outputNames.emplace(normal(out.path), &out); !added) throw twice(out, *seen->second);
    }
}

namespace {

/// Whether `folder` accepts a new file: one is made and removed. "" if so, else why not.
std::string cannotWriteIn(const std::string& folder) {
    const std::string probe = (std::filesystem::path(folder) / (".gseg-probe-" + std::to_string(::getpid()))).string();
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0600);
    if (fd < 0) return std::strerror(errno);
    ::close(fd);
    ::unlink(probe.c_str());
    return "";
}

}  // namespace

void checkOutputs(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs, OutputRules rules) {
    namespace fs = std::filesystem;
    checkOutputsAreNotInputs(inputs, outputs);
    std::set<std::string> writable;  // folders tried already (a run may write thousands of files into many)
    for (const NamedPath& out : outputs) {
        if (out.path.empty()) continue;
        const std::string what = out.argument + " " + out.path;
        std::error_code ec;
        if (fs::exists(fs::symlink_status(out.path, ec))) {
            if (fs::is_directory(out.path, ec)) throw std::invalid_argument(what + " is a folder, not a file");
            if (!rules.overwrite) throw std::invalid_argument(what + " exists: give -w (--overwrite) to replace it");
        }
        fs::path folder = fs::path(out.path).parent_path();
        if (folder.empty()) folder = ".";
        if (writable.count(folder.string())) continue;
        const std::string given = folder.string();
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
