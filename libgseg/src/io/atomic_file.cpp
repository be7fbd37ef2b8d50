#include <gseg/io/atomic_file.hpp>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fcntl.h>
#include <stdexcept>
#include <streambuf>
#include <sys/stat.h>
#include <unistd.h>

namespace gseg::io {
namespace {

std::string reason(int err) { return std::strerror(err); }

// Puts `temp` at `file` unless `file` exists (atomically where the file system can). Returns 0 or
// the errno (EEXIST: someone else made `file`).
int placeExclusively(const std::string& temp, const std::string& file) {
    if (::renameat2(AT_FDCWD, temp.c_str(), AT_FDCWD, file.c_str(), RENAME_NOREPLACE) == 0) return 0;
    if (errno != EINVAL && errno != ENOSYS && errno != EOPNOTSUPP) return errno;
    // No RENAME_NOREPLACE here (some network and FUSE file systems): a hard link fails if `file` exists.
    if (::link(temp.c_str(), file.c_str()) == 0) {
        ::unlink(temp.c_str());
        return 0;
    }
    if (errno == EEXIST) return EEXIST;
    struct stat st {};  // no hard links either: check, then rename (a race stays possible only here)
    if (::lstat(file.c_str(), &st) == 0) return EEXIST;
    return std::rename(temp.c_str(), file.c_str()) == 0 ? 0 : errno;
}

// A std::streambuf over an AtomicFile: what an ostream writer (OctoMap, iostreams) writes goes to
// the file in 64 KiB blocks; the file's error is kept and thrown again after the writer is done.
class FileBuf : public std::streambuf {
public:
    explicit FileBuf(AtomicFile& file) : file_(file) { setp(buf_, buf_ + sizeof buf_); }
    bool drain() {
        if (error_) return false;
        try {
            file_.write(pbase(), std::size_t(pptr() - pbase()));
        } catch (...) {
            error_ = std::current_exception();
            return false;
        }
        setp(buf_, buf_ + sizeof buf_);
        return true;
    }
    void rethrow() const {
        if (error_) std::rethrow_exception(error_);
    }

protected:
    int_type overflow(int_type c) override {
        if (!drain()) return traits_type::eof();
        if (!traits_type::eq_int_type(c, traits_type::eof())) sputc(traits_type::to_char_type(c));
        return traits_type::not_eof(c);
    }
    int sync() override { return drain() ? 0 : -1; }

private:
    AtomicFile& file_;
    char buf_[1 << 16];
    std::exception_ptr error_;
};

}  // namespace

namespace {

OutputTarget targetOf(const std::string& path) {
    try {
        return resolveOutput(path);
    } catch (const std::invalid_argument& e) {  // checked before any work by the tools; here a failure to write
        throw std::runtime_error(e.what());
    }
}

}  // namespace

AtomicFile::AtomicFile(std::string path) : target_(targetOf(path)) {
    if (target_.stream) {  // a pipe, terminal or device: the bytes go there as they come
        temp_ = target_.given;
        fd_ = ::open(temp_.c_str(), O_WRONLY | O_CLOEXEC);
        if (fd_ < 0) throw std::runtime_error(target_.given + ": cannot open for writing (" + reason(errno) + ")");
        exclusive_ = false;
        return;
    }
    const bool isNew = mustBeNew(target_.given);
    if (isNew && target_.exists)
        throw std::runtime_error(target_.given + " appeared after this run checked its outputs (another run writing it?): "
                                 "not replaced");
    exclusive_ = isNew || !target_.exists;
    removeStaleTemporaries(target_.file);
    for (int attempt = 0; fd_ < 0; ++attempt) {
        temp_ = sideFilePath(target_.file, "tmp");
        registered_ = std::make_unique<TemporaryRegistration>(temp_);
        fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd_ >= 0) break;
        const int err = errno;
        registered_.reset();
        if (err != EEXIST || attempt > 100) throw std::runtime_error(target_.given + ": cannot create (" + reason(err) + ")");
    }
}

