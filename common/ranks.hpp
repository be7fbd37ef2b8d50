#pragma once
/// \file ranks.hpp
/// The processes of one tool run (#12): the ranks of an MPI job when the tool was started by an
/// MPI launcher (`mpirun`, `mpiexec`, `srun --mpi=pmix`) in a build with GSEG_WITH_MPI, otherwise
/// this process alone (rank 0 of 1, exactly the tool as without MPI: MPI is not even initialised).
/// Tool code is the same either way; with one rank nothing is ever sent.
///
/// Messages are byte strings between rank 0 and the others. Waiting for one sleeps in short steps
/// instead of spinning (MPI libraries busy-poll by default, which takes a core from the work when
/// ranks share a machine). Every call is thread-safe.
///
/// Only rank 0 prints: the other ranks' stdout and stderr go to /dev/null, everything they have to
/// say (results, errors naming the item) is sent to rank 0.
///
/// A rank that stops answering (stopped, swapped out, its node gone silent) would otherwise hang
/// the job, since MPI only notices processes that end. So every rank sends a heartbeat several
/// times a second from a thread of its own, whatever its other threads do (rank 0 to every rank,
/// the others to rank 0), and watches those it hears from: one silent for the time-out
/// (`--mpi-timeout`, setTimeout(); default kDefaultTimeout) has the watching rank print
/// "<tool>: rank N has not answered for T s (time-out --mpi-timeout); ending the job", remove
/// its registered temporaries (gseg::io::AtomicFile) and end the whole job (MPI_Abort, exit 1).
/// At the end every rank says goodbye to those it watches and waits for theirs, so no heartbeat
/// is left in flight at MPI_Finalize, and MPI_Finalize itself is bounded by the time-out.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace gseg::tools {

class Ranks {
public:
    /// Joins the MPI job if started by a launcher (MPI_Init_thread, MPI_THREAD_SERIALIZED).
    /// Throws std::runtime_error if MPI cannot give that thread level.
    Ranks(int& argc, char**& argv);
    ~Ranks();  ///< MPI_Finalize
    Ranks(const Ranks&) = delete;
    Ranks& operator=(const Ranks&) = delete;

    int rank() const { return rank_; }
    int size() const { return size_; }
    bool root() const { return rank_ == 0; }
    /// Whether this build has MPI support (GSEG_WITH_MPI).
    static bool built();

    /// Point to point. Messages between two ranks with the same tag arrive in the order sent.
    /// `tag` >= kFirstToolTag; an empty string is a valid message.
    void send(int to, int tag, const std::string& bytes);
    std::string receive(int from, int tag);
    static constexpr int kFirstToolTag = 100;

    /// Collective (every rank calls it, in the same order): on rank 0 every rank's `mine` in rank
    /// order; on the others an empty vector.
    std::vector<std::string> gather(const std::string& mine);
    /// Collective: rank 0's `value` on every rank.
    std::string broadcast(const std::string& value);
    /// Collective: "" if `mine` is "" on every rank, else the first rank's message (prefixed
    /// "rank N: " for N > 0), on every rank. For setup errors that must stop all ranks alike.
    std::string firstError(const std::string& mine);
    /// Collective, at the end of a run: the exit code of the run, on every rank (rank 0's, or if
    /// that is 0, the first non-zero code of another rank), so the launcher's exit status is the tool's.
    int exitCode(int mine);

    /// [s] How long a rank may stay silent before the job is ended (see above), unless set.
    static constexpr double kDefaultTimeout = 60;
    /// Sets the time-out (`seconds` > 0; 0: none) and the tool's name for the time-out message.
    /// Every rank sets the same (they parse the same command line); until then kDefaultTimeout.
    /// Without MPI: nothing to watch.
    void setTimeout(const std::string& tool, double seconds);

private:
    int rank_ = 0, size_ = 1;
    bool mpi_ = false;  ///< MPI initialised by this object
    class Watch;
    std::unique_ptr<Watch> watch_;  ///< heartbeats and the time-out (MPI with more than one rank)
};

/// Has the ranks share items 0..n-1: split by `work` (splitByWork()), each rank does its own with
/// `doMine` (their indices, ascending; it returns one byte string per item, in that order), and
/// rank 0 gets every item's bytes by index (the other ranks get an empty vector). `owner`, if
/// given, receives each item's rank. Collective. If `doMine` throws on any rank, every rank throws
/// std::runtime_error with the first rank's message (Ranks::firstError()).
std::vector<std::string> shareItems(Ranks& ranks, const std::vector<std::uint64_t>& work,
                                    const std::function<std::vector<std::string>(const std::vector<std::size_t>&)>& doMine,
                                    std::vector<int>* owner = nullptr);

/// Collective: on rank 0 the CPUs (ascending ids) that the ranks on rank 0's machine may run on,
/// its own included (each rank's affinity: `mpirun` binds each rank to its cores); on the other
/// ranks an empty vector. Without MPI: this process's CPUs. For rank 0's work after the others
/// are done (the writing): their cores are idle then.
std::vector<int> cpusOfRanksOnThisMachine(Ranks& ranks);

/// Lets the calling thread, and the threads it starts from now on, run on `cpus` as well as on
/// its own CPUs (sched_setaffinity); the destructor gives it back its own. Nothing if `cpus` adds
/// none or the system refuses (a cpuset without them): cpus() then says its own.
class WiderAffinity {
public:
    explicit WiderAffinity(const std::vector<int>& cpus);
    ~WiderAffinity();
    WiderAffinity(const WiderAffinity&) = delete;
    WiderAffinity& operator=(const WiderAffinity&) = delete;
    /// How many CPUs the calling thread may run on now.
    unsigned cpus() const { return count_; }

private:
    std::vector<unsigned char> own_;  ///< the thread's cpu_set_t before, restored (empty: unchanged)
    unsigned count_ = 1;
};

/// The work of files for shareItems(): their sizes in bytes (0 where a size cannot be read).
std::vector<std::uint64_t> fileSizes(const std::vector<std::string>& paths);

/// Splits items over `ranks` by their work (e.g. bytes or points): the largest first, each to the
/// rank with the least work so far (on ties the one with fewer items, then the lowest rank). Deterministic; returns the rank of
/// each item. Throws std::invalid_argument if `ranks` < 1.
std::vector<int> splitByWork(const std::vector<std::uint64_t>& work, int ranks);

}  // namespace gseg::tools
