// Ranks with MPI (GSEG_WITH_MPI on). MPI is initialised only when a launcher started the process;
// every MPI call is made under one lock (MPI_THREAD_SERIALIZED), none of them blocks (so the
// heartbeat thread always gets its turn), and waiting polls with short sleeps so a waiting rank
// leaves its core to the work.
#include "ranks.hpp"

#include <gseg/io/atomic_file.hpp>

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <fcntl.h>
#include <iostream>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <unistd.h>

namespace gseg::tools {
namespace {

constexpr int kGatherTag = 1, kBroadcastTag = 2, kHeartbeatTag = 3;
constexpr char kBeat = 'h', kBye = 'b';  ///< heartbeat messages: "still here", "done, nothing more from me"
using Clock = std::chrono::steady_clock;

std::mutex& mpiLock() {
    static std::mutex m;
    return m;
}

/// Started by mpirun/mpiexec (OpenMPI, MPICH's Hydra) or srun with PMI/PMIx.
bool startedByLauncher() {
    for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
        if (std::getenv(v)) return true;
    return false;
}

/// Sleeps 20 us, then twice as long each time up to 1 ms: a reply within a millisecond of being
/// sent is seen at once, and an idle wait costs well under 1 % of a core.
class Backoff {
public:
    void pause() {
        std::this_thread::sleep_for(std::chrono::microseconds(us_));
        us_ = std::min(2 * us_, 1000);
    }

private:
    int us_ = 20;
};

void sendBytes(int to, int tag, const std::string& bytes) {
    if (bytes.size() > std::size_t(INT_MAX))
        throw std::length_error("message of " + std::to_string(bytes.size()) + " bytes: too large to send");
    MPI_Request request;
    {
        std::lock_guard<std::mutex> lock(mpiLock());
        MPI_Isend(bytes.data(), int(bytes.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD, &request);
    }
    for (Backoff wait;; wait.pause()) {
        int done = 0;
        {
            std::lock_guard<std::mutex> lock(mpiLock());
            MPI_Test(&request, &done, MPI_STATUS_IGNORE);
        }
        if (done) return;
    }
}

std::string receiveBytes(int from, int tag) {
    std::string bytes;
    MPI_Request request = MPI_REQUEST_NULL;
    for (Backoff wait;; wait.pause()) {
        std::lock_guard<std::mutex> lock(mpiLock());
        int found = 0;
        MPI_Message message;
        MPI_Status status;
        MPI_Improbe(from, tag, MPI_COMM_WORLD, &found, &message, &status);
        if (!found) continue;
        int count = 0;
        MPI_Get_count(&status, MPI_BYTE, &count);
        bytes.assign(std::size_t(count), '\0');
        // Not MPI_Mrecv: a large message from a rank that stops half-way would block there, under
        // the lock, and keep the heartbeat thread from noticing.
        MPI_Imrecv(bytes.data(), count, MPI_BYTE, &message, &request);
        break;
    }
    for (Backoff wait;; wait.pause()) {
        int done = 0;
        {
            std::lock_guard<std::mutex> lock(mpiLock());
            MPI_Test(&request, &done, MPI_STATUS_IGNORE);
        }
        if (done) return bytes;
    }
}

void checkTag(int tag) {
    if (tag < Ranks::kFirstToolTag)
        throw std::logic_error("Ranks: tags below " + std::to_string(Ranks::kFirstToolTag) + " are reserved");
}

}  // namespace

/// The heartbeats of one rank and the time-out on those it watches (rank 0: every other rank;
/// the others: rank 0), in a thread of its own: every tick it sends a heartbeat to each watched
/// rank, takes in theirs, and ends the job when one has been silent for the time-out.
class Ranks::Watch {
public:
    Watch(int rank, int size, int stderrFd) : rank_(rank), stderrFd_(stderrFd), heard_(std::size_t(size), Clock::now()),
                                              bye_(std::size_t(size), rank != 0) {
        if (rank == 0)
            for (int r = 1; r < size; ++r) peers_.push_back(r);
        else
            peers_.push_back(0), bye_[0] = false;
        bye_[std::size_t(rank)] = true;
        thread_ = std::thread([this] { loop(); });
    }
    ~Watch() {
        {
            std::lock_guard<std::mutex> lock(m_);
            stop_ = true;
        }
        cv_.notify_all();
        if (thread_.joinable()) thread_.join();
    }
    void setTimeout(const std::string& tool, double seconds) {
        std::lock_guard<std::mutex> lock(m_);
        tool_ = tool, timeout_ = seconds;
    }
    /// The goodbyes: has the thread send its last message to each watched rank and waits for
    /// theirs (still under the time-out); then the thread ends.
    void finish() {
        std::unique_lock<std::mutex> lock(m_);
        wantBye_ = true;
        cv_.notify_all();
        cv_.wait(lock, [&] { return done_; });
        lock.unlock();
        thread_.join();
    }
    /// Runs `finalize` (MPI_Finalize), ending the process if it does not return within the
    /// time-out (a rank that stopped after its goodbye would hold every rank there).
    void bounded(const std::function<void()>& finalize) {
        double timeout = 0;
        std::string tool;
        {
            std::lock_guard<std::mutex> lock(m_);
            timeout = timeout_, tool = tool_, stop_ = false;
        }
        std::thread guard;
        if (timeout > 0)
            guard = std::thread([=] {
                std::unique_lock<std::mutex> lock(m_);
                if (cv_.wait_for(lock, std::chrono::duration<double>(timeout), [&] { return stop_; })) return;
                say(tool + ": MPI_Finalize has not ended after " + seconds(timeout) + " s (time-out --mpi-timeout): a rank "
                    "stopped answering; ending");
                std::_Exit(1);
            });
        finalize();
        {
            std::lock_guard<std::mutex> lock(m_);
            stop_ = true;
        }
        cv_.notify_all();
        if (guard.joinable()) guard.join();
    }

private:
    const int rank_;
    const int stderrFd_;  ///< where the time-out is said (rank 0's stderr; the others keep theirs for it)
    std::vector<int> peers_;
    std::vector<Clock::time_point> heard_;  ///< by rank: when its last heartbeat came in
    std::vector<bool> bye_;                 ///< by rank: said goodbye (or not watched)
    std::mutex m_;
    std::condition_variable cv_;
    std::string tool_ = "gseg";
    double timeout_ = kDefaultTimeout;
    bool stop_ = false, wantBye_ = false, byeSent_ = false, done_ = false;
    std::thread thread_;

