#pragma once
/// \file cli.hpp
/// What every gseg tool's command line has, in one place (#11 item 4): MRPT's TCLAP; `--help` and
/// `--version` with gseg's version (exit 0); `-q/--quiet` (errors only) and `-v/--verbose` (more
/// detail); `-w/--overwrite` for the tools that write files; a usage error as one line naming the
/// tool (exit 2), in the same words in every tool: "unknown option '--ply_out' (did you mean
/// '--ply-out'?)", "missing required option -o/--output", "option --ply-out needs a value (FILE)",
/// "option -o/--output given twice", "unexpected argument 'x'". `--name=value` is read as
/// `--name value`. MRPT's TCLAP never exits from inside the parser: every MPI rank parses the same
/// arguments and returns the same code, only rank 0 prints.

#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <vector>

namespace gseg::tools {

/// Exit codes of every tool (README, "Exit codes"): 0 done; 1 failure (bad input, nothing or not
/// everything written); 2 bad usage (before any work, nothing changed); 3 done, but inputs (scans,
/// frames, files) were skipped and named.
enum Exit { kDone = 0, kBadInput = 1, kBadUsage = 2, kPartlyDone = 3 };

/// What a std::invalid_argument means where a tool catches it: bad usage (the checks before any
/// work: an option's value, an output that cannot be written) or bad input (inside the work, where
/// it names a bad file).
enum class InvalidArgument { BadUsage, BadInput };

/// The one error-to-exit-code path of every tool, for the exception being handled (call them in a
/// catch block). currentError(): its message in one line (MRPT's exceptions reduced to their
/// reason, gseg::mrpt::errorReason; "unknown error" for one not derived from std::exception).
/// exitCodeOf(): kBadUsage for a std::invalid_argument meaning bad usage, else kBadInput.
/// reportError(): prints "<tool>: <currentError()>" on stderr and returns exitCodeOf().
std::string currentError();
int exitCodeOf(InvalidArgument meaning);
int reportError(const std::string& tool, InvalidArgument meaning);

enum class Verbosity { Quiet, Normal, Verbose };

/// The process's verbosity (set by CommandLine::parse(); Normal before).
Verbosity verbosity();
void setVerbosity(Verbosity v);

/// What a tool says besides errors: say() to stdout unless --quiet; detail() to stdout with
/// --verbose only; note() to stderr unless --quiet (remarks that are not errors). Errors are
/// printed with std::fprintf(stderr, ...) whatever the verbosity.
void say(const char* format, ...) __attribute__((format(printf, 1, 2)));
void detail(const char* format, ...) __attribute__((format(printf, 1, 2)));
void note(const char* format, ...) __attribute__((format(printf, 1, 2)));
/// note()s "<tool>: warning: <w>" for each of `warnings` (a configuration's ignored keys,
/// gseg::mrpt::LoadedConfig::warnings): every tool says each once, after loading its configuration.
void noteWarnings(const std::string& tool, const std::vector<std::string>& warnings);
/// "rawlog-gseg (gseg) 0.1.0", "gseg segment 0.1.0": what --version prints.
std::string versionLine(const std::string& toolName);

/// [bytes] A memory size given as `flag` (e.g. --max-memory): a number of MB ("500"), or with a
/// unit K, M, G or T (powers of 1000, "2G", "1.5GB"). Throws std::invalid_argument naming `flag`.
double parseMemorySize(const std::string& flag, const std::string& value);

/// The candidate nearest to `typed` (edit distance, ignoring case; or the one candidate it begins
/// with), "" when none is near enough to be what was meant: the "did you mean" of every tool.
std::string nearestName(const std::string& typed, const std::vector<std::string>& candidates);

/// Where gseg::Progress writes: stderr, or nowhere (null) with --quiet.
std::FILE* progressOut();

/// A tool's command line. Construct it, add the tool's own arguments to cmd(), call parse().
class CommandLine {
public:
    /// `name` as the user calls the tool ("rawlog-gseg", "gseg segment"); `description` for
    /// --help; `writesFiles` adds -w/--overwrite. `printing` false (MPI ranks other than 0): the
    /// same parsing and exit codes, nothing printed.
    CommandLine(std::string name, const std::string& description, bool writesFiles, bool printing = true);
    ~CommandLine();
    CommandLine(const CommandLine&) = delete;
    CommandLine& operator=(const CommandLine&) = delete;

    TCLAP::CmdLine& cmd() { return cmd_; }

    /// Parses; sets the verbosity. Returns -1 to go on, kDone after --help or --version (printed),
    /// kBadUsage after a usage error (one line printed on stderr). Unknown, repeated and
    /// value-less options and missing required ones are found before TCLAP reads the line (TCLAP
    /// would take an unknown option for a positional input, or say "Couldn't find match").
    int parse(int argc, char** argv);

    /// -w / --overwrite was given (false for a tool that writes no file).
    bool overwrite() const { return overwrite_ && overwrite_->getValue(); }

    /// Adds `--mpi-timeout SECONDS` (before parse()), for the tools that run under mpirun/srun:
    /// how long a rank may stay silent before the job is ended (Ranks::setTimeout()).
    void addMpiTimeout();
    /// [s] The value of --mpi-timeout (Ranks::kDefaultTimeout if not given; 0: none).
    double mpiTimeout() const { return mpiTimeoutSeconds_; }

    /// A usage error found after parsing: prints "<name>: <what>; see <name> --help" (when
    /// printing) and returns kBadUsage.
    int usageError(const std::string& what) const;

private:
    class Output;
    /// The usage mistakes found in `args` (argv without argv[0]; `--name=value` split in place),
    /// "" when none; `helpOrVersion` set to the --help / -h / --version given, if any.
    std::string checkArguments(std::vector<std::string>& args, std::string& helpOrVersion);
    std::string name_;
    bool printing_;
    TCLAP::CmdLine cmd_;
    std::unique_ptr<Output> output_;
    TCLAP::SwitchArg quiet_, verbose_;
    std::unique_ptr<TCLAP::SwitchArg> overwrite_;
    std::unique_ptr<TCLAP::ValueArg<std::string>> mpiTimeout_;
    double mpiTimeoutSeconds_;
};

}  // namespace gseg::tools
