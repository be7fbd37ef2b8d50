#pragma once
/// \file atomic_file.hpp
/// Outputs written completely or not at all. AtomicFile writes to a temporary file beside its
/// target (`<target>.tmp<pid>`), checks every write and the close, and renames the temporary over
/// the target only on commit(). Temporaries sit in a registry that a signal handler can read:
/// after installTemporaryCleanup(), an interrupted run (SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE)
/// or a crash (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT) removes them before the process ends.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace gseg::io {

/// One output file, written through a temporary file and renamed into place by commit().
/// Not copyable; one object per output; usable from any thread (one thread per object).
class AtomicFile {
public:
    /// Creates the temporary beside `path`. Throws std::runtime_error naming `path` if it cannot.
    explicit AtomicFile(std::string path);
    /// Removes the temporary unless commit() succeeded.
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    /// Appends `size` bytes. Throws std::runtime_error naming the target and the reason (e.g. "No
    /// space left on device") if they cannot all be written; the temporary is then removed.
    void write(const void* data, std::size_t size);

    /// Closes the temporary (checked: a failed close loses data on some file systems) and renames
    /// it over the target. Throws std::runtime_error and removes the temporary on failure.
    void commit();

    /// Removes the temporary now (also done by the destructor).
    void discard() noexcept;

    const std::string& path() const { return path_; }
    const std::string& temporaryPath() const { return temp_; }
    std::uint64_t bytesWritten() const { return written_; }

private:
    [[noreturn]] void fail(const std::string& what, int err);

    std::string path_, temp_;
    int fd_ = -1;
    int slot_ = -1;  // registry slot of the temporary
    std::uint64_t written_ = 0;
};

/// A temporary file that another writer creates by path (not an AtomicFile), registered for the
/// same cleanup on signals and crashes as AtomicFile's: the handler removes it. Destruction only
/// unregisters the path; the file itself is the writer's business.
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

/// Writes `bytes` to `path` through an AtomicFile. Throws std::runtime_error on failure (and
/// leaves neither a partial file nor a temporary).
void writeFileAtomic(const std::string& path, const void* bytes, std::size_t size);

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

/// A path given on a command line, with the name of its argument for messages.
struct NamedPath {
    std::string argument;  ///< e.g. "--labels-out" or "input"
    std::string path;
};

/// Throws std::invalid_argument if an output is the same file as an input (same device and
/// inode: hard links and symbolic links count) or two outputs name the same file. Empty paths are
/// ignored. Call it before anything is written.
void checkOutputsAreNotInputs(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs);

/// What checkOutputs() allows.
struct OutputRules {
    bool overwrite = false;    ///< an existing output may be replaced (the tools' -w / --overwrite)
    bool makeFolders = false;  ///< a missing folder is fine if it can be made (the tool makes it)
};

/// Checks before any work that every output can be written, and throws std::invalid_argument
/// (bad usage) naming the argument and the path otherwise: checkOutputsAreNotInputs(); an output
/// that exists is refused unless `rules.overwrite`, one that is a folder always; its folder must
/// exist (or with `rules.makeFolders` its nearest existing parent) and accept a new file (tried:
/// permissions, read-only file systems and root all count). Empty paths are ignored.
void checkOutputs(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs, OutputRules rules);

}  // namespace gseg::io