    static std::string seconds(double s) {
        char text[32];
        std::snprintf(text, sizeof text, "%g", s);
        return text;
    }
    void say(const std::string& line) const {
        const std::string text = line + "\n";
        if (::write(stderrFd_, text.data(), text.size()) < 0) {
        }
    }

    void loop() {
        Clock::time_point last = Clock::now();
        std::unique_lock<std::mutex> lock(m_);
        while (!stop_) {
            const double timeout = timeout_;
            // While saying goodbye, listen closely: the ranks end together (a rank that ends with
            // a non-zero code before the others makes the launcher kill them).
            const auto tick = std::chrono::duration<double>(wantBye_ ? 0.001 : timeout > 0 ? std::clamp(timeout / 10, 0.02, 0.25) : 0.25);
            const bool bye = wantBye_ && !byeSent_;
            lock.unlock();
            exchange(bye ? kBye : byeSent_ ? 0 : kBeat);
            lock.lock();
            byeSent_ = byeSent_ || bye;
            const Clock::time_point now = Clock::now();
            // This rank itself did not run for a while (the whole job stopped with Ctrl-Z, a
            // loaded machine): the others get a fresh time-out rather than the blame.
            if (timeout > 0 && now - last > std::chrono::duration<double>(timeout / 2))
                for (auto& t : heard_) t = now;
            last = now;
            bool all = true;
            for (int p : peers_) {
                if (bye_[std::size_t(p)]) continue;
                all = false;
                if (timeout > 0 && now - heard_[std::size_t(p)] > std::chrono::duration<double>(timeout)) {
                    const std::string tool = tool_;
                    lock.unlock();
                    endJob(tool + ": rank " + std::to_string(p) + " has not answered for " + seconds(timeout) +
                           " s (time-out --mpi-timeout); ending the job");
                }
            }
            if (byeSent_ && all) {
                done_ = true;
                cv_.notify_all();
                return;
            }
            cv_.wait_for(lock, tick, [&] { return stop_ || (wantBye_ && !byeSent_); });
        }
    }

