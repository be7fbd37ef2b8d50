#pragma once
/// \file progress.hpp
/// Progress of a long loop, for the map tools: a bar redrawn in place on a terminal, plain lines
/// (about every 10 %, and every item of short runs) otherwise.

#include <cstddef>
#include <cstdio>
#include <string>
#include <unistd.h>

namespace gseg::map {

class Progress {
public:
    /// `out` is where progress goes (a tool passes stderr); `total` items are expected.
    Progress(std::FILE* out, std::string label, std::size_t total)
        : out_(out), label_(std::move(label)), total_(total), tty_(::isatty(::fileno(out)) == 1) {}

    /// Item `done` (1-based) finished; `note` is appended (e.g. the figures of that item).
    void update(std::size_t done, const std::string& note = "") {
        if (tty_) {
            const int width = 30, filled = total_ ? int(width * done / total_) : width;
            std::fprintf(out_, "\r%s [%s%s] %zu/%zu %s\033[K", label_.c_str(), std::string(std::size_t(filled), '#').c_str(),
                         std::string(std::size_t(width - filled), ' ').c_str(), done, total_, note.c_str());
            if (done == total_) std::fputc('\n', out_);
        } else if (total_ <= 20 || done == total_ || (10 * done / total_) != (10 * (done - 1) / total_)) {
            std::fprintf(out_, "%s %zu/%zu %s\n", label_.c_str(), done, total_, note.c_str());
        }
        std::fflush(out_);
    }

private:
    std::FILE* out_;
    std::string label_;
    std::size_t total_;
    bool tty_;
};

}  // namespace gseg::map
