#pragma once
/// \file progress.hpp
/// Progress of long runs: a bar on a terminal, a plain line every 10 % otherwise.

#include <cstddef>
#include <cstdio>
#include <mutex>
#include <string>
#include <unistd.h>
#include <utility>

namespace gseg::app {

class Progress {
public:
    Progress(std::string what, std::size_t total)
        : what_(std::move(what)), total_(total), tty_(::isatty(::fileno(stderr)) != 0) {}

    /// One more item done (thread-safe).
    void step() {
        std::lock_guard<std::mutex> lock(mutex_);
        ++done_;
        if (tty_) {
            const int width = 30, filled = total_ ? int(width * done_ / total_) : width;
            std::fprintf(stderr, "\r%s [%s%s] %zu/%zu", what_.c_str(), std::string(std::size_t(filled), '#').c_str(),
                         std::string(std::size_t(width - filled), ' ').c_str(), done_, total_);
            if (done_ == total_) std::fprintf(stderr, "\n");
        } else if (total_ && (done_ * 10 / total_ != (done_ - 1) * 10 / total_ || done_ == total_)) {
            std::fprintf(stderr, "%s: %zu/%zu\n", what_.c_str(), done_, total_);
        }
    }

private:
    std::string what_;
    std::size_t total_, done_ = 0;
    bool tty_;
    std::mutex mutex_;
};

}  // namespace gseg::app
