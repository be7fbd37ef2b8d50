#include "remote_workers.hpp"

#include <gseg/io/atomic_file.hpp>
#include <gseg/io/bytes.hpp>
#include <gseg/map/memory_policy.hpp>
#include <gseg/map/scan_message.hpp>
#include <gseg/mrpt/errors.hpp>

#include <algorithm>
#include <cstdio>
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
