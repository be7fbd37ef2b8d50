#pragma once
/// \file temporary_cleanup.hpp
/// What an interrupted or crashed run leaves behind: nothing. Temporaries of outputs sit in a
/// registry that a signal handler reads: after installTemporaryCleanup(), an interrupted run
/// (SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE) or a crash (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT)
/// removes them before the process ends. While a set of outputs is being put in place
/// (SignalDeferral), a termination signal waits until the set is complete or rolled back, so
/// outputs that belong together are all new or all old. SIGKILL cannot be caught: its temporaries
/// stay until the next run to the same output removes them (removeStaleTemporaries()).

#include <string>
#include <vector>

namespace gseg::io {

/// A temporary file registered for removal on signals and crashes. Destruction only unregisters
/// the path; the file itself is its writer's business.
class TemporaryRegistration {
public:
    /// Throws std::runtime_error if the path is too long or too many temporaries are registered.
    explicit TemporaryRegistration(const std::string& path);
    ~TemporaryRegistration();
    TemporaryRegistration(TemporaryRegistration&& other) noexcept : slot_(other.slot_) { other.slot_ = -1; }
    TemporaryRegistration(const TemporaryRegistration&) = delete;
    TemporaryRegistration& operator=(const TemporaryRegistration&) = delete;
    TemporaryRegistration& operator=(TemporaryRegistration&&) = delete;

private:
    int slot_ = -1;
};

/// While one of these lives (in any thread), SIGINT, SIGTERM, SIGHUP, SIGQUIT and SIGPIPE are
/// held back by the handler of installTemporaryCleanup(); when the last one ends, a signal that
/// arrived meanwhile takes effect (cleanup, message, end of the process). Nestable, thread-safe.
class SignalDeferral {
public:
    SignalDeferral();
    ~SignalDeferral();
    SignalDeferral(const SignalDeferral&) = delete;
    SignalDeferral& operator=(const SignalDeferral&) = delete;
};

/// Installs the signal handlers that remove registered temporaries (idempotent). A termination
/// signal that the process inherited as ignored (e.g. SIGINT of a background job) stays ignored.
/// SIGXFSZ is ignored, so that a file-size limit makes the write fail (and be reported) instead of
/// killing the process. After the cleanup the handler prints one line to stderr, `<tool>:
/// interrupted (SIGTERM) while <activity>; temporary outputs removed` or `<tool>: crashed
/// (SIGSEGV) ...`, and lets the signal's default action end the process.
void installTemporaryCleanup(const std::string& toolName);

/// What the process is doing, for that line (e.g. "reading entry 12 of drive.rawlog"); kept in a
/// fixed buffer (at most 255 bytes), thread-safe.
void setActivity(const std::string& activity);

/// Temporaries currently registered (for tests and diagnostics).
std::vector<std::string> registeredTemporaries();

/// The one naming rule of temporaries and kept-aside previous versions: `<folder>/.<name>.gseg-
/// <host>-<pid>-<n>.<kind>` beside the file `path` (same folder, so the final rename is atomic).
/// `kind` is "tmp", "bak" or "set" (the journal of a set being put in place); `n` tells apart
/// several of one process.
std::string sideFilePath(const std::string& path, const char* kind);

/// Removes the side files (see sideFilePath()) of `path` left by processes of this host that no
/// longer run (a killed run's temporaries and kept-aside versions); returns how many. A folder is
/// read once per process, however many outputs it holds. Never throws. First, a dead run's set
/// journal found in the folder (a run killed, e.g. by SIGKILL, between the renames of a set) is
/// rolled back: its replaced files get their previous versions back, its new files are removed,
/// so the set is all old again. (The journal lies beside the set's first file: a later run finds
/// it when it writes into that folder.)
std::size_t removeStaleTemporaries(const std::string& path) noexcept;

}  // namespace gseg::io
