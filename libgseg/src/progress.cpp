#include <gseg/progress.hpp>

#include <algorithm>
#include <cmath>
#include <unistd.h>

namespace gseg {

std::string formatDuration(double seconds) {
    const long s = std::lround(std::max(0.0, seconds));
    char buf[48];
    if (s >= 3600) std::snprintf(buf, sizeof buf, "%ld h %02ld min", s / 3600, (s % 3600) / 60);
    else if (s >= 60) std::snprintf(buf, sizeof buf, "%ld min %02ld s", s / 60, s % 60);
    else std::snprintf(buf, sizeof buf, "%ld s", s);
    return buf;
}

Progress::Progress(std::FILE* out, std::string label, std::string unit, int tty, double interval, Clock clock)
    : out_(out), label_(std::move(label)), unit_(std::move(unit)),
      tty_(tty < 0 ? out && ::isatty(::fileno(out)) == 1 : tty == 1), interval_(interval), clock_(std::move(clock)),
      start_(clock_()) {}

std::string Progress::line(std::size_t done, double fraction, const std::string& note) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return compose(done, fraction, note);
}

std::string Progress::compose(std::size_t done, double fraction, const std::string& note) const {
    const double elapsed = clock_() - start_;
    char buf[160];
    int n = std::snprintf(buf, sizeof buf, "%s: %zu %s, %.1f %s/s", label_.c_str(), done, unit_.c_str(),
                          elapsed > 0 ? double(done) / elapsed : 0.0, unit_.c_str());
    std::string s(buf, std::size_t(std::max(0, n)));
    if (fraction > 0 && fraction <= 1) {
        std::snprintf(buf, sizeof buf, ", %.0f %%, %s left", 100 * fraction, formatDuration(elapsed * (1 - fraction) / fraction).c_str());
        s += buf;
    }
    if (!note.empty()) s += " (" + note + ")";
    return s;
}

void Progress::update(std::size_t done, double fraction, const std::string& note) {
    if (!out_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    const double now = clock_();
    if (now - lastPrint_ < (tty_ ? 0.2 : interval_)) return;
    lastPrint_ = now;
    const std::string text = compose(done, fraction, note);
    if (tty_) std::fprintf(out_, "\r%s\033[K", text.c_str());
    else std::fprintf(out_, "%s\n", text.c_str());
    std::fflush(out_);
}

void Progress::message(const std::string& text) {
    if (!out_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    if (tty_) std::fprintf(out_, "\r%s\033[K\n", text.c_str());
    else std::fprintf(out_, "%s\n", text.c_str());
    lastPrint_ = -1e300;  // redraw the live line at the next update
    std::fflush(out_);
}

void Progress::finish(std::size_t done, const std::string& note) {
    if (!out_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    const std::string text = compose(done, -1, note) + ", " + formatDuration(clock_() - start_) + " in all";
    if (tty_) std::fprintf(out_, "\r%s\033[K\n", text.c_str());
    else std::fprintf(out_, "%s\n", text.c_str());
    std::fflush(out_);
}

}  // namespace gseg
