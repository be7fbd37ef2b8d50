#pragma once
/// \file text.hpp
/// The small text and timing helpers every layer and tool uses, in one place: trimming, prefix and
/// suffix tests, lower case, one number parser (the option tables' and every command-line number's)
/// and the seconds since a time point.

#include <algorithm>
#include <cctype>
#include <charconv>
#include <chrono>
#include <optional>
#include <string>
#include <system_error>

namespace gseg {

/// The blanks trim() removes by default: those of std::isspace in the C locale.
inline constexpr const char* kBlanks = " \t\n\v\f\r";

/// `s` without the `blanks` at its start and end.
inline std::string trim(const std::string& s, const char* blanks = kBlanks) {
    const std::size_t b = s.find_first_not_of(blanks);
    if (b == std::string::npos) return "";
    return s.substr(b, s.find_last_not_of(blanks) - b + 1);
}

inline bool startsWith(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }

inline bool endsWith(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// `s` in lower case (ASCII letters only).
inline std::string lowercase(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

/// The one number parser: `text` (blanks around it allowed) as one T, as std::from_chars reads it
/// (no locale, no leading '+', "inf" and "nan" for floating point); std::nullopt when `text` is
/// empty, holds anything else or the number is out of T's range.
template <typename T>
std::optional<T> parseNumber(const std::string& text) {
    const std::string t = trim(text);
    T v{};
    const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || ec != std::errc() || ptr != t.data() + t.size()) return std::nullopt;
    return v;
}

/// [s] The time since `t0` on the steady clock.
inline double secondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace gseg
