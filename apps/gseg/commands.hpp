#pragma once
/// \file commands.hpp
/// Sub-commands of the `gseg` tool. Each takes the arguments after the sub-command name
/// (argv[0] is "gseg <cmd>"), prints its own usage on error and returns the exit code.

namespace gseg::app {
int runSegment(int argc, char** argv);
int runBench(int argc, char** argv);
int runEval(int argc, char** argv);
}  // namespace gseg::app