    /// Under the MPI lock: `send` (a beat or the goodbye; 0: nothing) to each watched rank, and
    /// every heartbeat that came in.
    void exchange(char send) {
        static const char beat = kBeat, bye = kBye;
        std::lock_guard<std::mutex> mpi(mpiLock());
        if (send)
            for (int p : peers_) {
                MPI_Request request;
                MPI_Isend(send == kBye ? &bye : &beat, 1, MPI_BYTE, p, kHeartbeatTag, MPI_COMM_WORLD, &request);
                MPI_Request_free(&request);  // a constant buffer: nothing to wait for
            }
        for (;;) {
            int found = 0;
            MPI_Status status;
            MPI_Iprobe(MPI_ANY_SOURCE, kHeartbeatTag, MPI_COMM_WORLD, &found, &status);
            if (!found) return;
            char c = 0;
            MPI_Recv(&c, 1, MPI_BYTE, status.MPI_SOURCE, kHeartbeatTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
            std::lock_guard<std::mutex> lock(m_);
            heard_[std::size_t(status.MPI_SOURCE)] = Clock::now();
            if (c == kBye) bye_[std::size_t(status.MPI_SOURCE)] = true;
        }
    }

    /// Says why, removes this process's temporaries (the launcher then ends every rank with
    /// SIGTERM, whose handler removes the rest) and ends every rank.
    [[noreturn]] void endJob(const std::string& why) {
        say(why);
        // The temporaries being written now; the launcher's SIGTERM after MPI_Abort then runs the
        // output layer's own cleanup (gseg::io::installTemporaryCleanup()) for whatever is left.
        for (const std::string& t : gseg::io::registeredTemporaries()) ::unlink(t.c_str());
        std::unique_lock<std::mutex> mpi(mpiLock(), std::defer_lock);
        for (int i = 0; i < 100 && !mpi.try_lock(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
        MPI_Abort(MPI_COMM_WORLD, 1);
        std::_Exit(1);
    }
};

Ranks::Ranks(int& argc, char**& argv) {
    if (!startedByLauncher()) return;
    int provided = 0;
    MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided);
    mpi_ = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    if (provided < MPI_THREAD_SERIALIZED) {
        if (rank_ == 0) std::fprintf(stderr, "MPI gives thread level %d, gseg needs MPI_THREAD_SERIALIZED\n", provided);
        MPI_Abort(MPI_COMM_WORLD, 1);  // an environment that cannot run the tools at all
    }
    int sayFd = STDERR_FILENO;
    if (rank_ != 0) {  // rank 0 prints for all (but a time-out is said where it is seen)
        sayFd = ::fcntl(STDERR_FILENO, F_DUPFD_CLOEXEC, 3);
        const int null = ::open("/dev/null", O_WRONLY);
        if (null >= 0) ::dup2(null, STDOUT_FILENO), ::dup2(null, STDERR_FILENO), ::close(null);
        if (sayFd < 0) sayFd = STDERR_FILENO;
    }
    if (size_ > 1) watch_ = std::make_unique<Watch>(rank_, size_, sayFd);
}

Ranks::~Ranks() {
    if (!mpi_) return;
    std::fflush(nullptr);
    std::cout.flush();
    if (!watch_) {
        MPI_Finalize();
        return;
    }
    watch_->finish();
    watch_->bounded([] { MPI_Finalize(); });
}

void Ranks::setTimeout(const std::string& tool, double seconds) {
    if (watch_) watch_->setTimeout(tool, seconds);
}

bool Ranks::built() { return true; }

void Ranks::send(int to, int tag, const std::string& bytes) {
    checkTag(tag);
    sendBytes(to, tag, bytes);
}

std::string Ranks::receive(int from, int tag) {
    checkTag(tag);
    return receiveBytes(from, tag);
}

std::vector<std::string> Ranks::gather(const std::string& mine) {
    if (rank_ != 0) {
        sendBytes(0, kGatherTag, mine);
        return {};
    }
    std::vector<std::string> all{mine};
    for (int r = 1; r < size_; ++r) all.push_back(receiveBytes(r, kGatherTag));
    return all;
}

std::string Ranks::broadcast(const std::string& value) {
    if (rank_ != 0) return receiveBytes(0, kBroadcastTag);
    for (int r = 1; r < size_; ++r) sendBytes(r, kBroadcastTag, value);
    return value;
}

}  // namespace gseg::tools
