#pragma once
/// \file commands.hpp
/// Sub-commands of the `gseg` tool. Each takes the arguments after the sub-command name
/// (argv[0] is "gseg <cmd>"), prints its own usage on error and returns the exit code.

#include "common/ranks.hpp"

namespace gseg::app {
int runSegment(int argc, char** argv);
int runBench(int argc, char** argv);
/// Scores a 2D map against a labelled KITTI drive (gseg/eval/map_score.hpp).
int runEvalMap(int argc, char** argv);
/// Under an MPI launcher the frames are split over `ranks`; rank 0 writes the reports.
int runEval(int argc, char** argv, tools::Ranks& ranks);
}  // namespace gseg::app
