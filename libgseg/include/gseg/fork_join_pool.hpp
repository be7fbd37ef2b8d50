#pragma once
/// \file fork_join_pool.hpp
/// gseg's one intra-task pool: several threads on the parts of one task (the cells of one scan),
/// next to gseg::runOrdered (ordered_pipeline.hpp), the one pool for streams of tasks (scans,
/// frames). The threads are started once and kept (a GroundSegmenter with Params::threads > 1
/// owns one in its workspace), so a scan pays no thread start. Each part writes only its own
/// results, so what a task computes never depends on the number of threads or on timing.

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace gseg {

/// A fixed set of threads that run the parts of one call of run() together with the caller.
class ForkJoinPool {
public:
    /// `threads` >= 1 threads in all, the caller included (threads - 1 are started here).
    explicit ForkJoinPool(unsigned threads);
    ~ForkJoinPool();
    ForkJoinPool(const ForkJoinPool&) = delete;
    ForkJoinPool& operator=(const ForkJoinPool&) = delete;

    /// Threads in all, the caller included.
    unsigned threads() const { return unsigned(workers_.size()) + 1; }

    /// Runs `part(p, thread)` for every p in [0, parts) and returns when all have run; `thread` in
    /// [0, threads()) names the thread running it (0: the caller), for per-thread scratch memory.
    /// Parts are taken in increasing order by whichever thread is free. If parts throw, the
    /// exception of the lowest part is rethrown here after all parts have ended. One run() at a
    /// time (not reentrant).
    void run(std::size_t parts, const std::function<void(std::size_t part, unsigned thread)>& part);

    /// run() over [0, n) in chunks of `chunk` items: `body(begin, end, thread)`.
    template <class Body>
    void forRange(std::size_t n, std::size_t chunk, Body&& body) {
        if (n == 0) return;
        const std::size_t parts = (n + chunk - 1) / chunk;
        run(parts, [&](std::size_t p, unsigned thread) { body(p * chunk, std::min(n, (p + 1) * chunk), thread); });
    }

private:
    void loop(unsigned thread);
    void work(unsigned thread);

    std::vector<std::thread> workers_;
    std::mutex mutex_;
    std::condition_variable start_, done_;
    std::size_t generation_ = 0;   // incremented per run()
    unsigned busy_ = 0;            // workers still in the current run()
    bool stop_ = false;
    const std::function<void(std::size_t, unsigned)>* part_ = nullptr;
    std::size_t parts_ = 0;
    std::atomic<std::size_t> next_{0};
    std::exception_ptr error_;
    std::size_t errorPart_ = 0;
};

}  // namespace gseg
