// What the tools share for MPI (#12), in one process: the split of work over ranks, the bytes of
// the messages, and the ranks of a tool started without a launcher (one process, MPI untouched).
// Under mpirun (#18 point 3): a rank that stops answering ends the job, named, within
// --mpi-timeout, leaving no output.
#include "common/ranks.hpp"

#include <support/child.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <dirent.h>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <limits>
#include <thread>
#include <sched.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

using gseg::tools::splitByWork;

namespace {

std::vector<std::uint64_t> loads(const std::vector<std::uint64_t>& work, const std::vector<int>& owner, int ranks) {
    std::vector<std::uint64_t> l(std::size_t(ranks), 0);
    for (std::size_t i = 0; i < work.size(); ++i) l[std::size_t(owner[i])] += work[i];
    return l;
}

/// The ranks of this test process, started without a launcher (one object per process, as MPI
/// can only be initialised once).
gseg::tools::Ranks& alone() {
    for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"}) ::unsetenv(v);
    static int argc = 1;
    static char name[] = "test", *args[] = {name, nullptr};
    static char** argv = args;
    static gseg::tools::Ranks ranks(argc, argv);
    return ranks;
}

}  // namespace

TEST(SplitByWork, LargestFirstToTheLeastLoadedRank) {
    // Largest first: 9 -> 0, 8 -> 1, 7 -> 1 (8 < 9), 6 -> 0 (9 < 15), 5 -> 0 (15 = 15: the lower rank), 4 -> 1.
    const std::vector<std::uint64_t> work = {5, 9, 4, 7, 8, 6};
    const std::vector<int> owner = splitByWork(work, 2);
    EXPECT_EQ(owner, (std::vector<int>{0, 0, 1, 1, 1, 0}));
    EXPECT_EQ(loads(work, owner, 2), (std::vector<std::uint64_t>{20, 19}));
    EXPECT_EQ(splitByWork(work, 2), owner) << "deterministic";
}

TEST(SplitByWork, TiesGoToTheLowestRankAndEveryItemHasOne) {
    EXPECT_EQ(splitByWork({3, 3, 3, 3}, 3), (std::vector<int>{0, 1, 2, 0}));
    EXPECT_EQ(splitByWork({0, 0, 0}, 2), (std::vector<int>{0, 1, 0})) << "unknown sizes still spread";
    EXPECT_EQ(splitByWork({7}, 1), (std::vector<int>{0}));
    EXPECT_TRUE(splitByWork({}, 2).empty());
    EXPECT_THROW(splitByWork({1}, 0), std::invalid_argument);
}

TEST(SplitByWork, OneHugeItemDoesNotDragOthersAlong) {
    std::vector<std::uint64_t> work(20, 1);
    work[7] = 100;
    const std::vector<int> owner = splitByWork(work, 3);
    for (std::size_t i = 0; i < work.size(); ++i) {
        if (i != 7) {
            EXPECT_NE(owner[i], owner[7]) << "item " << i << " shares the rank of the huge one";
        }
    }
    EXPECT_EQ(loads(work, owner, 3)[1] + loads(work, owner, 3)[2], 19u);
}

TEST(ShareItems, OneProcessDoesEveryItemAndGetsThemBackByIndex) {
    gseg::tools::Ranks& ranks = alone();
    std::vector<int> owner;
    std::vector<std::size_t> asked;
    const auto all = gseg::tools::shareItems(ranks, {5, 9, 1}, [&](const std::vector<std::size_t>& mine) {
        asked = mine;
        std::vector<std::string> out;
        for (std::size_t i : mine) out.push_back("item " + std::to_string(i));
        return out;
    }, &owner);
    EXPECT_EQ(asked, (std::vector<std::size_t>{0, 1, 2})) << "ascending";
    EXPECT_EQ(all, (std::vector<std::string>{"item 0", "item 1", "item 2"}));
    EXPECT_EQ(owner, (std::vector<int>{0, 0, 0}));
    auto throws = [](const std::vector<std::size_t>&) -> std::vector<std::string> { throw std::runtime_error("disk gone"); };
    EXPECT_THROW(gseg::tools::shareItems(ranks, {1, 2}, throws), std::runtime_error);
    auto short_ = [](const std::vector<std::size_t>&) { return std::vector<std::string>{"only one"}; };
    EXPECT_THROW(gseg::tools::shareItems(ranks, {1, 2}, short_), std::runtime_error) << "one result per item";
}

