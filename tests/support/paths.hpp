#pragma once
/// \file paths.hpp
/// Where tests find the shared real data and the built tools.

#include <filesystem>
#include <string>
#include <vector>

#include <sys/types.h>

namespace gseg::test {

/// `<shared>/data/<relative>` if that file exists, else "" (the caller skips with a message).
std::string sharedData(const std::string& relative);

/// Message for GTEST_SKIP() when shared data is absent.
std::string missingDataMessage(const std::string& relative);

/// `path` in single quotes: one word of a shell command line (runCommand()); `path` holds no quote.
inline std::string q(const std::filesystem::path& path) { return "'" + path.string() + "'"; }

/// Path of a built executable (`<build>/bin/<name>`).
std::string tool(const std::string& name);

/// The command that starts `processes` ranks of a tool on this machine
/// (`mpirun --allow-run-as-root --oversubscribe -np N`, OpenMPI), or "" with the reason in
/// `whyNot` when the build has no MPI support (GSEG_WITH_MPI off) or mpirun is absent.
std::string mpirun(int processes, std::string& whyNot);

/// In a test body: `const std::string var` = mpirun(processes), or the test is skipped with the reason.
#define GSEG_TEST_MPIRUN_OR_SKIP(var, processes)                       \
    std::string var##WhyNot;                                           \
    const std::string var = gseg::test::mpirun(processes, var##WhyNot); \
    if (var.empty()) GTEST_SKIP() << var##WhyNot

/// The whole content of a text file ("" if it cannot be read).
std::string readText(const std::string& path);

/// Writes `text` as it is (binary) to `<build>/tests/<group>/<name>`, creating the folder if
/// needed; returns the path.
std::string writeTestFile(const std::string& group, const std::string& name, const std::string& text);

/// Exit status and combined stdout + stderr of a shell command.
struct CommandResult {
    int status = -1;  ///< exit code, -1 if it did not exit normally
    std::string output;
};
CommandResult runCommand(const std::string& shellCommand);

/// runCommand() of the built tool `name` with `args` (shell words): exit status and stdout + stderr.
CommandResult runToolCommand(const std::string& name, const std::string& args);

/// The built `gseg` with `subcommand` and `args` (shell words, e.g. "'scan.bin' --threads 2")
/// through runCommand(): its stdout + stderr, and its exit code in `status`.
std::string runGseg(const std::string& subcommand, const std::string& args, int& status);

/// Exit status, stdout and stderr (apart) of a built tool run by runTool().
struct ToolRun {
    int status = 0;  ///< exit code; 128 + the signal's number when a signal ended it
    std::string out, err;
};

/// Runs the built tool `name` with `args` (shell words) through bash, `limits` before it (e.g.
/// "ulimit -f 64; trap '' XFSZ;") and `launcher` in front of it (e.g. mpirun()); its stdout and
/// stderr go through `dir`/out.txt and `dir`/err.txt (which stay there) and come back.
ToolRun runTool(const std::string& name, const std::string& args, const std::string& dir,
                const std::string& limits = "", const std::string& launcher = "");

/// Starts the built tool `name` with `args` without waiting for it (no shell), its stderr into
/// `stderrPath`; its pid, or -1 if it could not be started. For tests that act on a running tool
/// (signals, pipes); the caller waits for it with waitpid().
pid_t spawnTool(const std::string& name, const std::vector<std::string>& args, const std::string& stderrPath);

}  // namespace gseg::test