AtomicFile::~AtomicFile() { discard(); }

void AtomicFile::discard() noexcept {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    if (registered_ && !done_) ::unlink(temp_.c_str());
    registered_.reset();
}

void AtomicFile::fail(const std::string& what, int err) {
    discard();
    throw std::runtime_error(target_.given + ": " + what + " (" + reason(err) + ")");
}

void AtomicFile::write(const void* data, std::size_t size) {
    if (fd_ < 0) throw std::logic_error(target_.given + ": write after commit or failure");
    const char* p = static_cast<const char*>(data);
    while (size > 0) {
        const ssize_t n = ::write(fd_, p, size);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) fail("write failed after " + std::to_string(written_) + " bytes", n < 0 ? errno : EIO);
        p += n, size -= std::size_t(n), written_ += std::uint64_t(n);
    }
}

void AtomicFile::write(const std::function<void(std::ostream&)>& fill) {
    FileBuf buf(*this);
    std::ostream out(&buf);
    fill(out);
    out.flush();
    buf.rethrow();
    if (!out) fail("the writer failed", EIO);
}

void AtomicFile::close() {
    if (fd_ < 0) throw std::logic_error(target_.given + ": commit after commit or failure");
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail("closing the written file failed", errno);
}

namespace {

/// The journal of a set being put in place (see rollBackJournal() in temporary_cleanup.cpp): one
/// line per file, "R\t<file>\t<bak>" for one that replaces a previous version (kept aside as
/// <bak> until all are in place), "N\t<file>\t<temporary>" for a new one. Written whole beside
/// the first file before any rename, removed once all are in place: a run killed in between
/// (SIGKILL: no handler runs) leaves it, and the next run to that folder rolls the set back.
/// Returns its path, or "" where it could not be written (then no rollback after SIGKILL).
std::string writeJournal(const std::string& first, const std::string& lines) {
    const std::string temp = sideFilePath(first, "tmp"), journal = sideFilePath(first, "set");
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) return "";
    bool ok = true;
    for (std::size_t at = 0; ok && at < lines.size();) {
        const ssize_t n = ::write(fd, lines.data() + at, lines.size() - at);
        if (n < 0 && errno == EINTR) continue;
        ok = n > 0;
        at += ok ? std::size_t(n) : 0;
    }
    ok = ::close(fd) == 0 && ok;
    if (ok && std::rename(temp.c_str(), journal.c_str()) == 0) return journal;
    ::unlink(temp.c_str());
    return "";
}

}  // namespace

