#pragma once
/// \file output_files.hpp
/// Output files written completely or not at all, checked before any work, never over an input.

#include <gseg/io/atomic_file.hpp>

#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace gseg::map {

/// `<folder>/.tmp<pid>_<name>` beside `path` (same folder, so the final rename is atomic).
std::string temporaryPathFor(const std::string& path);

/// Writes `bytes` to `path`, checking every write and the close. Throws std::runtime_error
/// naming the file and the reason (e.g. "No space left on device"); removes a partial file.
void writeFileChecked(const std::string& path, const std::string& bytes);
/// The same for content written by `fill` into a stream (no copy of it in memory).
void writeFileChecked(const std::string& path, const std::function<void(std::ostream&)>& fill);

/// A set of output files that appear together or not at all. Write file i to temporary(i), then
/// commit(). Without commit() (an exception on the way), the destructor removes the temporaries;
/// they are registered with gseg::io's cleanup, so a tool that called
/// gseg::io::installTemporaryCleanup() also loses none on a signal or crash.
class AtomicFiles {
public:
    explicit AtomicFiles(std::vector<std::string> paths);
    ~AtomicFiles();
    AtomicFiles(const AtomicFiles&) = delete;
    AtomicFiles& operator=(const AtomicFiles&) = delete;

    const std::string& temporary(std::size_t i) const { return temps_[i]; }
    const std::vector<std::string>& paths() const { return paths_; }

    /// Renames every temporary into place. The previous version of each file is kept aside (hard
    /// link) until all renames succeeded; if one fails, the files renamed so far get their previous
    /// versions back (or are removed where there was none), and std::runtime_error names the file.
    void commit();

private:
    std::vector<std::string> paths_, temps_;
    std::vector<gseg::io::TemporaryRegistration> registered_;
    bool committed_ = false;
};

}  // namespace gseg::map
