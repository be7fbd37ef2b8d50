#include <gseg/io/temporary_cleanup.hpp>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <dirent.h>
#include <map>
#include <mutex>
#include <stdexcept>
#include <sys/types.h>
#include <sys/stat.h>
#include <unistd.h>

namespace gseg::io {
namespace {

// --- The registry of temporaries, read by the signal handler ------------------------------------
// Fixed storage only: the handler may not allocate. A slot is 0 (free), 1 (being filled) or 2
// (holds a path to remove). 1024 slots of 4 KiB stay untouched (no memory) until used.
constexpr int kSlots = 1024;
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
    throw std::runtime_error(path + ": more than " + std::to_string(kSlots) + " temporary outputs open at once");
}

// --- Signals held back while a set of outputs is put in place -----------------------------------
std::atomic<int> g_deferring{0};
std::atomic<int> g_pending{0};

// --- What the process is doing, and who it is (for the handler's message) -----------------------
char g_tool[64] = "gseg";
char g_activity[2][256] = {{0}, {0}};
std::atomic<int> g_activityIndex{0};
std::mutex g_activityMutex;

void put(const char* s) {
    ssize_t ignored = ::write(STDERR_FILENO, s, std::strlen(s));
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

bool isTermination(int sig) { return std::find(std::begin(kTerminationSignals), std::end(kTerminationSignals), sig) != std::end(kTerminationSignals); }

extern "C" void cleanupHandler(int sig) {
    const int savedErrno = errno;
    if (isTermination(sig)) {
        // Published before the check: a SignalDeferral ending meanwhile sees it and raises it again.
        g_pending.store(sig);
        if (g_deferring.load() > 0) {
            errno = savedErrno;
            return;
        }
        g_pending.store(0);
    }
    int removed = 0;
    for (Slot& s : g_slots)
        if (s.state.load() == 2 && ::unlink(s.path) == 0) ++removed;
    put("\n");
    put(g_tool);
    put(isTermination(sig) ? ": interrupted (" : ": crashed (");
    put(signalName(sig));
    put(")");
    const char* activity = g_activity[g_activityIndex.load()];
    if (activity[0]) {
        put(" while ");
        put(activity);
    }
    put(removed ? "; temporary outputs removed\n" : "\n");
    // The default action ends the process once this handler returns (the signal is blocked until
    // then; a crash re-executes the faulting instruction and ends it as well).
    struct sigaction dfl {};
    dfl.sa_handler = SIG_DFL;
    sigemptyset(&dfl.sa_mask);
    ::sigaction(sig, &dfl, nullptr);
    ::raise(sig);
    errno = savedErrno;
}

std::once_flag g_installed;

// --- Side files: names, and the ones of dead processes ------------------------------------------
std::string hostTag() {
    char host[256] = {0};
    if (::gethostname(host, sizeof host - 1) != 0) return "host";
    std::string tag;
    for (const char* c = host; *c && tag.size() < 32; ++c)
        if (std::isalnum(static_cast<unsigned char>(*c))) tag += *c;  // no '-': it separates the fields
    return tag.empty() ? "host" : tag;
}

const std::string& thisHost() {
    static const std::string host = hostTag();
    return host;
}

constexpr std::size_t kNameChars = 200;  // of the output's name in a side file's (NAME_MAX is 255)

std::pair<std::string, std::string> splitPath(const std::string& path) {
    const auto slash = path.find_last_of('/');
    if (slash == std::string::npos) return {"", path};
    return {path.substr(0, slash + 1), path.substr(slash + 1)};
}

bool processRuns(long pid) { return pid > 0 && (::kill(pid_t(pid), 0) == 0 || errno == EPERM); }

// The output name a side file (`.<name>.gseg-<host>-<pid>-<n>.<tmp|bak>`) of a dead process of
// this host belongs to, or "" if it is none.
std::string staleOwner(const std::string& entry) {
    if (entry.size() < 6 || entry[0] != '.') return "";
    const std::string kind = entry.substr(entry.size() - 4);
    if (kind != ".tmp" && kind != ".bak" && kind != ".set") return "";
    const std::string tag = ".gseg-" + thisHost() + "-";
    const std::size_t at = entry.rfind(tag);
    if (at == std::string::npos || at < 1) return "";
    const std::string rest = entry.substr(at + tag.size(), entry.size() - 4 - at - tag.size());  // <pid>-<n>
    const std::size_t dash = rest.find('-');
    if (dash == std::string::npos || dash == 0 || dash + 1 >= rest.size() ||
        rest.find_first_not_of("0123456789") != dash || rest.find_first_not_of("0123456789", dash + 1) != std::string::npos)
        return "";
    const long pid = std::strtol(rest.substr(0, dash).c_str(), nullptr, 10);
    if (pid == long(::getpid()) || processRuns(pid)) return "";
    return entry.substr(1, at - 1);
}

/// Rolls back the set a dead run was putting in place (its journal, see commitTogether() in
/// atomic_file.cpp): each replaced file gets its kept-aside previous version back, each new file
/// that was placed is removed; then the journal goes. Lines: "R\t<file>\t<bak>" (replaced) or
/// "N\t<file>\t<temporary>" (new). A journal only exists while a set is incomplete.
void rollBackJournal(const std::string& journal) {
    std::string text;
    if (FILE* f = std::fopen(journal.c_str(), "rb")) {
        char buf[4096];
        for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) text.append(buf, n);
        std::fclose(f);
    }
    std::size_t at = 0;
    while (at < text.size()) {
        std::size_t end = text.find('\n', at);
        if (end == std::string::npos) break;  // a journal is complete before any rename (written, then renamed in place)
        const std::string line = text.substr(at, end - at);
        at = end + 1;
        const std::size_t t1 = line.find('\t'), t2 = line.find('\t', t1 == std::string::npos ? 0 : t1 + 1);
        if (line.size() < 2 || t1 != 1 || t2 == std::string::npos) continue;
        const std::string file = line.substr(2, t2 - 2), side = line.substr(t2 + 1);
        if (line[0] == 'R') {
            // The previous version: back in place (a no-op where the link was made but the rename not).
            struct stat st {};
            if (::lstat(side.c_str(), &st) == 0 && std::rename(side.c_str(), file.c_str()) == 0) ::unlink(side.c_str());
        } else if (line[0] == 'N') {
            struct stat st {};
            if (::lstat(side.c_str(), &st) != 0) ::unlink(file.c_str());  // its temporary is gone: it was placed
            else ::unlink(side.c_str());
        }
    }
    ::unlink(journal.c_str());
}

std::mutex g_staleMutex;
// folder -> output name (as in side-file names) -> stale side files; each folder read once.
std::map<std::string, std::map<std::string, std::vector<std::string>>> g_stale;

}  // namespace