TEST(Ranks, WithoutALauncherTheToolIsOneProcess) {
    gseg::tools::Ranks& ranks = alone();
    EXPECT_EQ(ranks.rank(), 0);
    EXPECT_EQ(ranks.size(), 1);
    EXPECT_TRUE(ranks.root());
    EXPECT_EQ(ranks.gather("mine"), (std::vector<std::string>{"mine"}));
    EXPECT_EQ(ranks.broadcast("value"), "value");
    EXPECT_EQ(ranks.firstError(""), "");
    EXPECT_EQ(ranks.firstError("bad file"), "bad file") << "rank 0's message has no prefix";
    EXPECT_EQ(ranks.exitCode(0), 0);
    EXPECT_EQ(ranks.exitCode(3), 3);
    ranks.setTimeout("test", 0.5);  // nothing to watch
    EXPECT_EQ(ranks.gather("still"), (std::vector<std::string>{"still"}));
}

namespace {

std::vector<int> cpusOfThisThread() {
    cpu_set_t set;
    CPU_ZERO(&set);
    std::vector<int> cpus;
    if (::sched_getaffinity(0, sizeof set, &set) == 0)
        for (int c = 0; c < CPU_SETSIZE; ++c)
            if (CPU_ISSET(c, &set)) cpus.push_back(c);
    return cpus;
}

}  // namespace

// #35: rank 0 writes on the cores of the ranks on its machine; one process: its own.
TEST(Ranks, TheCpusOfOneProcessAreItsOwnAndAWiderAffinityIsGivenBack) {
    const std::vector<int> own = cpusOfThisThread();
    ASSERT_FALSE(own.empty());
    EXPECT_EQ(gseg::tools::cpusOfRanksOnThisMachine(alone()), own);
    if (own.size() < 2) GTEST_SKIP() << "one CPU: nothing to widen to";
    // On a thread of its own, bound to the first CPU as mpirun binds a rank.
    std::vector<int> inside, started, after;
    unsigned counted = 0, nothingAdded = 0;
    std::thread([&] {
        cpu_set_t one;
        CPU_ZERO(&one);
        CPU_SET(own[0], &one);
        if (::sched_setaffinity(0, sizeof one, &one) != 0) return;
        nothingAdded = gseg::tools::WiderAffinity({own[0]}).cpus();
        {
            const gseg::tools::WiderAffinity wide({own[0], own[1]});
            counted = wide.cpus();
            inside = cpusOfThisThread();
            std::thread([&] { started = cpusOfThisThread(); }).join();  // a writer it starts
        }
        after = cpusOfThisThread();
    }).join();
    EXPECT_EQ(nothingAdded, 1u);
    EXPECT_EQ(counted, 2u);
    EXPECT_EQ(inside, (std::vector<int>{own[0], own[1]}));
    EXPECT_EQ(started, inside) << "threads started meanwhile inherit the wider set";
    EXPECT_EQ(after, (std::vector<int>{own[0]})) << "given back";
}

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

