#include "remote_workers.hpp"

#include <gseg/io/atomic_file.hpp>
#include <gseg/io/bytes.hpp>
#include <gseg/map/memory_policy.hpp>
#include <gseg/map/scan_message.hpp>
#include <gseg/mrpt/errors.hpp>

#include <gseg/map/scan_update.hpp>

#include <algorithm>
#include <condition_variable>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <new>
#include <stdexcept>
#include <thread>

using gseg::io::ByteReader;
using gseg::io::ByteWriter;

namespace rawlog_octomap {
namespace {

constexpr int kHelloTag = gseg::tools::Ranks::kFirstToolTag;  // rank r -> 0: its worker threads
constexpr int kJobTag = kHelloTag + 1000;                      // + thread: 0 -> r, a scan ("" = stop)
constexpr int kResultTag = kJobTag + 1000;                     // + thread: r -> 0, its result
constexpr int kPartTag = kResultTag + 1000;                    // 0 -> holder: a scan's voxels, the end, or stop
constexpr int kVoxelsTag = kPartTag + 1;                       // holder -> 0: its voxels ("GSB1...") or "E" and its error
enum PartKind : std::uint64_t { kPart = 0, kEnd = 1, kStop = 2 };

/// A holder of voxels on rank r > 0 (#35): its part of every scan's update, from rank 0 (the scans
/// cast there or on other ranks) and from this rank's workers, applied in scan order on a thread
/// of its own. At the end (rank 0 says how many scans there were) it sends its voxels to rank 0.
class VoxelHolder {
public:
    VoxelHolder(gseg::tools::Ranks& ranks, const gseg::map::TraversabilityOptions& options) : ranks_(ranks) {
        try {
            map_ = std::make_unique<gseg::map::TraversabilityMap>(options);
            map_->shareVoxels(ranks.rank(), ranks.size());
        } catch (const std::exception& e) {
            error_ = gseg::mrpt::errorReason(e);
        }
        receiver_ = std::thread([this] { receive(); });
        applier_ = std::thread([this] { apply(); });
    }
    ~VoxelHolder() {
        receiver_.join();
        applier_.join();
    }
    VoxelHolder(const VoxelHolder&) = delete;
    VoxelHolder& operator=(const VoxelHolder&) = delete;

    /// A scan's part, cast here. Waits while kMaxWaiting parts wait to be applied (unless this
    /// one is the next), so this rank's workers do not run ahead of its voxels; rank 0's parts
    /// are taken at once (the one needed next may come after them).
    void add(std::size_t scan, gseg::map::ScanUpdate part) {
        std::unique_lock<std::mutex> lock(m_);
        changed_.wait(lock, [&] { return stop_ || scan == next_ || waiting_.size() < kMaxWaiting; });
        waiting_.emplace(scan, std::move(part));
        changed_.notify_all();
    }

private:
    /// Rank 0's messages, until the end or stop.
    void receive() {
        while (true) {
            const std::string bytes = ranks_.receive(0, kPartTag);
            ByteReader in(bytes);
            const std::uint64_t kind = in.u64(), n = in.u64();
            std::lock_guard<std::mutex> lock(m_);
            if (kind == kPart) {
                try {
                    waiting_.emplace(std::size_t(n), gseg::map::deserializeScanUpdate(in.str()));
                } catch (const std::exception& e) {
                    if (error_.empty()) error_ = gseg::mrpt::errorReason(e);
                    waiting_.emplace(std::size_t(n), gseg::map::ScanUpdate());
                }
            } else if (kind == kEnd) {
                total_ = std::size_t(n);
            } else {
                stop_ = true;
            }
            changed_.notify_all();
            if (kind != kPart) return;
        }
    }

    /// The parts in scan order; then the voxels (or the first error) to rank 0.
    void apply() {
        std::string failed;  // this thread's first error
        std::unique_lock<std::mutex> lock(m_);
        while (true) {
            changed_.wait(lock, [&] { return stop_ || next_ == total_ || waiting_.count(next_); });
            if (stop_) return;
            if (next_ == total_) break;
            auto node = waiting_.extract(next_++);
            changed_.notify_all();  // room for a part add() holds back
            if (failed.empty() && !error_.empty()) failed = error_;
            lock.unlock();
            try {
                if (failed.empty()) map_->apply(node.mapped());
            } catch (const std::bad_alloc&) {
                failed = "out of memory holding the voxels of rank " + std::to_string(ranks_.rank());
            } catch (const std::exception& e) {
                failed = gseg::mrpt::errorReason(e);
            }
            lock.lock();
        }
        if (failed.empty()) failed = error_;
        lock.unlock();
        std::string reply;
        try {
            if (failed.empty()) reply = map_->voxelBytes();  // "GSB1...": the voxels
            map_.reset();
        } catch (const std::bad_alloc&) {
            failed = "out of memory sending the voxels of rank " + std::to_string(ranks_.rank());
        }
        if (!failed.empty()) reply = "E" + ("rank " + std::to_string(ranks_.rank()) + ": " + failed);
        ranks_.send(0, kVoxelsTag, reply);
    }

