#pragma once
/// \file output_checks.hpp
/// Where an output path lands, and the checks every tool makes before any work: an output is
/// never an input, exists only with -w, names a file (not a folder) in a folder that takes one.

#include <string>
#include <vector>

namespace gseg::io {

/// Where the bytes of an output named `given` go.
struct OutputTarget {
    std::string given;    ///< the path as named
    std::string file;     ///< the regular file written (through any symbolic links), or `given` to stream into
    bool stream = false;  ///< a pipe, FIFO, terminal, socket or device (or /dev/stdout, /proc/self/fd/N): written in place, as produced
    bool exists = false;  ///< `file` exists now
};

/// Resolves `given`: a symbolic link is followed to the file it names (written through, never
/// replaced; a dangling link creates its destination), anything that is not a regular file or a
/// folder is streamed into. Throws std::invalid_argument for an empty name, a folder, a link loop
/// or a name whose folder does not exist.
OutputTarget resolveOutput(const std::string& given);

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
/// file that exists is refused unless `rules.overwrite` (a pipe, terminal or device is written
/// into, no -w needed), a folder or a link loop always; the folder of the file written (through
/// links) must exist (or with `rules.makeFolders` its nearest existing parent) and accept a new
/// file (tried: permissions, read-only file systems and root all count). Empty paths are ignored.
/// Without `rules.overwrite` the outputs are remembered as new: a writer (AtomicFile) that finds
/// one existing later (another run made it meanwhile) fails instead of replacing it.
void checkOutputs(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs, OutputRules rules);

/// Checks a prefix that names a set of files (PREFIX_ground.bt, ...): throws std::invalid_argument
/// if it is empty, ends in '/' (the files would be named "_ground.bt" inside a folder) or is an
/// existing folder, device or other thing that is not a regular file (`-o /dev/null` would create
/// the set in /dev). A prefix naming an existing regular file is fine (its name only starts the set's).
void checkOutputPrefix(const std::string& prefix);

/// Whether checkOutputs() was told that `path` must be a new file (no -w), and this process has
/// not written it since.
bool mustBeNew(const std::string& path);

/// This process has written `path` (AtomicFile calls it): it may replace its own file later.
void writtenByThisProcess(const std::string& path);

}  // namespace gseg::io