/// A job started with `sh -c 'exec COMMAND'` (so its pid is the launcher's), stdout and stderr into
/// a pipe the test reads: waiting for a line is waiting on an event, not a sleep.
class Job {
public:
    explicit Job(const std::string& command) {
        int fds[2];
        if (::pipe2(fds, O_CLOEXEC) != 0) return;
        posix_spawn_file_actions_t actions;
        posix_spawn_file_actions_init(&actions);
        posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
        posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
        const std::string exec = "exec " + command;
        const char* argv[] = {"/bin/sh", "-c", exec.c_str(), nullptr};
        if (::posix_spawn(&pid_, "/bin/sh", &actions, nullptr, const_cast<char**>(argv), environ) != 0) pid_ = -1;
        posix_spawn_file_actions_destroy(&actions);
        ::close(fds[1]);
        out_ = fds[0];
    }
    ~Job() {
        if (pid_ > 0) ::kill(pid_, SIGKILL), ::waitpid(pid_, nullptr, 0);
        if (out_ >= 0) ::close(out_);
    }
    pid_t pid() const { return pid_; }
    const std::string& output() const { return text_; }
    /// Reads until `text` has come (true) or the job closed its output (false).
    bool waitFor(const std::string& text) {
        while (text_.find(text) == std::string::npos)
            if (!readSome()) return false;
        return true;
    }
    /// Reads to the end and waits for the job: its exit code (128 + signal if killed).
    int finish() {
        while (readSome()) {
        }
        int st = 0;
        ::waitpid(pid_, &st, 0);
        pid_ = -1;
        return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    }

private:
    pid_t pid_ = -1;
    int out_ = -1;
    std::string text_;
    bool readSome() {
        char buf[4096];
        const ssize_t n = ::read(out_, buf, sizeof buf);
        if (n <= 0) return false;
        text_.append(buf, std::size_t(n));
        return true;
    }
};

/// The child of `parent` that is MPI rank `rank` (OpenMPI puts OMPI_COMM_WORLD_RANK in its
/// environment); -1 if there is none.
pid_t rankProcess(pid_t parent, int rank) {
    const std::string want = "OMPI_COMM_WORLD_RANK=" + std::to_string(rank);
    DIR* proc = ::opendir("/proc");
    pid_t found = -1;
    for (dirent* e; proc && found < 0 && (e = ::readdir(proc));) {
        const pid_t pid = pid_t(std::atoi(e->d_name));
        if (pid <= 0) continue;
        std::ifstream stat("/proc/" + std::string(e->d_name) + "/stat");
        std::string line;
        std::getline(stat, line);
        const std::size_t close = line.rfind(')');
        int ppid = -1;
        char state = 0;
        if (close == std::string::npos || std::sscanf(line.c_str() + close + 1, " %c %d", &state, &ppid) != 2 || ppid != parent)
            continue;
        std::ifstream env("/proc/" + std::string(e->d_name) + "/environ");
        for (std::string var; std::getline(env, var, '\0');)
            if (var == want) found = pid;
    }
    if (proc) ::closedir(proc);
    return found;
}

/// Starts `tool args` on two ranks with --mpi-timeout 2, stops rank 1 (SIGSTOP) once `working`
/// has appeared on the output (rank 0's first progress line: rank 1 is past MPI's start and has
/// work), and checks that the job ends on its own, naming rank 1, within the time-out and a
/// margin, leaving nothing in `dir` but `keep`.
void expectStoppedRankEndsTheJob(const std::string& mpirun, const std::string& tool, const std::string& toolName,
                                 const std::string& args, const std::string& working, const fs::path& dir,
                                 const std::string& keep) {
    Job job(mpirun + "'" + gseg::test::tool(tool) + "' " + args + " --mpi-timeout 2");
    ASSERT_GT(job.pid(), 0);
    ASSERT_TRUE(job.waitFor(working)) << job.output();
    const pid_t rank1 = rankProcess(job.pid(), 1);
    ASSERT_GT(rank1, 0) << "rank 1 of the job";
    ASSERT_EQ(::kill(rank1, SIGSTOP), 0);
    const auto stopped = Clock::now();
    const int code = job.finish();
    const double seconds = std::chrono::duration<double>(Clock::now() - stopped).count();
    if (::kill(rank1, 0) == 0) ::kill(rank1, SIGKILL);  // had the launcher left it (it does not)
    EXPECT_NE(code, 0) << job.output();
    EXPECT_NE(job.output().find(toolName + ": rank 1 has not answered for 2 s (time-out --mpi-timeout); ending the job"),
              std::string::npos) << job.output();
    EXPECT_GT(seconds, 1.5) << "the time-out, not something else, ended it";
    EXPECT_LT(seconds, 20) << "within the time-out and a margin (a loaded machine)";
    std::string left;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.path().filename() != keep) left += e.path().filename().string() + " ";
    EXPECT_EQ(left, "") << "no output, no temporary";
}

}  // namespace

