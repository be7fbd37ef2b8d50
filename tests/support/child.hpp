#pragma once
/// \file child.hpp
/// Runs test code in a forked child process: for signals, resource limits and crashes that must
/// not touch the test process itself.

#include <functional>
#include <string>

namespace gseg::test {

/// How a child ended.
struct ChildResult {
    bool exited = false;  ///< true: exit code in `code`; false: killed by signal `signal`
    int code = -1;
    int signal = 0;
};

/// Forks; the child runs `body` and exits with its return value (an escaping exception exits
/// with 99). The parent waits and returns how the child ended.
ChildResult runInChild(const std::function<int()>& body);

/// The names of the entries of `dir` that contain `part` (e.g. ".tmp"), sorted.
std::string entriesContaining(const std::string& dir, const std::string& part);

}  // namespace gseg::test
