#include <support/paths.hpp>

#include <cstdio>
#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <spawn.h>
#include <sstream>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace gseg::test {

std::string sharedData(const std::string& relative) {
    const std::string path = std::string(GSEG_SHARED_DIR) + "/data/" + relative;
    struct stat st {};
    return ::stat(path.c_str(), &st) == 0 ? path : std::string();
}

std::string missingDataMessage(const std::string& relative) {
    return "shared data " + std::string(GSEG_SHARED_DIR) + "/data/" + relative +
           " is absent (a checkout outside the project's workspace): skipped";
}

std::string tool(const std::string& name) { return std::string(GSEG_BINARY_DIR) + "/bin/" + name; }

std::string mpirun(int processes, std::string& whyNot) {
    if (!GSEG_TEST_WITH_MPI) {
        whyNot = "this build has no MPI support (GSEG_WITH_MPI is off): skipped";
        return "";
    }
    const std::string launcher = GSEG_TEST_MPIRUN;
    if (launcher.empty() || ::access(launcher.c_str(), X_OK) != 0) {
        whyNot = "mpirun is not installed (Debian: openmpi-bin): skipped";
        return "";
    }
#if defined(__SANITIZE_ADDRESS__)
    // Sanitized builds: OpenMPI's components (dlopened, gone at exit), PMIx and the MRPT libraries
    // in an MPI process leave allocations that LeakSanitizer reports at exit; not ours, and the
    // same code is leak-checked in every run without mpirun. Other ASan checks stay on.
    const char* options = std::getenv("ASAN_OPTIONS");
    const std::string env = "env ASAN_OPTIONS='" + std::string(options ? options : "") + ":detect_leaks=0' ";
#else
    const std::string env;
#endif
    return env + "'" + launcher + "' --allow-run-as-root --oversubscribe -np " + std::to_string(processes) + " ";
}

std::string readText(const std::string& path) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::string writeTestFile(const std::string& group, const std::string& name, const std::string& text) {
    const std::filesystem::path dir = std::filesystem::path(GSEG_BINARY_DIR) / "tests" / group;
    std::filesystem::create_directories(dir);
    const std::string path = (dir / name).string();
    std::ofstream(path, std::ios::binary) << text;
    return path;
}

CommandResult runCommand(const std::string& shellCommand) {
    CommandResult r;
    FILE* pipe = ::popen((shellCommand + " 2>&1").c_str(), "r");
    if (!pipe) return r;
    char buf[1024];
    while (std::fgets(buf, sizeof buf, pipe)) r.output += buf;
    const int st = ::pclose(pipe);
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return r;
}

CommandResult runToolCommand(const std::string& name, const std::string& args) {
    return runCommand("'" + tool(name) + "' " + args);
}

std::string runGseg(const std::string& subcommand, const std::string& args, int& status) {
    const CommandResult r = runToolCommand("gseg", subcommand + " " + args);
    status = r.status;
    return r.output;
}

ToolRun runTool(const std::string& name, const std::string& args, const std::string& dir, const std::string& limits,
                const std::string& launcher) {
    ToolRun r;
    const std::string command =
        limits + " exec " + launcher + tool(name) + " " + args + " > " + dir + "/out.txt 2> " + dir + "/err.txt";
    const int st = std::system(("bash -c \"" + command + "\"").c_str());
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);  // a crash is >= 128
    r.out = readText(dir + "/out.txt");
    r.err = readText(dir + "/err.txt");
    return r;
}

pid_t spawnTool(const std::string& name, const std::vector<std::string>& args, const std::string& stderrPath) {
    const std::string path = tool(name);
    std::vector<char*> argv{const_cast<char*>(path.c_str())};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 2, stderrPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    pid_t pid = -1;
    const int rc = ::posix_spawn(&pid, path.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    return rc == 0 ? pid : -1;
}

}  // namespace gseg::test
