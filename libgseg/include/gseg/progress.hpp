#pragma once
/// \file progress.hpp
/// Progress of a long run, shared by every gseg tool: items done, items per second and the time
/// left. On a terminal one live line, redrawn at most every 0.2 s; otherwise (a log file, a pipe)
/// plain lines at a steady rate: the first item, then one line every `interval` seconds, and the
/// end. Plain C++ (no MRPT); every member is thread-safe, so worker threads may report directly.

#include <chrono>
#include <cstddef>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>

namespace gseg {

class Progress {
public:
    using Clock = std::function<double()>;  ///< seconds, monotonic

    /// `out` is where progress goes (a tool passes stderr; null: nowhere, e.g. --quiet); `label`
    /// starts every line ("rawlog-gseg"); `unit` names the items ("scans").
    /// `tty`: 1 live line, 0 plain lines, -1 (default) whether `out` is a terminal.
    Progress(std::FILE* out, std::string label, std::string unit, int tty = -1, double interval = 10.0,
             Clock clock = steadySeconds);

    /// `done` items finished; `fraction` of the whole work done (0..1, e.g. bytes of the input
    /// read; negative: unknown, no time left shown); `note` is appended in parentheses.
    void update(std::size_t done, double fraction, const std::string& note = "");
    /// A message line (e.g. a skipped item) that does not garble the live line.
    void message(const std::string& text);
    /// The last line (always printed): items, rate and elapsed time.
    void finish(std::size_t done, const std::string& note = "");

    /// The text of a line (no newline), for tests and logs.
    std::string line(std::size_t done, double fraction, const std::string& note) const;

    static double steadySeconds() {
        return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    }

private:
    std::string compose(std::size_t done, double fraction, const std::string& note) const;  ///< line(), unlocked

    std::FILE* out_;
    std::string label_, unit_;
    bool tty_;
    double interval_;
    Clock clock_;
    double start_, lastPrint_ = -1e300;
    mutable std::mutex mutex_;
};

/// "2 min 05 s", "45 s", "1 h 03 min".
std::string formatDuration(double seconds);

}  // namespace gseg