void commitTogether(const std::vector<AtomicFile*>& files) {
    for (AtomicFile* f : files) f->close();  // every write checked before anything is replaced
    SignalDeferral hold;                     // a termination signal waits until all are in place or none
    std::vector<AtomicFile*> placed;
    std::vector<std::string> backups(files.size()), backupNames(files.size());
    std::string lines;
    std::size_t inPlace = 0;  // files put in place by rename (not streamed)
    for (std::size_t i = 0; i < files.size(); ++i) {
        const AtomicFile* f = files[i];
        if (f->target_.stream) continue;
        ++inPlace;
        if (!f->exclusive_) backupNames[i] = sideFilePath(f->target_.file, "bak");
        lines += f->exclusive_ ? "N\t" + f->target_.file + "\t" + f->temp_ + "\n" : "R\t" + f->target_.file + "\t" + backupNames[i] + "\n";
    }
    setActivity("putting " + std::to_string(inPlace) + " written file" + (inPlace == 1 ? "" : "s") + " in place");
    // One rename is atomic by itself; a set of several needs the journal.
    std::string journal;
    for (const AtomicFile* f : files)
        if (inPlace > 1 && !f->target_.stream) {
            journal = writeJournal(f->target_.file, lines);
            break;
        }
    auto rollBack = [&] {
        for (std::size_t i = 0; i < files.size(); ++i) {
            AtomicFile* f = files[i];
            const bool wasPlaced = std::find(placed.begin(), placed.end(), f) != placed.end();
            if (wasPlaced && !backups[i].empty()) std::rename(backups[i].c_str(), f->target_.file.c_str());
            else if (wasPlaced) ::unlink(f->target_.file.c_str());
            else if (!backups[i].empty()) ::unlink(backups[i].c_str());
            if (!f->target_.stream) ::unlink(f->temp_.c_str());
            f->registered_.reset();
        }
        if (!journal.empty()) ::unlink(journal.c_str());
    };
    // New files first: they fail if another run made them meanwhile, and nothing was replaced yet.
    for (int pass = 0; pass < 2; ++pass) {
        for (std::size_t i = 0; i < files.size(); ++i) {
            AtomicFile* f = files[i];
            if (f->target_.stream || f->exclusive_ != (pass == 0)) continue;
            const std::string& file = f->target_.file;
            int err = 0;
            if (f->exclusive_) {
                err = placeExclusively(f->temp_, file);
            } else {
                const std::string& backup = backupNames[i];  // the previous version, until all are in place
                if (::link(file.c_str(), backup.c_str()) == 0) backups[i] = backup;
                else if (errno != ENOENT && errno != EPERM && errno != EOPNOTSUPP) err = errno;
                if (!err && std::rename(f->temp_.c_str(), file.c_str()) != 0) err = errno;
            }
            if (err) {
                rollBack();
                const std::string others = files.size() > 1 ? "; none of the " + std::to_string(files.size()) + " files changed"
                                                            : "; nothing changed";
                if (err == EEXIST)
                    throw std::runtime_error(f->target_.given + " was created by another program while this run worked: "
                                             "not replaced" + others);
                throw std::runtime_error(f->target_.given + ": cannot put the written file in place (" + reason(err) + ")" +
                                         others);
            }
            placed.push_back(f);
        }
    }
    // All in place: removing the journal is the commit point (a run killed after it keeps the new
    // set; the next run only removes the kept-aside versions).
    if (!journal.empty()) ::unlink(journal.c_str());
    setActivity(files.size() == 1 ? std::string("ending (the output was written and is complete)")
                                  : "ending (all " + std::to_string(files.size()) + " outputs were written and are complete)");
    for (std::size_t i = 0; i < files.size(); ++i) {
        if (!backups[i].empty()) ::unlink(backups[i].c_str());
        writtenByThisProcess(files[i]->target_.given);
        files[i]->done_ = true;
        files[i]->registered_.reset();
    }
}

void AtomicFile::commit() {
    if (inSet_) throw std::logic_error(target_.given + ": a member of an AtomicFileSet is committed by the set");
    commitTogether({this});
}

AtomicFileSet::AtomicFileSet(const std::vector<std::string>& paths) {
    if (!paths.empty())  // what a signal's message names from here on (no longer the last entry read)
        setActivity("writing " + paths.front() +
                    (paths.size() > 1 ? " and the other " + std::to_string(paths.size() - 1) + " outputs" : std::string()));
    for (const std::string& p : paths) add(p);
}

AtomicFile& AtomicFileSet::add(const std::string& path) {
    files_.push_back(std::make_unique<AtomicFile>(path));
    files_.back()->inSet_ = true;
    return *files_.back();
}

std::vector<std::string> AtomicFileSet::paths() const {
    std::vector<std::string> out;
    for (const auto& f : files_) out.push_back(f->path());
    return out;
}

void AtomicFileSet::commit() {
    std::vector<AtomicFile*> files;
    for (const auto& f : files_) files.push_back(f.get());
    commitTogether(files);
}

void writeFileAtomic(const std::string& path, const void* bytes, std::size_t size) {
    AtomicFile file(path);
    file.write(bytes, size);
    file.commit();
}

}  // namespace gseg::io
