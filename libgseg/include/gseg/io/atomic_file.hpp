#pragma once
/// \file atomic_file.hpp
/// Outputs written completely or not at all: the one output mechanism of gseg. An AtomicFile
/// writes to a temporary beside the file it names (sideFilePath(), through symbolic links),
/// checks every write and the close, and puts it in place only on commit(); an AtomicFileSet
/// commits several together, all new or all old, also under signals (SignalDeferral). A file
/// that did not exist when its writer started (or that checkOutputs() was told is new) is created
/// exclusively: a second run writing it meanwhile fails instead of being overwritten. A pipe,
/// terminal or device is written into as the bytes come (resolveOutput()).

#include <gseg/io/output_checks.hpp>
#include <gseg/io/temporary_cleanup.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

namespace gseg::io {

class AtomicFileSet;

/// One output file. Not copyable; usable from any thread (one thread per object).
class AtomicFile {
public:
    /// Creates the temporary (or opens the stream); removes stale temporaries of `path` first.
    /// Throws std::runtime_error naming `path` if it cannot (also where `path` is no place for a
    /// file: see resolveOutput()).
    explicit AtomicFile(std::string path);
    /// Removes the temporary unless committed.
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    /// Appends `size` bytes. Throws std::runtime_error naming the output and the reason (e.g. "No
    /// space left on device") if they cannot all be written; the temporary is then removed.
    void write(const void* data, std::size_t size);
    /// Appends what `fill` writes into a std::ostream (no copy in memory); errors as write().
    void write(const std::function<void(std::ostream&)>& fill);

    /// Closes the temporary (checked) and puts it in place. Throws std::runtime_error on failure
    /// (nothing changed at `path`). For a member of an AtomicFileSet, the set commits.
    void commit();

    /// Removes the temporary now (also done by the destructor).
    void discard() noexcept;

    const std::string& path() const { return target_.given; }
    /// Where the bytes go now: the temporary, or the stream.
    const std::string& temporaryPath() const { return temp_; }
    std::uint64_t bytesWritten() const { return written_; }
    bool streamed() const { return target_.stream; }

private:
    friend class AtomicFileSet;
    friend void commitTogether(const std::vector<AtomicFile*>& files);
    [[noreturn]] void fail(const std::string& what, int err);
    void close();  ///< the checked close before the rename

    OutputTarget target_;
    bool exclusive_ = true;  ///< create `target_.file`, never replace it
    bool inSet_ = false;
    std::string temp_;
    int fd_ = -1;
    std::unique_ptr<TemporaryRegistration> registered_;
    std::uint64_t written_ = 0;
    bool done_ = false;
};

/// Outputs that belong together (a map's files, a report's tables): written one by one into
/// their temporaries, then all put in place by commit(), or none. Not copyable.
class AtomicFileSet {
public:
    /// One AtomicFile per path (empty paths are not allowed). Throws as AtomicFile.
    explicit AtomicFileSet(const std::vector<std::string>& paths);
    AtomicFile& operator[](std::size_t i) { return *files_[i]; }
    /// One more file of the set (where its name is known only after some of the others are
    /// written). Throws as AtomicFile.
    AtomicFile& add(const std::string& path);
    std::size_t size() const { return files_.size(); }
    std::vector<std::string> paths() const;

    /// Closes every temporary (checked) and puts all in place. If any step fails, every file the
    /// set had put in place gets its previous version back (or is removed where there was none),
    /// and std::runtime_error names the file and the reason. A termination signal during the
    /// renames waits until they are done (SignalDeferral).
    void commit();

private:
    std::vector<std::unique_ptr<AtomicFile>> files_;
};

/// Writes `bytes` to `path` through an AtomicFile. Throws std::runtime_error on failure (and
/// leaves neither a partial file nor a temporary).
void writeFileAtomic(const std::string& path, const void* bytes, std::size_t size);

}  // namespace gseg::io
