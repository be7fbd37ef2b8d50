#pragma once
/// \file ordered_pipeline.hpp
/// gseg's one worker pool: items are produced in order, worked on in parallel, and their results
/// consumed strictly in item order, with a bounded number of items in flight. Map building
/// (gseg::map::MapBuilder: scans read, segmented and ray cast in parallel, the map updates in scan
/// order), `gseg eval` (frames scored in parallel, reported in order) and `gseg bench` (one timing
/// run per thread) all run on it.
///
/// The three roles are plain functions, so the same split serves other transports: rawlog-octomap
/// under MPI gives this pipeline one more worker per worker thread of every other process, whose
/// `work` sends the item there and waits for its result (a serialised ScanUpdate); the maps are
/// the same bytes as one process's.

#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace gseg {

/// The cores this process may run on: its CPU affinity (taskset, a Slurm or container cpuset, an
/// MPI launcher's binding: `mpirun -np 1` binds its rank to one core), at least 1. The default
/// worker count of every tool and of the rawlog reader's decode threads:
/// std::thread::hardware_concurrency() counts the machine's cores, and threads beyond the
/// process's own only take turns on them.
unsigned usableCores();

/// How runOrdered() runs.
struct PipelineOptions {
    unsigned workers = 2;      ///< worker threads; 0: everything on the calling thread, one item at a time
    std::size_t capacity = 6;  ///< items in flight at most (produced, not yet consumed): bounds memory; >= 1
};

/// Runs `produce` on the calling thread until it returns false (it fills the next item),
/// `work(worker, item)` on the worker threads (`worker` in [0, workers), so each worker can keep
/// its own state), and `consume(index, result)` on one thread for index 0, 1, 2, ... in order.
///
/// Errors: an exception thrown by any role is rethrown here once every thread has ended; if
/// several are thrown, the one of the earliest item (a producer error counts at the index of the
/// item it was producing), so the error does not depend on timing. Items after an error are not
/// consumed; every item before it is.
template <class Item, class Result>
void runOrdered(const std::function<bool(Item&)>& produce, const std::function<Result(unsigned, Item&)>& work,
                const std::function<void(std::size_t, Result&)>& consume, const PipelineOptions& options) {
    if (options.workers == 0) {
        for (std::size_t index = 0;; ++index) {
            Item item;
            if (!produce(item)) return;
            Result r = work(0, item);
            consume(index, r);
        }
    }
    struct Done {
        Result result{};
        std::exception_ptr error;
    };
    std::mutex m;
    std::condition_variable changed;
    std::vector<std::pair<std::size_t, Item>> queue;  // produced, not yet taken by a worker (FIFO)
    std::size_t queueHead = 0;
    std::map<std::size_t, Done> done;                 // worked on, not yet consumed
    std::size_t produced = 0, consumed = 0;
    bool producing = true, stop = false;
    std::exception_ptr error;
    std::size_t errorIndex = std::numeric_limits<std::size_t>::max();
    auto fail = [&](std::size_t index, std::exception_ptr e) {  // under the lock
        if (index < errorIndex) errorIndex = index, error = e;
    };
    const std::size_t capacity = options.capacity == 0 ? 1 : options.capacity;

    auto worker = [&](unsigned id) {
        std::unique_lock<std::mutex> lock(m);
        while (true) {
            changed.wait(lock, [&] { return stop || queueHead < queue.size() || !producing; });
            if (stop || queueHead == queue.size()) return;  // stopped, or nothing left to produce
            auto [index, item] = std::move(queue[queueHead++]);
            if (queueHead == queue.size()) queue.clear(), queueHead = 0;
            lock.unlock();
            Done d;
            try {
                d.result = work(id, item);
            } catch (...) {
                d.error = std::current_exception();
            }
            lock.lock();
            done.emplace(index, std::move(d));
            changed.notify_all();
        }
    };
    auto consumer = [&] {
        std::unique_lock<std::mutex> lock(m);
        while (true) {
            changed.wait(lock, [&] { return stop || done.count(consumed) || (!producing && consumed == produced); });
            if (stop || !done.count(consumed)) return;
            auto node = done.extract(consumed);
            if (node.mapped().error) {
                fail(consumed, node.mapped().error);
                stop = true;
                changed.notify_all();
                return;
            }
            lock.unlock();
            std::exception_ptr e;
            try {
                consume(consumed, node.mapped().result);
            } catch (...) {
                e = std::current_exception();
            }
            lock.lock();
            if (e) {
                fail(consumed, e);
                stop = true;
            }
            ++consumed;
            changed.notify_all();
            if (stop) return;
        }
    };

    std::vector<std::thread> threads;
    for (unsigned i = 0; i < options.workers; ++i) threads.emplace_back(worker, i);
    threads.emplace_back(consumer);
    {
        std::unique_lock<std::mutex> lock(m);
        while (true) {
            changed.wait(lock, [&] { return stop || produced - consumed < capacity; });
            if (stop) break;
            lock.unlock();
            Item item;
            bool more = false;
            std::exception_ptr e;
            try {
                more = produce(item);
            } catch (...) {
                e = std::current_exception();
            }
            lock.lock();
            if (e) fail(produced, e);  // items before it are still consumed (or fail earlier)
            if (e || !more) break;
            queue.emplace_back(produced++, std::move(item));
            changed.notify_all();
        }
        producing = false;
        changed.notify_all();
    }
    for (auto& t : threads) t.join();
    if (error) std::rethrow_exception(error);
}

}  // namespace gseg