TemporaryRegistration::TemporaryRegistration(const std::string& path) : slot_(registerTemporary(path)) {}

TemporaryRegistration::~TemporaryRegistration() {
    if (slot_ >= 0) g_slots[slot_].state.store(0);
}

SignalDeferral::SignalDeferral() { g_deferring.fetch_add(1); }

SignalDeferral::~SignalDeferral() {
    if (g_deferring.fetch_sub(1) == 1)
        if (const int sig = g_pending.exchange(0)) ::raise(sig);
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
        for (int sig : kTerminationSignals) sigaddset(&sa.sa_mask, sig);  // one handler at a time
        sa.sa_flags = SA_ONSTACK;
        for (int sig : kTerminationSignals) {
            struct sigaction old {};
            ::sigaction(sig, nullptr, &old);
            if (old.sa_handler != SIG_IGN) ::sigaction(sig, &sa, nullptr);
        }
        sa.sa_flags = SA_ONSTACK | SA_RESETHAND;
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

std::string sideFilePath(const std::string& path, const char* kind) {
    static std::atomic<unsigned> counter{0};
    const auto [dir, name] = splitPath(path);
    return dir + "." + name.substr(0, kNameChars) + ".gseg-" + thisHost() + "-" + std::to_string(::getpid()) + "-" +
           std::to_string(counter.fetch_add(1)) + "." + kind;
}

std::size_t removeStaleTemporaries(const std::string& path) noexcept {
    try {
        const auto [dir, name] = splitPath(path);
        std::lock_guard<std::mutex> lock(g_staleMutex);
        auto folder = g_stale.find(dir);
        if (folder == g_stale.end()) {
            folder = g_stale.emplace(dir, std::map<std::string, std::vector<std::string>>{}).first;
            std::vector<std::string> journals;
            if (DIR* d = ::opendir(dir.empty() ? "." : dir.c_str())) {
                while (const dirent* e = ::readdir(d)) {
                    const std::string owner = staleOwner(e->d_name);
                    if (owner.empty()) continue;
                    const std::string entry = e->d_name;
                    if (entry.compare(entry.size() - 4, 4, ".set") == 0) journals.push_back(dir + entry);
                    else folder->second[owner].push_back(dir + entry);
                }
                ::closedir(d);
            }
            // A dead run's incomplete set: rolled back (previous versions restored) before its
            // side files are removed below.
            for (const std::string& j : journals) rollBackJournal(j);
        }
        const auto stale = folder->second.find(name.substr(0, kNameChars));
        if (stale == folder->second.end()) return 0;
        std::size_t removed = 0;
        for (const std::string& f : stale->second) removed += ::unlink(f.c_str()) == 0;
        folder->second.erase(stale);
        return removed;
    } catch (...) {
        return 0;
    }
}

}  // namespace gseg::io
