#include <gseg/fork_join_pool.hpp>

#include <algorithm>

namespace gseg {

ForkJoinPool::ForkJoinPool(unsigned threads) {
    for (unsigned t = 1; t < std::max(1u, threads); ++t) workers_.emplace_back([this, t] { loop(t); });
}

ForkJoinPool::~ForkJoinPool() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    start_.notify_all();
    for (auto& w : workers_) w.join();
}

// Takes parts until none is left; records the exception of the lowest failing part.
void ForkJoinPool::work(unsigned thread) {
    for (std::size_t p; (p = next_.fetch_add(1)) < parts_;) {
        try {
            (*part_)(p, thread);
        } catch (...) {
            std::lock_guard<std::mutex> lock(mutex_);
            if (!error_ || p < errorPart_) error_ = std::current_exception(), errorPart_ = p;
        }
    }
}

void ForkJoinPool::loop(unsigned thread) {
    std::size_t seen = 0;
    for (;;) {
        {
            std::unique_lock<std::mutex> lock(mutex_);
            start_.wait(lock, [&] { return stop_ || generation_ != seen; });
            if (stop_) return;
            seen = generation_;
        }
        work(thread);
        std::lock_guard<std::mutex> lock(mutex_);
        if (--busy_ == 0) done_.notify_one();
    }
}

void ForkJoinPool::run(std::size_t parts, const std::function<void(std::size_t, unsigned)>& part) {
    if (parts == 0) return;
    if (workers_.empty() || parts == 1) {
        for (std::size_t p = 0; p < parts; ++p) part(p, 0);
        return;
    }
    {
        std::lock_guard<std::mutex> lock(mutex_);
        part_ = &part;
        parts_ = parts;
        next_ = 0;
        error_ = nullptr;
        busy_ = unsigned(workers_.size());
        ++generation_;
    }
    start_.notify_all();
    work(0);
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return busy_ == 0; });
    part_ = nullptr;
    if (error_) {
        std::exception_ptr e = error_;
        error_ = nullptr;
        std::rethrow_exception(e);
    }
}

}  // namespace gseg