    static constexpr std::size_t kMaxWaiting = 8;
    gseg::tools::Ranks& ranks_;
    std::unique_ptr<gseg::map::TraversabilityMap> map_;
    std::mutex m_;
    std::condition_variable changed_;
    std::map<std::size_t, gseg::map::ScanUpdate> waiting_;  ///< parts by scan, not yet applied
    std::size_t next_ = 0, total_ = std::numeric_limits<std::size_t>::max();
    bool stop_ = false;
    std::string error_;  ///< the first error of the receiving thread or the set-up (the voxels are not sent then)
    std::thread receiver_, applier_;
};

}  // namespace

RemoteWorkers::RemoteWorkers(gseg::tools::Ranks& ranks) : ranks_(ranks) {
    for (int r = 1; r < ranks.size(); ++r) {
        const std::string hello = ranks.receive(r, kHelloTag);
        ByteReader in(hello);
        for (std::uint64_t j = 0, n = in.u64(); j < n; ++j) slots_.emplace_back(r, int(j));
    }
}

RemoteWorkers::~RemoteWorkers() {
    for (const auto& [rank, thread] : slots_) ranks_.send(rank, kJobTag + thread, "");
    if (!merged_)
        for (int q = 1; q < holders(); ++q) ranks_.send(q, kPartTag, ByteWriter().u64(kStop).u64(0).take());
}

int RemoteWorkers::holders() const { return std::min(ranks_.size(), int(gseg::map::kVoxelHolders)); }

void RemoteWorkers::route(const ScanJob& job, ScanResult& r) {
    for (int q = 1; q < holders(); ++q) {
        if (q == r.rank) continue;  // it kept its part
        const std::string part = gseg::map::serializeScanUpdate(gseg::map::takeVoxels(r.update, q, ranks_.size()));
        ranks_.send(q, kPartTag, ByteWriter().u64(kPart).u64(job.index).str(part).take());
    }
}

std::vector<std::size_t> RemoteWorkers::mergeVoxels(gseg::map::MapBuilder& builder, std::size_t scans) {
    merged_ = true;
    for (int q = 1; q < holders(); ++q) ranks_.send(q, kPartTag, ByteWriter().u64(kEnd).u64(scans).take());
    std::vector<std::string> replies;  // every holder's, before any error is thrown (none is left sending)
    for (int q = 1; q < holders(); ++q) replies.push_back(ranks_.receive(q, kVoxelsTag));
    for (const std::string& reply : replies)
        if (reply.compare(0, 1, "E") == 0) throw std::runtime_error(reply.substr(1));
    std::vector<std::size_t> bricks;
    for (std::string& reply : replies) {
        builder.mergeVoxels(reply);  // GSB1, then the brick count
        bricks.push_back(std::size_t(ByteReader(reply, "voxels", 4).u64()));
        std::string().swap(reply);
    }
    return bricks;
}

ScanResult RemoteWorkers::operator()(unsigned slot, const ScanJob& job) {
    const auto [rank, thread] = slots_.at(slot);
    ranks_.send(rank, kJobTag + thread, gseg::map::encodeScanJob(job));
    return gseg::map::decodeScanResult(ranks_.receive(rank, kResultTag + thread));
}

void serveScans(gseg::tools::Ranks& ranks, const Cli& cli) {
    const unsigned threads = std::max(1u, cli.threads);
    std::vector<ScanWorker> workers;
    std::string setupError;
    try {
        for (unsigned i = 0; i < threads; ++i) workers.emplace_back(cli.loaded, cli.options);
    } catch (const std::exception& e) {
        setupError = gseg::mrpt::errorReason(e);
    }
    // This rank's voxels (#35), if it holds some: a thread applying them, one receiving rank 0's parts.
    std::unique_ptr<VoxelHolder> holder;
    if (ranks.rank() < int(gseg::map::kVoxelHolders)) holder = std::make_unique<VoxelHolder>(ranks, cli.options);
    ranks.send(0, kHelloTag, ByteWriter().u64(threads).bytes());
    auto serve = [&](unsigned thread) {
        for (std::string bytes; !(bytes = ranks.receive(0, kJobTag + int(thread))).empty();) {
            std::string reply;
            std::string scan = "a scan";
            try {
                const ScanJob job = gseg::map::decodeScanJob(bytes);
                scan = job.describe();
                if (!setupError.empty()) throw std::runtime_error(scan + ": rank " + std::to_string(ranks.rank()) + ": " + setupError);
                ScanResult r = workers[thread](job);
                r.rank = ranks.rank();
                if (holder) {  // its part of the voxels stays here
                    holder->add(job.index, gseg::map::takeVoxels(r.update, ranks.rank(), ranks.size()));
                }
                reply = gseg::map::encodeScanResult(r);
            } catch (const std::bad_alloc&) {
                reply = gseg::map::encodeScanError(gseg::map::outOfMemoryMessage(
                    "segmenting and ray casting " + scan + " on rank " + std::to_string(ranks.rank()), cli.options));
            } catch (const std::exception& e) {  // the worker's errors name the scan
                const std::string reason = gseg::mrpt::errorReason(e);
                reply = gseg::map::encodeScanError(reason.rfind(scan, 0) == 0 ? reason : scan + " on rank " + std::to_string(ranks.rank()) + ": " + reason);
            }
            ranks.send(0, kResultTag + int(thread), reply);
        }
    };
    std::vector<std::thread> pool;
    for (unsigned t = 1; t < threads; ++t) pool.emplace_back(serve, t);
    serve(0);
    for (auto& t : pool) t.join();
}

}  // namespace rawlog_octomap
