// Ranks with MPI (GSEG_WITH_MPI on). MPI is initialised only when a launcher started the process;
// every MPI call is made under one lock (MPI_THREAD_SERIALIZED), and waiting polls with short
// sleeps so a waiting rank leaves its core to the work.
#include "ranks.hpp"

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <climits>
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

constexpr int kGatherTag = 1, kBroadcastTag = 2;

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
    for (Backoff wait;; wait.pause()) {
        std::lock_guard<std::mutex> lock(mpiLock());
        int found = 0;
        MPI_Message message;
        MPI_Status status;
        MPI_Improbe(from, tag, MPI_COMM_WORLD, &found, &message, &status);
        if (!found) continue;
        int count = 0;
        MPI_Get_count(&status, MPI_BYTE, &count);
        std::string bytes(std::size_t(count), '\0');
        MPI_Mrecv(bytes.data(), count, MPI_BYTE, &message, MPI_STATUS_IGNORE);
        return bytes;
    }
}

void checkTag(int tag) {
    if (tag < Ranks::kFirstToolTag)
        throw std::logic_error("Ranks: tags below " + std::to_string(Ranks::kFirstToolTag) + " are reserved");
}

}  // namespace

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
    if (rank_ != 0) {  // rank 0 prints for all
        const int null = ::open("/dev/null", O_WRONLY);
        if (null >= 0) ::dup2(null, STDOUT_FILENO), ::dup2(null, STDERR_FILENO), ::close(null);
    }
}

Ranks::~Ranks() {
    if (!mpi_) return;
    std::fflush(nullptr);
    std::cout.flush();
    MPI_Finalize();
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