TEST(RanksTimeOut, AStoppedRankEndsRawlogOctomapNamedWithinTheTimeOut) {
    GSEG_TEST_MPIRUN_OR_SKIP(mpirun, 2);
    const std::string seq = gseg::test::sharedData("semantickitti/sequences/00/poses.txt");
    if (seq.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti/sequences/00/poses.txt");
    const fs::path dir = gseg::test::freshDir("ranks", "stopped_octomap");
    // 24 scans: far more work than the first scan's, so rank 1 is stopped in the middle of it.
    const auto r = gseg::test::runCommand("'" + gseg::test::tool("kitti2rawlog") + "' -q --repeat 4 -i '" +
                                          fs::path(seq).parent_path().string() + "' -o '" + (dir / "drive.rawlog").string() + "'");
    ASSERT_EQ(r.status, 0) << r.output;
    expectStoppedRankEndsTheJob(mpirun, "rawlog-octomap", "rawlog-octomap",
                                "-i '" + (dir / "drive.rawlog").string() + "' -o '" + (dir / "m").string() + "' -c '" +
                                    GSEG_SOURCE_DIR + "/config/kitti_hdl64.yaml' --threads 1",
                                "rawlog-octomap: 1 scans", dir, "drive.rawlog");
}

TEST(RanksTimeOut, AStoppedRankEndsGsegEvalNamedWithinTheTimeOut) {
    GSEG_TEST_MPIRUN_OR_SKIP(mpirun, 2);
    const std::string root = gseg::test::sharedData("semantickitti-extra/sequences");
    if (root.empty()) GTEST_SKIP() << gseg::test::missingDataMessage("semantickitti-extra/sequences");
    const fs::path dir = gseg::test::freshDir("ranks", "stopped_eval");
    expectStoppedRankEndsTheJob(mpirun, "gseg", "gseg eval",
                                "eval -i '" + fs::path(root).parent_path().string() + "' --threads 1 --report '" +
                                    (dir / "out/r").string() + "'",
                                "gseg eval: 1 frames", dir, "");
}

TEST(RanksTimeOut, TheOptionIsCheckedLikeEveryOther) {
    for (const char* bad : {"-1", "soon", "nan"}) {
        const auto r = gseg::test::runCommand("'" + gseg::test::tool("rawlog-octomap") + "' -i x.rawlog -o x --mpi-timeout " + bad);
        EXPECT_EQ(r.status, 2) << r.output;
        EXPECT_NE(r.output.find("rawlog-octomap: --mpi-timeout needs a number of seconds >= 0 (0: none), got '" + std::string(bad) + "'"),
                  std::string::npos) << r.output;
    }
    const auto help = gseg::test::runCommand("'" + gseg::test::tool("gseg") + "' eval --help");
    EXPECT_NE(help.output.find("--mpi-timeout"), std::string::npos) << help.output;
    EXPECT_NE(help.output.find("(default 60; 0: wait for ever)"), std::string::npos) << help.output;
    const auto split = gseg::test::runCommand("'" + gseg::test::tool("rawlog-gseg") + "' --help");
    EXPECT_NE(split.output.find("--mpi-timeout"), std::string::npos) << split.output;
}
